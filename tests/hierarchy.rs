//! The lighting grid hierarchy on the GPU: its lights flattened with their bands
//! (`manylights_scene::hierarchy`), uploaded with `GpuScene::set_light_bands` and shaded by
//! the brute-force reference, against the hierarchy's shading in f64 at the same surface points.

mod common;

use glam::DVec3;
use manylights_gpu::GpuScene;
use manylights_scene::hierarchy::{self, Hierarchy, HierarchyParams};
use manylights_scene::light::{Range, shade};
use manylights_scene::procedural::ProceduralScene;
use manylights_scene::{LightGenerator, LightSpec, RadiusRule, Scene};
use manylights_shade::ReferenceRenderer;

fn atrium(count: u32, spots: f32) -> Scene {
    let mut scene = ProceduralScene::from_name("atrium")
        .unwrap()
        .build()
        .unwrap();
    let spec = LightSpec {
        generator: LightGenerator::Uniform,
        count,
        seed: 48,
        radius: RadiusRule::Fixed(3.0),
        intensity: 2.0,
        spot_fraction: spots,
        spot_outer_deg: 50.0,
        ..LightSpec::default()
    };
    scene.lights = spec.generate(&scene).unwrap();
    scene
}

fn rgb(t: [f32; 4]) -> DVec3 {
    DVec3::new(t[0].into(), t[1].into(), t[2].into())
}

/// Every level's light and every spot, shaded on the GPU with its band, against
/// `hierarchy::shade` in f64. The bands are continuous (0 at both ends), so f32 rounding of a
/// distance moves a term by a rounding, not by a step: 1e-4 of each pixel plus 1e-6 of the
/// image's mean. The hierarchy's image also differs from the lights' own at infinite range by
/// its bias, which is small at this alpha but not zero (the hierarchy is in effect).
#[test]
fn hierarchy_lights_shade_as_their_oracle() {
    let ctx = common::gpu();
    // The papers' ramps and narrow ones (the frame's band ramp, GpuScene::set_light_bands).
    // Spots in the point lights' nodes and in direction bins.
    for (ramp, spot_bins) in [(hierarchy::RAMP, 0), (1.25, 5)] {
        hierarchy_lights_shade_as_their_oracle_with(&ctx, ramp, spot_bins);
    }
}

fn hierarchy_lights_shade_as_their_oracle_with(
    ctx: &manylights_gpu::GpuContext,
    ramp: f64,
    spot_bins: u32,
) {
    let (w, h) = (40, 24);
    let original = atrium(1500, 0.2);
    let hier = Hierarchy::build(
        &original.lights,
        HierarchyParams {
            alpha: 2.0,
            spacing: 0.75,
            finest_nodes: hierarchy::FINEST_NODES,
            growth: hierarchy::GROWTH,
            ramp,
            top_lights: 16,
            sample_from: None,
            spot_bins,
        },
    );
    assert!(hier.levels.len() >= 4, "{} levels", hier.levels.len());
    let (flat, bands) = hier.flatten(hierarchy::reach(&original));
    let scene = Scene {
        lights: flat.clone(),
        ..original.clone()
    };
    let gpu = GpuScene::upload_with(
        ctx,
        &scene,
        manylights_gpu::LightModel::hierarchy(ramp as f32),
        &scene.camera,
        w,
        h,
    )
    .unwrap();
    gpu.set_light_bands(ctx, &flat, &bands);
    let rr = ReferenceRenderer::new(ctx, &gpu);
    let got = rr.render(ctx, &gpu, w, h).unwrap();
    let eye = scene.camera.position.as_dvec3();
    let (mut checked, mut biased) = (0, 0);
    let mut mean = 0.0;
    let mut pairs = Vec::new();
    for (k, (p, n)) in got.position.data.iter().zip(&got.normal.data).enumerate() {
        if p[3] == 0.0 {
            continue;
        }
        let (pos, nrm) = (rgb(*p), rgb(*n));
        let v = (eye - pos).normalize();
        let m = &scene.materials[n[3] as usize];
        let want = hierarchy::shade(pos, nrm, v, m, &flat, &bands);
        let exact = shade(pos, nrm, v, m, &original.lights, Range::Infinite);
        if (want - exact).abs().max_element() > 1e-3 * exact.max_element() {
            biased += 1;
        }
        mean += want.element_sum() / 3.0;
        pairs.push((k, rgb(got.color.data[k]), want));
    }
    mean /= pairs.len() as f64;
    for (k, g, want) in &pairs {
        assert!(
            (*g - *want).abs().max_element() <= 1e-4 * want.max_element() + 1e-6 * mean,
            "pixel {k}: gpu {g} vs f64 {want}"
        );
        checked += 1;
    }
    assert!(checked > (w * h / 2) as usize, "{checked} pixels");
    assert!(
        biased > 0,
        "the hierarchy's estimate is the lights' own everywhere"
    );
}

/// The lights a GPU build of `plan` wrote into `gpu_scene`.
fn shaded_lights(
    ctx: &manylights_gpu::GpuContext,
    gpu_scene: &GpuScene,
    plan: &manylights_gpu::hierarchy::HierarchyPlan,
) -> Vec<manylights_gpu::layout::GpuLight> {
    let bytes =
        manylights_gpu::readback::read_buffer(ctx, &gpu_scene.lights, 0, plan.shaded_count() * 64)
            .unwrap();
    bytemuck::cast_slice(&bytes).to_vec()
}

/// Level `level`'s live spot aggregates as the GPU built them: each has the cone of one of the
/// oracle's direction bins (its axis and cosines as a light of that cone holds them), and each
/// bin's aggregates carry the oracle's power for that bin (to 1e-5 of the level's).
fn spot_aggregates_have_their_bins_cones(
    lights: &[manylights_gpu::layout::GpuLight],
    plan: &manylights_gpu::hierarchy::HierarchyPlan,
    oracle: &Hierarchy,
    level: usize,
    what: &str,
) {
    use manylights_gpu::layout::{GpuLight, LIGHT_KIND_SPOT};
    let cones: Vec<GpuLight> = oracle
        .bins
        .iter()
        .map(|b| GpuLight::from(&b.light(glam::Vec3::ZERO, 1.0, glam::Vec3::ONE)))
        .collect();
    let mut built = vec![DVec3::ZERO; cones.len() + 1];
    let (first, n) = plan.level_range(level);
    for l in &lights[first as usize..(first + n) as usize] {
        if l.intensity == 0.0 || l.radius == 0.0 {
            continue;
        }
        let bin = if l.shape() == LIGHT_KIND_SPOT {
            1 + cones
                .iter()
                .position(|c| {
                    (c.direction, c.cos_inner, c.cos_outer)
                        == (l.direction, l.cos_inner, l.cos_outer)
                })
                .unwrap_or_else(|| panic!("{what}: level {level}: a spot of no bin's cone: {l:?}"))
        } else {
            0
        };
        built[bin] += (l.color * l.intensity).as_dvec3();
    }
    let mut want = vec![DVec3::ZERO; cones.len() + 1];
    for l in &oracle.levels[level] {
        want[l.bin as usize] += l.power;
    }
    let total: f64 = want.iter().map(|p| p.element_sum()).sum();
    for (b, (got, want)) in built.iter().zip(&want).enumerate() {
        assert!(
            (*got - *want).abs().max_element() < 1e-5 * total,
            "{what}: level {level}, bin {b}: {got} against {want}"
        );
    }
    assert!(cones.is_empty() || want[1..].iter().any(|p| p.element_sum() > 0.0));
}

/// The lights a GPU build wrote for level `level` of `plan`: the live ones (power and reach).
fn built_level(
    lights: &[manylights_gpu::layout::GpuLight],
    plan: &manylights_gpu::hierarchy::HierarchyPlan,
    level: usize,
) -> Vec<(DVec3, DVec3)> {
    let (first, n) = plan.level_range(level);
    lights[first as usize..(first + n) as usize]
        .iter()
        .filter(|l| l.intensity > 0.0 && l.radius > 0.0)
        .map(|l| (l.position.as_dvec3(), (l.color * l.intensity).as_dvec3()))
        .collect()
}

/// `built` against the oracle's level: the same total power (to 1e-5), and every light of
/// either that carries at least `least` of it (1e-6 where not said otherwise) matched in the other by a light at its position (to
/// 1e-4 of the spacing) with its power (to 1e-5 of the total). Several nodes may sit at one
/// position (the 8 around a lone light on a grid finer than the lights each gather only it),
/// so a match is any light that agrees in both. Nodes that gather a vanishing weight (a light's
/// far corners at a coarse grid: 1e-12 of a light) are left out: f32 sums hold them to a few
/// bits, or as nothing, and they light nothing.
fn same_level(
    built: &[(DVec3, DVec3)],
    oracle: &[hierarchy::LevelLight],
    spacing: f64,
    what: &str,
) {
    same_level_above(built, oracle, spacing, 1e-6, what);
}

fn same_level_above(
    built: &[(DVec3, DVec3)],
    oracle: &[hierarchy::LevelLight],
    spacing: f64,
    least: f64,
    what: &str,
) {
    let total: f64 = oracle.iter().map(|l| l.power.element_sum()).sum();
    let built_total: f64 = built.iter().map(|l| l.1.element_sum()).sum();
    assert!(
        (built_total - total).abs() < 1e-5 * total,
        "{what}: power {built_total} against {total}"
    );
    let oracle: Vec<(DVec3, DVec3)> = oracle.iter().map(|l| (l.position, l.power)).collect();
    for (from, to, dir) in [
        (built, &oracle[..], "built"),
        (&oracle[..], built, "oracle"),
    ] {
        for (position, power) in from.iter().filter(|l| l.1.element_sum() >= least * total) {
            let there: Vec<&(DVec3, DVec3)> = to
                .iter()
                .filter(|(p, _)| p.distance(*position) < 1e-4 * spacing)
                .collect();
            assert!(
                !there.is_empty(),
                "{what}: {dir} light at {position} ({power}), none there"
            );
            assert!(
                there
                    .iter()
                    .any(|(_, q)| (*q - *power).abs().max_element() < 1e-5 * total),
                "{what}: {dir} power {power} at {position} against {:?}",
                there.iter().map(|l| l.1).collect::<Vec<_>>()
            );
        }
    }
}

/// The hierarchy built on the GPU (`manylights_gpu::hierarchy`) is its oracle's
/// (`Hierarchy::build_fixed` with the plan's shape): every level's lights, positions and powers,
/// the point lights and spots with their bands; and again after every light has moved, in the
/// same buffers, with nothing dropped. Both ways of holding the sums (two 32-bit atomics, one
/// 64-bit atomic: lavapipe has both).
#[test]
fn the_gpu_build_is_its_oracle_and_follows_moving_lights() {
    use manylights_gpu::hierarchy::Sums;
    let ctx = common::gpu();
    assert!(
        ctx.features.int64_atomic_add,
        "adapter {} offers no 64-bit atomic add (SHADER_INT64_ATOMIC_ALL_OPS); lavapipe does: \
         run the tests on it (scripts/ensure-vulkan.sh installs it)",
        ctx.info.name
    );
    assert_eq!(Sums::for_context(&ctx), Sums::Bits64);
    // The papers' bands, growing ones and narrow ramps (the bands' radii are the plan's);
    // every level made from cells (0), and none (each light spread at once).
    // Spots in the point lights' nodes (no bins) and in direction bins of 5 a side. Every
    // light moving, or the first 900 or 1,200 or all 1,500 kept still (their level-1 sums
    // kept from the first build).
    for (sums, growth, ramp, cell_items, spot_bins, kept) in [
        (Sums::Bits32, 1.0, 2.0, 0, 0, 0),
        (Sums::Bits32, 1.0, 2.0, u32::MAX, 5, 900),
        (Sums::Bits64, 1.0, 2.0, 0, 5, 900),
        (Sums::Bits64, 1.0, 2.0, u32::MAX, 0, 1500),
        (Sums::Bits64, 1.15, 2.0, 0, 0, 1200),
        (Sums::Bits64, 1.15, 1.25, 0, 5, 0),
    ] {
        gpu_build_is_its_oracle(&ctx, sums, growth, ramp, cell_items, spot_bins, kept);
    }
}

fn gpu_build_is_its_oracle(
    ctx: &manylights_gpu::GpuContext,
    sums: manylights_gpu::hierarchy::Sums,
    growth: f64,
    ramp: f64,
    cell_items: u32,
    spot_bins: u32,
    kept: u32,
) {
    use manylights_gpu::hierarchy::{GpuHierarchy, HierarchyPlan};
    use manylights_gpu::layout::GpuLight;
    let original = atrium(1500, 0.2);
    let params = HierarchyParams {
        alpha: 2.0,
        spacing: 0.75,
        finest_nodes: hierarchy::FINEST_NODES,
        growth,
        ramp,
        top_lights: 16,
        sample_from: None,
        spot_bins,
    };
    let b = original
        .lights
        .iter()
        .fold(original.bounds(), |b, l| b.union_point(l.position));
    let margin = glam::Vec3::splat(2.0);
    let reach = hierarchy::reach(&original);
    let (mut plan, _) = HierarchyPlan::new(
        &original.lights,
        params,
        (b.min - margin, b.max + margin),
        reach,
        2.0,
    )
    .unwrap();
    assert!(plan.levels >= 4, "{} levels", plan.levels);
    assert_eq!(plan.static_lights, 0, "a plan of new keeps no light still");
    plan.static_lights = kept;
    let shaded = Scene {
        lights: plan.placeholder(&original.lights),
        ..original.clone()
    };
    let camera = original.camera;
    // A scene uploaded for other ranges is refused: it would not shade the bands.
    let windowed = GpuScene::upload(ctx, &shaded, &camera, 32, 32).unwrap();
    let refused = GpuHierarchy::with_cells(
        ctx,
        plan.clone(),
        &original.lights,
        &windowed,
        sums,
        cell_items,
    );
    let message = refused.err().expect("refused").to_string();
    assert!(message.contains("HierarchyPlan::light_model"), "{message}");
    let gpu_scene =
        GpuScene::upload_with(ctx, &shaded, plan.light_model(), &camera, 32, 32).unwrap();
    let build = GpuHierarchy::with_cells(
        ctx,
        plan.clone(),
        &original.lights,
        &gpu_scene,
        sums,
        cell_items,
    )
    .unwrap();
    assert_eq!(build.sums(), sums);
    assert_eq!(build.kept_lights(), kept);
    // Spots among the lights: every light takes the general path.
    assert_eq!(gpu_scene.light_path(), manylights_gpu::LightPath::General);
    let moved: Vec<manylights_scene::Light> = original
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| manylights_scene::Light {
            position: if i < kept as usize {
                l.position
            } else {
                l.position + glam::Vec3::new((i % 7) as f32 * 0.2 - 0.6, 0.5, (i % 3) as f32 * -0.4)
            },
            ..*l
        })
        .collect();
    for (place, lights) in [("at home", &original.lights), ("moved", &moved)] {
        let what = format!(
            "{sums:?}, growth {growth}, ramp {ramp}, cells from {cell_items} items, \
             {spot_bins} spot bins, {kept} lights kept still, {place}"
        );
        let gpu: Vec<GpuLight> = lights.iter().map(GpuLight::from).collect();
        ctx.queue
            .write_buffer(build.source(), 0, bytemuck::cast_slice(&gpu));
        build.build(ctx).unwrap();
        let shaded = shaded_lights(ctx, &gpu_scene, &plan);
        let out: &[GpuLight] = &shaded;
        let oracle = Hierarchy::build_fixed(lights, params, plan.h, plan.levels);
        let (flat, bands) = oracle.flatten(reach);
        // Level 0 and the spots: the lights themselves, with their bands.
        let points = oracle.levels[0].len();
        for (k, (l, band)) in flat.iter().zip(&bands).take(points).enumerate() {
            let want = GpuLight::from(l).with_band(band);
            assert_eq!(out[k].position, want.position, "{what}: point {k}");
            assert_eq!(
                (out[k].radius, out[k].alpha, out[k].kind),
                (want.radius, want.alpha, want.kind),
                "{what}: point {k}"
            );
            assert!(
                (out[k].color - want.color).abs().max_element() < 1e-6 * want.color.max_element()
            );
        }
        let spots = &out[out.len() - oracle.spots.len()..];
        for (s, (l, band)) in spots.iter().zip(
            flat.iter()
                .zip(&bands)
                .skip(flat.len() - oracle.spots.len()),
        ) {
            let want = GpuLight::from(l).with_band(band);
            assert_eq!(
                bytemuck::bytes_of(s),
                bytemuck::bytes_of(&want),
                "{what}: spot"
            );
        }
        assert!(
            spot_bins == 0 || oracle.bins.len() >= 4,
            "{} direction bins",
            oracle.bins.len()
        );
        for level in 1..plan.levels {
            let spacing = plan.h * f64::from(1u32 << (level - 1));
            spot_aggregates_have_their_bins_cones(out, &plan, &oracle, level, &what);
            same_level(
                &built_level(out, &plan, level),
                &oracle.levels[level],
                spacing,
                &format!("{what}: level {level}"),
            );
            // Every light of the level carries its band.
            let (first, _) = plan.level_range(level);
            let want = bands[flat.len()
                - oracle.spots.len()
                - oracle.levels[level..].iter().map(Vec::len).sum::<usize>()];
            assert_eq!(
                out[first as usize].alpha, want.r as f32,
                "{what}: level {level}'s band"
            );
            assert_eq!(
                out[first as usize].falloff(),
                manylights_gpu::layout::LIGHT_FALLOFF_BAND,
                "{what}: level {level}'s falloff"
            );
        }
        assert_eq!(build.dropped(ctx).unwrap(), (0, 0), "{what}");
    }
}

/// Sampled bands on the GPU (`sample_from`): every live aggregate of the sampled levels carries
/// its soft band drawn with `band_xi(seed, node_draw(level, its node's key))`
/// (`Band::sampled`), the reach cut to match; the levels below keep their soft bands; the same
/// frame built again draws the same band for each node wherever its slot; a new seed draws
/// anew.
#[test]
fn the_gpu_build_samples_the_bands_it_is_asked_to() {
    use manylights_gpu::hierarchy::{GpuHierarchy, HierarchyPlan};
    use manylights_gpu::layout::{GpuLight, LIGHT_FALLOFF_BAND};
    let ctx = common::gpu();
    let original = atrium(600, 0.0);
    let params = HierarchyParams {
        alpha: 1.5,
        spacing: 0.5,
        finest_nodes: hierarchy::FINEST_NODES,
        growth: hierarchy::GROWTH,
        // Narrow ramps: drawn within (1, 1.5) of inner and r.
        ramp: 1.5,
        top_lights: 16,
        sample_from: Some(1),
        spot_bins: hierarchy::SPOT_BINS,
    };
    let (plan, shaded) = HierarchyPlan::for_scene(&original, params, None).unwrap();
    assert!(plan.levels >= 3, "{} levels", plan.levels);
    let gpu_scene =
        GpuScene::upload_with(&ctx, &shaded, plan.light_model(), &original.camera, 32, 32).unwrap();
    let build = GpuHierarchy::new(&ctx, plan.clone(), &original.lights, &gpu_scene).unwrap();
    // Point lights alone: the hierarchy's lights take the band points' short path.
    assert_eq!(
        gpu_scene.light_path(),
        manylights_gpu::LightPath::BandPoints
    );
    // A build's shaded lights and its hash table's slot keys.
    let read = |seed: u32| -> (Vec<GpuLight>, Vec<u32>) {
        build.set_seed(&ctx, seed);
        build.build(&ctx).unwrap();
        let bytes = manylights_gpu::readback::read_buffer(
            &ctx,
            &gpu_scene.lights,
            0,
            plan.shaded_count() * 64,
        )
        .unwrap();
        let lights = bytemuck::cast_slice(&bytes).to_vec();
        (lights, build.slot_keys(&ctx).unwrap())
    };
    // Seed 3, seed 4, and seed 3 again.
    let (a, keys_a) = read(3);
    let (b, keys_b) = read(4);
    let (c, keys_c) = read(3);
    let r = |l: usize| params.alpha * plan.h * f64::from(1u32 << l);
    // The shaded light of `level` whose node is `key` in a build of those keys.
    let find = |keys: &[u32], level: usize, key: u32| {
        let (first, count) = plan.level_range(level);
        let slots = (first - plan.points) as usize..(first - plan.points + count) as usize;
        keys[slots.clone()]
            .iter()
            .position(|&k| k == key)
            .map(|t| first as usize + t)
    };
    let mut checked = 0;
    for level in 0..plan.levels {
        let (first, count) = plan.level_range(level);
        let soft = hierarchy::Band::with_ramp(
            if level == 0 { 0.0 } else { r(level - 1) },
            if level + 1 == plan.levels {
                f64::INFINITY
            } else {
                r(level)
            },
            params.ramp,
        );
        for i in first..first + count {
            let l = &a[i as usize];
            if l.intensity == 0.0 {
                continue; // a dead slot
            }
            if level == 0 {
                assert!(!l.hard_band(), "level 0 light {i} stays soft");
                assert_eq!(l.falloff(), LIGHT_FALLOFF_BAND, "level 0 light {i}");
                continue;
            }
            let key = keys_a[(i - plan.points) as usize];
            assert_ne!(key, 0, "light {i}: a live aggregate's slot has its node");
            let id = hierarchy::node_draw(level as u32, key);
            let want = soft.sampled(hierarchy::band_xi(3, id));
            let from = f32::from_bits(l.interleave);
            assert!(l.hard_band(), "light {i} of level {level}");
            assert!(
                (f64::from(from) - want.inner).abs() <= 1e-5 * want.inner.max(1.0),
                "light {i}: from {from}, want {}",
                want.inner
            );
            assert!(
                (f64::from(l.alpha) - want.r).abs() <= 1e-5 * want.r.max(1.0)
                    || (l.alpha.is_infinite() && want.r.is_infinite()),
                "light {i}: to {}, want {}",
                l.alpha,
                want.r
            );
            // The same reach, to the f32 rounding of `r (c - (c - 1) xi)` on either side.
            let reach = (want.r as f32).min(plan.reach);
            assert!(
                (l.radius - reach).abs() <= 2.0 * f32::EPSILON * reach,
                "light {i}'s reach: {} against {reach}",
                l.radius
            );
            // The same frame built again draws the same band for the same node, wherever
            // its slot; seed 4 draws anew.
            let again = find(&keys_c, level, key).expect("the node in the same frame's build");
            assert_eq!(
                (c[again].interleave, c[again].alpha, c[again].radius),
                (l.interleave, l.alpha, l.radius),
                "light {i}: the same frame's draw"
            );
            let other = find(&keys_b, level, key).expect("the node in seed 4's build");
            assert_ne!(
                b[other].interleave, l.interleave,
                "light {i}: seed 4 draws anew"
            );
            checked += 1;
        }
    }
    assert!(checked > 20, "{checked} sampled lights");
    assert_eq!(build.dropped(&ctx).unwrap(), (0, 0));
}

/// Builds `plan` on the GPU from `home` (the lights uploaded with it), then for each light set
/// of `frames` in turn writes it into the build's source and builds: each frame's levels
/// against the oracle's where `check` says, and the splats dropped over all of them.
fn build_frames(
    ctx: &manylights_gpu::GpuContext,
    plan: &manylights_gpu::hierarchy::HierarchyPlan,
    shaded: &Scene,
    home: &[manylights_scene::Light],
    frames: &[Vec<manylights_scene::Light>],
    check: bool,
    what: &str,
) -> (u64, u64) {
    use manylights_gpu::hierarchy::GpuHierarchy;
    use manylights_gpu::layout::GpuLight;
    let gpu_scene =
        GpuScene::upload_with(ctx, shaded, plan.light_model(), &shaded.camera, 16, 16).unwrap();
    let build = GpuHierarchy::new(ctx, plan.clone(), home, &gpu_scene).unwrap();
    // The lights that never move are splatted once (every one, where none moves).
    let kept = if plan.levels > 1 {
        plan.static_lights
    } else {
        0
    };
    assert_eq!(build.kept_lights(), kept, "{what}");
    for (f, lights) in frames.iter().enumerate() {
        let gpu: Vec<GpuLight> = lights.iter().map(GpuLight::from).collect();
        ctx.queue
            .write_buffer(build.source(), 0, bytemuck::cast_slice(&gpu));
        build.build(ctx).unwrap();
        if !check {
            continue;
        }
        let shaded = shaded_lights(ctx, &gpu_scene, plan);
        let out: &[GpuLight] = &shaded;
        let oracle = Hierarchy::build_fixed(lights, plan.params, plan.h, plan.levels);
        // Lights packed into a few cells leave nodes of 1e-6 of the power whose weights come
        // from a light at a cell's far face: f32 holds those weights to a few bits (a node's
        // position to 1e-4 of the spacing). They are left out above 1e-5.
        for level in 1..plan.levels {
            same_level_above(
                &built_level(out, plan, level),
                &oracle.levels[level],
                plan.h * f64::from(1u32 << (level - 1)),
                1e-5,
                &format!("{what}, frame {f}: level {level}"),
            );
        }
    }
    build.dropped(ctx).unwrap()
}

/// `lights` at each of frames `0..frames`, those from `first` on where `motion` puts them.
fn moved_frames(
    lights: &[manylights_scene::Light],
    motion: &manylights_scene::Motion,
    first: usize,
    frames: u32,
) -> Vec<Vec<manylights_scene::Light>> {
    (0..frames)
        .map(|f| {
            lights
                .iter()
                .enumerate()
                .map(|(i, l)| manylights_scene::Light {
                    position: if i < first {
                        l.position
                    } else {
                        motion.position(i as u32, l.position, l.radius, f)
                    },
                    ..*l
                })
                .collect()
        })
        .collect()
}

fn params_at(spacing: f64) -> HierarchyParams {
    HierarchyParams {
        alpha: 1.0,
        spacing,
        finest_nodes: hierarchy::FINEST_NODES,
        growth: hierarchy::GROWTH,
        ramp: hierarchy::RAMP,
        top_lights: 16,
        sample_from: None,
        spot_bins: hierarchy::SPOT_BINS,
    }
}

/// The tables hold what the lights need at any spacing: from 5 cm (a grid far finer than the
/// lights, 8 nodes a light until the finest-grid rule doubles it) to 4 m (a few nodes in all),
/// the GPU build drops nothing and is its oracle, in a scene of uniform lights and in one of
/// tight clusters (most cells empty, a few crowded: where open addressing's runs grow long).
#[test]
fn the_hierarchy_drops_nothing_at_any_spacing() {
    let ctx = common::gpu();
    let uniform = atrium(1500, 0.0);
    let mut clustered = uniform.clone();
    clustered.lights = LightSpec {
        generator: LightGenerator::Clustered {
            clusters: 6,
            spread: 0.3,
        },
        count: 1500,
        seed: 5,
        radius: RadiusRule::Fixed(2.0),
        ..LightSpec::default()
    }
    .generate(&clustered)
    .unwrap();
    for (name, scene) in [("uniform", &uniform), ("clustered", &clustered)] {
        for spacing in [0.05, 0.1, 0.25, 0.5, 1.0, 2.0, 4.0] {
            let (plan, shaded) = manylights_gpu::hierarchy::HierarchyPlan::for_scene(
                scene,
                params_at(spacing),
                None,
            )
            .unwrap();
            let what = format!("{name}, spacing {spacing} (h {})", plan.h);
            let dropped = build_frames(
                &ctx,
                &plan,
                &shaded,
                &scene.lights,
                std::slice::from_ref(&scene.lights),
                true,
                &what,
            );
            assert_eq!(dropped, (0, 0), "{what}");
        }
    }
}

/// Moving lights get tables for every frame they are rendered at: lights packed tightly at
/// home (a few grid cells) that wander up to 4 m reach far more nodes than home has. Planned
/// for the frames, the build drops nothing at any of them and is its oracle; tables of twice
/// home's nodes (the rule before) drop splats into full tables at the same frames.
#[test]
fn moving_lights_get_tables_for_every_frame() {
    use manylights_gpu::hierarchy::{HierarchyPlan, Moving};
    let ctx = common::gpu();
    let mut scene = atrium(1, 0.0);
    let motion = manylights_scene::Motion::Noise(6.0);
    scene.lights = LightSpec {
        generator: LightGenerator::Clustered {
            clusters: 1,
            spread: 0.05,
        },
        count: 1200,
        seed: 7,
        radius: RadiusRule::Fixed(4.0),
        motion,
        ..LightSpec::default()
    }
    .generate(&scene)
    .unwrap();
    let frames = 6;
    let moved = moved_frames(&scene.lights, &motion, 0, frames);
    let params = params_at(0.25);
    let moving = Moving {
        motion: &motion,
        first: 0,
        frames,
        anchors: &[],
    };
    let (plan, shaded) = HierarchyPlan::for_scene(&scene, params, Some(moving)).unwrap();
    let home = Hierarchy::build(&scene.lights, params);
    assert!(
        plan.slots[0] as usize > 4 * home.levels[1].len(),
        "the lights spread: {} slots for {} nodes at home",
        plan.slots[0],
        home.levels[1].len()
    );
    let dropped = build_frames(&ctx, &plan, &shaded, &scene.lights, &moved, true, "planned");
    assert_eq!(dropped, (0, 0));
    // Twice home's nodes, in a box that covers the motion.
    let b = scene.bounds();
    let margin = glam::Vec3::splat(6.0);
    let (old, _) = HierarchyPlan::new(
        &scene.lights,
        params,
        (b.min - margin, b.max + margin),
        hierarchy::reach(&scene) + 8.0,
        2.0,
    )
    .unwrap();
    let old_shaded = Scene {
        lights: old.placeholder(&scene.lights),
        ..scene.clone()
    };
    let (outside, full) =
        build_frames(&ctx, &old, &old_shaded, &scene.lights, &moved, false, "old");
    assert_eq!(outside, 0);
    assert!(full > 0, "tables of twice home's nodes held every frame");
}

/// Lights that never move are splatted into level 1 once: planned with the lights from 1,000
/// on moving (`Moving::first`), the build keeps the first 1,000's sums, and at every frame,
/// the others wherever the motion puts them, it is its oracle of every light, nothing dropped.
/// A plan of lights that stay home keeps them all.
#[test]
fn lights_that_stay_are_splatted_once() {
    use manylights_gpu::hierarchy::{HierarchyPlan, Moving};
    let ctx = common::gpu();
    let scene = atrium(1500, 0.2);
    let motion = manylights_scene::Motion::Noise(3.0);
    let first = 1000;
    let frames = 4;
    let moved = moved_frames(&scene.lights, &motion, first, frames);
    assert_ne!(moved[2][first].position, scene.lights[first].position);
    let params = params_at(0.5);
    let moving = Moving {
        motion: &motion,
        first,
        frames,
        anchors: &[],
    };
    let (plan, shaded) = HierarchyPlan::for_scene(&scene, params, Some(moving)).unwrap();
    assert_eq!(plan.static_lights, first as u32);
    let dropped = build_frames(&ctx, &plan, &shaded, &scene.lights, &moved, true, "kept");
    assert_eq!(dropped, (0, 0));
    let (home, _) = HierarchyPlan::for_scene(&scene, params, None).unwrap();
    assert_eq!(home.static_lights, 1500);
}
