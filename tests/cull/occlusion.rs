//! Culling by visibility (`CullSettings::occlusion`, `cull.occlusion`) after every strategy with
//! lists of a list a bin, over the procedural scenes with lights reaching across them: each
//! bin's list loses only lights the f64 occluder test hides from its cell (conservative against
//! `manylights_scene::occluders::hides` with no margin), keeps the others in order, loses every
//! light the f64 test hides with a wide margin, and counts what it drops; and against the
//! shadowed exact set at every pixel (a light needed where it reaches the point and its shadow
//! ray is clear through the BVH) the lists miss nothing. The tests must fire: pairs dropped in
//! every scene with walls, and lights in range that the shadowed exact set leaves out.

use super::*;
use manylights_cull::blocks::occlusion::{CellView, cell_corners};
use manylights_cull::layout::GpuTileDepth;
use manylights_scene::occluders::{hides, occluders};
use manylights_scene::procedural::NAMES;
use manylights_scene::ray::opaque_triangles;

/// The strategies with lists of a list a bin (the clusters fourth).
fn list_strategies() -> Vec<Strategy> {
    vec![
        Strategy::tiled_gather(8),
        Strategy::depth_mask(16),
        Strategy::TiledScatter { tile_size: 8 },
        Strategy::Clustered {
            tile_size: 16,
            slices: 16,
            slicing: Slicing::Exponential,
            skip_empty: false,
            ordered: true,
            cells: false,
        },
    ]
}

#[test]
fn occlusion_drops_only_hidden_lights_and_misses_none_the_shadowed_light_needs() {
    let ctx = common::gpu();
    let (w, h) = (96, 64);
    let (mut dropped_all, mut unseen_all) = (0u64, 0u64);
    for (s_i, name) in NAMES.iter().enumerate() {
        let mut scene = ProceduralScene::from_name(name).unwrap().build().unwrap();
        let extent = scene.light_bounds.extent().max_element();
        scene.lights = LightSpec {
            generator: LightGenerator::Uniform,
            count: 200,
            seed: 41 + s_i as u64,
            radius: RadiusRule::Fixed(extent * 0.3),
            intensity: 1.0,
            ..LightSpec::default()
        }
        .generate(&scene)
        .unwrap();
        let camera = scene.camera;
        let occ = occluders(
            &opaque_triangles(&scene),
            f64::from(extent * extent) * 1e-3,
            64,
        );
        let (mut gs, depth, _) = common::depth_prepass(&ctx, &scene, &camera, w, h);
        gs.build_bvh(&ctx, &scene).unwrap();
        let mut culler = Culler::new(&ctx, &gs);
        culler.set_occluders(&ctx, &occ).unwrap();
        let frame = GpuFrame::new(&camera, w, h, scene.lights.len() as u32);
        let view = CellView {
            clip_from_view: frame.clip_from_view.as_dmat4(),
            world_from_view: frame.world_from_view.as_dmat4(),
            size: (w, h),
        };
        let mut timer = GpuTimer::new(&ctx, 64);
        // Clusters with the box test take their pixels' depth bounds, without it their slices'.
        let runs = list_strategies()
            .into_iter()
            .map(|s| (s, true))
            .chain([(list_strategies()[3], false)]);
        for (strategy, tile_boxes) in runs {
            let plain = CullSettings {
                tile_boxes,
                ..CullSettings::for_camera(&camera)
            };
            let occluding = CullSettings {
                occlusion: true,
                ..plain
            };
            let what = format!("{name}, {} (box test {tile_boxes})", strategy.name());
            let off = culler
                .run(&ctx, &gs, &depth, &strategy, &plain, &mut timer)
                .unwrap();
            let on = culler
                .run(&ctx, &gs, &depth, &strategy, &occluding, &mut timer)
                .unwrap();
            assert_eq!(
                on.passes.iter().any(|p| p.name == "cull.occlusion"),
                !occ.is_empty(),
                "{what}: the occlusion pass runs where the scene has occluders"
            );
            let (a, b) = (off.read(&ctx).unwrap(), on.read(&ctx).unwrap());
            let td: Vec<GpuTileDepth> = bytemuck::pod_collect_to_vec(
                &readback::read_buffer(&ctx, &on.tile_depth, 0, on.tile_depth.size()).unwrap(),
            );
            let occupancy: Vec<u32> = bytemuck::pod_collect_to_vec(
                &readback::read_buffer(&ctx, &on.occupancy, 0, on.occupancy.size()).unwrap(),
            );
            let mut dropped = 0u64;
            for bin in 0..on.params.bins {
                let (all, kept) = (a.list(bin as usize), b.list(bin as usize));
                // Kept in order: a subsequence of the list without occlusion.
                let mut it = all.iter();
                for l in kept {
                    assert!(
                        it.any(|x| x == l),
                        "{what}: bin {bin} keeps {l}, not in order of its list"
                    );
                }
                if all.len() == kept.len() {
                    continue;
                }
                let cell =
                    cell_corners(&on.params, &view, (&td, &occupancy), bin).unwrap_or_else(|| {
                        panic!("{what}: bin {bin} drops lights with no covered pixel")
                    });
                let kept: HashSet<u32> = kept.iter().copied().collect();
                for &l in all {
                    let p = scene.lights[l as usize].position.as_dvec3();
                    let wide = 1e-3
                        * p.abs()
                            .max_element()
                            .max(cell[0].abs().max_element())
                            .max(1.0);
                    let hidden = kept.get(&l).is_none();
                    if hidden {
                        dropped += 1;
                        assert!(
                            occ.iter().any(|o| hides(o, p, &cell, 0.0)),
                            "{what}: bin {bin} drops light {l} at {p}, which no occluder hides from its cell in f64"
                        );
                    } else {
                        assert!(
                            !occ.iter().any(|o| hides(o, p, &cell, wide)),
                            "{what}: bin {bin} keeps light {l} at {p}, which f64 hides from its cell with a wide margin"
                        );
                    }
                }
            }
            assert_eq!(
                u64::from(on.occluded),
                dropped,
                "{what}: dropped pairs counted"
            );
            let inv = frame.clip_from_world.inverse();
            let shadowed = culler
                .exact_counts_with(&ctx, &gs, &depth, &on, inv, 1, true)
                .unwrap();
            let unshadowed = culler
                .exact_counts_with(&ctx, &gs, &depth, &off, inv, 1, false)
                .unwrap();
            let missed: u64 = shadowed.iter().map(|c| u64::from(c[1] - c[2])).sum();
            assert_eq!(
                missed, 0,
                "{what}: lists miss lights the shadowed exact set needs"
            );
            let unseen: u64 = unshadowed
                .iter()
                .zip(&shadowed)
                .map(|(u, s)| u64::from(u[1] - s[1]))
                .sum();
            println!(
                "{what}: {} occluders, {dropped} pairs dropped of {}; {unseen} (pixel, light) pairs in range unseen",
                occ.len(),
                a.indices.len()
            );
            dropped_all += dropped;
            unseen_all += unseen;
        }
    }
    assert!(
        dropped_all > 1000,
        "the test must fire: {dropped_all} pairs dropped"
    );
    assert!(
        unseen_all > 1000,
        "the shadowed exact set must differ: {unseen_all}"
    );
}

#[test]
fn occlusion_refuses_zbin_and_a_culler_without_occluders() {
    let ctx = common::gpu();
    let scene = ProceduralScene::from_name("atrium")
        .unwrap()
        .build()
        .unwrap();
    let (gs, depth, _) = common::depth_prepass(&ctx, &scene, &scene.camera, 32, 32);
    let mut culler = Culler::new(&ctx, &gs);
    let mut timer = GpuTimer::new(&ctx, 16);
    let settings = CullSettings {
        occlusion: true,
        ..CullSettings::for_camera(&scene.camera)
    };
    let err = |culler: &Culler, strategy: &Strategy| match culler.run(
        &ctx,
        &gs,
        &depth,
        strategy,
        &settings,
        &mut GpuTimer::new(&ctx, 16),
    ) {
        Ok(_) => panic!("occlusion ran where it should be refused"),
        Err(e) => e.to_string(),
    };
    let e = err(&culler, &Strategy::tiled_gather(8));
    assert!(
        e.contains("occlusion") && e.contains("set_occluders"),
        "{e}"
    );
    // More occluders than the pass's workgroup holds: an error naming the field and the bound.
    let many = manylights_scene::occluders::of_scene(&scene);
    assert!(!many.is_empty());
    let many: Vec<_> = many.iter().cycle().take(65).cloned().collect();
    let e = culler.set_occluders(&ctx, &many).unwrap_err().to_string();
    assert!(
        e.contains("occluders = 65") && e.contains("at most 64"),
        "{e}"
    );
    culler.set_occluders(&ctx, &[]).unwrap();
    let zbin = Strategy::ZBin {
        tile_size: 8,
        bins: 32,
        slicing: Slicing::Exponential,
    };
    let e = err(&culler, &zbin);
    assert!(e.contains("occlusion") && e.contains("z-binning"), "{e}");
    // No occluder: nothing dropped, no pass.
    let out = culler
        .run(
            &ctx,
            &gs,
            &depth,
            &Strategy::tiled_gather(8),
            &settings,
            &mut timer,
        )
        .unwrap();
    assert_eq!(out.occluded, 0);
    assert!(!out.passes.iter().any(|p| p.name == "cull.occlusion"));
}
