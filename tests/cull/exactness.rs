//! Zero false negatives: over random seeds on the CPU and the GPU, in deep views; 2.5D against
//! gather; and a check that a false negative does show.

use super::*;

/// Zero false negatives for every strategy's CPU oracle over 200 random scene/light/camera
/// seeds (depth buffers from the GPU prepass; lists and exact sets on the CPU).
#[test]
fn cpu_oracles_have_no_false_negatives_over_200_seeds() {
    let ctx = common::gpu();
    let (w, h) = (37, 23);
    let mut fp = vec![(0u64, 0u64); strategies().len()];
    for seed in 1000..1200u64 {
        let case = random_case(seed);
        let r = render(&ctx, &case, w, h);
        for (k, s) in strategies().iter().enumerate() {
            let (p, lists) = oracle_lists(&r, &case, s);
            let m = metrics(&r, &p, &lists);
            assert_eq!(
                m.false_negatives,
                0,
                "{} {}: {} false negatives",
                case.label,
                s.name(),
                m.false_negatives
            );
            fp[k].0 += m.evaluated;
            fp[k].1 += m.needed;
        }
    }
    for (s, (e, n)) in strategies().iter().zip(fp) {
        println!(
            "{s:?}: false-positive ratio over 200 seeds {:.3}",
            e as f64 / n as f64
        );
    }
}

/// Zero false negatives for every strategy on the GPU over 10 random seeds.
#[test]
fn gpu_strategies_have_no_false_negatives_over_10_seeds() {
    let ctx = common::gpu();
    let (w, h) = (61, 37);
    let mut culler = None;
    for seed in 2000..2010u64 {
        let case = random_case(seed);
        let r = render(&ctx, &case, w, h);
        let culler = culler.get_or_insert_with(|| Culler::new(&ctx, &r.gpu_scene));
        for s in strategies() {
            let out = run_gpu(&ctx, culler, &r, &case, &s);
            let m = metrics(&r, &out.params, &out.read(&ctx).unwrap());
            assert_eq!(m.false_negatives, 0, "{} {}", case.label, s.name());
        }
    }
}

/// Deep views, where depth precision and the exponential slices are at their worst: the
/// atrium and the CIS 5650 hall with near 0.01 and far 5000, and a street-level view down the
/// city: every strategy keeps every light a pixel needs, on the GPU, at 97 x 61.
#[test]
fn gpu_strategies_have_no_false_negatives_in_deep_views() {
    let ctx = common::gpu();
    let (w, h) = (97, 61);
    let deep = |name: &str| {
        let mut scene = ProceduralScene::from_name(name).unwrap().build().unwrap();
        scene.lights = LightSpec {
            generator: LightGenerator::Uniform,
            count: 300,
            seed: 21,
            radius: RadiusRule::Fixed(scene.light_bounds.extent().max_element() * 0.08),
            ..LightSpec::default()
        }
        .generate(&scene)
        .unwrap();
        let mut camera = scene.camera;
        if let Projection::Perspective { near, far, .. } = &mut camera.projection {
            (*near, *far) = (0.01, 5000.0);
        }
        Case {
            scene,
            camera,
            label: format!("{name}, near 0.01, far 5000"),
        }
    };
    let mut cases = vec![deep("atrium"), deep("cis5650")];
    // Street level: the eye 1.7 m above the ground between the city's blocks, looking down the
    // street to the far side.
    let mut city = deep("city");
    let b = city.scene.bounds();
    let street_z = b.min.z + 0.5;
    city.camera = Camera::perspective(
        Vec3::new(b.min.x + 1.0, 1.7, street_z),
        Vec3::new(b.max.x, 1.7, street_z),
        60.0,
        0.01,
        5000.0,
    );
    city.label = "city at street level, near 0.01, far 5000".into();
    cases.push(city);
    let mut culler = None;
    for case in &cases {
        let r = render(&ctx, case, w, h);
        let culler = culler.get_or_insert_with(|| Culler::new(&ctx, &r.gpu_scene));
        let covered = r.depth.iter().filter(|&&z| z < 1.0).count();
        assert!(
            covered > (w * h) as usize / 4,
            "{}: {covered} pixels covered",
            case.label
        );
        for s in strategies() {
            let out = run_gpu(&ctx, culler, &r, case, &s);
            let m = metrics(&r, &out.params, &out.read(&ctx).unwrap());
            assert!(m.needed > 0, "{}: no light reaches a pixel", case.label);
            assert_eq!(m.false_negatives, 0, "{} {}", case.label, s.name());
        }
    }
}

/// 2.5D culling keeps a subset of tiled gather's lists in every tile (over 20 seeds, on the
/// GPU), and on `pillars` culls strictly more.
#[test]
fn depth_mask_never_keeps_what_gather_culls_and_wins_on_pillars() {
    let ctx = common::gpu();
    let mut culler = None;
    let mut cases: Vec<Case> = (3000..3020u64).map(random_case).collect();
    let mut pillars = ProceduralScene::Pillars(PillarsParams::default())
        .build()
        .unwrap();
    pillars.lights = LightSpec {
        generator: LightGenerator::LightField,
        count: 512,
        radius: RadiusRule::Fixed(1.0),
        ..LightSpec::default()
    }
    .generate(&pillars)
    .unwrap();
    let camera = pillars.camera;
    cases.push(Case {
        scene: pillars,
        camera,
        label: "pillars".into(),
    });
    for case in &cases {
        let r = render(&ctx, case, 96, 54);
        let culler = culler.get_or_insert_with(|| Culler::new(&ctx, &r.gpu_scene));
        let gather = run_gpu(&ctx, culler, &r, case, &Strategy::tiled_gather(16));
        let masked = run_gpu(&ctx, culler, &r, case, &Strategy::depth_mask(16));
        let (g, m) = (gather.read(&ctx).unwrap(), masked.read(&ctx).unwrap());
        for b in 0..g.ranges.len() {
            let gs = g.sorted(b);
            for l in m.list(b) {
                assert!(
                    gs.binary_search(l).is_ok(),
                    "{}: tile {b}: 2.5D keeps light {l} that gather culls",
                    case.label
                );
            }
        }
        if case.label == "pillars" {
            let (mg, mm) = (
                metrics(&r, &gather.params, &g),
                metrics(&r, &masked.params, &m),
            );
            println!(
                "pillars, 512 lights of radius 1 m, 96x54, 16 px tiles: lights evaluated per pixel {:.2} (gather) vs {:.2} (2.5D), \
                 false-positive ratio {:.2} vs {:.2}, list entries {} vs {}",
                mg.lights_per_pixel_mean,
                mm.lights_per_pixel_mean,
                mg.false_positive_ratio.unwrap(),
                mm.false_positive_ratio.unwrap(),
                g.indices.len(),
                m.indices.len()
            );
            assert!(
                mm.evaluated < mg.evaluated,
                "2.5D must cull strictly more on pillars"
            );
            assert_eq!(mm.false_negatives + mg.false_negatives, 0);
        }
    }
}

/// The false-negative check can fail: lists culled with lights shrunk by 5% (a negative slack)
/// miss lights that reach some pixels, and `evaluate` counts them.
#[test]
fn shrunk_lights_produce_false_negatives() {
    let ctx = common::gpu();
    let mut missed = 0;
    for seed in 4000..4010u64 {
        let case = random_case(seed);
        let r = render(&ctx, &case, 48, 32);
        let s = Strategy::tiled_gather(8);
        let mut p = s.params(
            r.w,
            r.h,
            r.lights.len() as u32,
            &CullSettings::for_camera(&case.camera),
        );
        let td = cpu::depth_bounds(&r.frame, &p, &r.depth, r.w, r.h).0;
        let shrunk: Vec<GpuLight> = r
            .lights
            .iter()
            .map(|l| GpuLight {
                radius: l.radius * 0.95,
                ..*l
            })
            .collect();
        p.slack = 0.0;
        missed += metrics(
            &r,
            &p,
            &cpu::gather(&r.frame, &p, &shrunk, &td).to_bin_lists(),
        )
        .false_negatives;
    }
    assert!(
        missed > 0,
        "culling with shrunk lights must show false negatives"
    );
}
