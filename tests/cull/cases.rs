//! The random scenes, lights and cameras of the culling tests, and what they share: rendering
//! a case, the oracles' lists, running a strategy and checking its declared plan.

use super::*;

/// Every strategy, with tile sizes and cluster options varied.
pub(crate) fn strategies() -> Vec<Strategy> {
    vec![
        Strategy::tiled_gather(8),
        // Coarse-to-fine with several coarse tiles, partial ones at the edges; and without.
        Strategy::tiled_gather(4),
        Strategy::TiledGather {
            tile_size: 16,
            coarse: 0,
        },
        Strategy::tiled_gather(32),
        Strategy::TiledScatter { tile_size: 8 },
        Strategy::TiledScatter { tile_size: 16 },
        Strategy::DepthMask {
            tile_size: 8,
            coarse: 0,
        },
        Strategy::depth_mask(16),
        Strategy::Clustered {
            tile_size: 16,
            slices: 16,
            slicing: Slicing::Exponential,
            skip_empty: false,
            ordered: true,
            cells: false,
        },
        Strategy::Clustered {
            tile_size: 8,
            slices: 8,
            slicing: Slicing::Linear,
            skip_empty: true,
            ordered: false,
            cells: false,
        },
        Strategy::ZBin {
            tile_size: 8,
            bins: 32,
            slicing: Slicing::Exponential,
        },
        // Bins of several workgroups' worth (cull.zbin.bins reduces 256 in workgroup memory).
        Strategy::ZBin {
            tile_size: 16,
            bins: 1024,
            slicing: Slicing::Linear,
        },
    ]
}

/// One test configuration: a scene with lights and a camera.
pub(crate) struct Case {
    pub(crate) scene: Scene,
    pub(crate) camera: Camera,
    pub(crate) label: String,
}

/// A random scene, lights and camera. Besides the generated lights every case holds a light
/// containing the camera, one whose centre is behind the camera, and one crossing the near
/// plane; spots range from 1 degree to 120 degrees.
pub(crate) fn random_case(seed: u64) -> Case {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let which = rng.random_range(0..4u32);
    let proc_scene = match which {
        0 => ProceduralScene::Atrium(AtriumParams {
            bays: rng.random_range(2..6),
            storeys: rng.random_range(1..3),
            cloth: rng.random_bool(0.5),
            glass: false,
        }),
        1 => ProceduralScene::Pillars(PillarsParams {
            count: rng.random_range(4..40),
            width: rng.random_range(0.05..0.5),
            gap: rng.random_range(2.0..30.0),
            glass: false,
        }),
        2 => ProceduralScene::Topdown(TopdownParams {
            size: rng.random_range(5.0..60.0),
            subdivisions: 4,
        }),
        _ => ProceduralScene::City(CityParams {
            blocks: rng.random_range(2..6),
            seed,
            max_height: rng.random_range(5.0..40.0),
        }),
    };
    let mut scene = proc_scene.build().unwrap();
    let b = scene.light_bounds;
    let ext = b.extent().max_element();
    let spec = LightSpec {
        generator: match rng.random_range(0..4u32) {
            0 => LightGenerator::Uniform,
            1 => LightGenerator::SurfaceHugging { offset: 0.05 },
            2 => LightGenerator::Clustered {
                clusters: 3,
                spread: ext * 0.05,
            },
            _ => LightGenerator::LightField,
        },
        count: rng.random_range(20..160),
        seed,
        radius: RadiusRule::Fixed(ext * rng.random_range(0.02..0.4)),
        intensity: 1.0,
        spot_fraction: 0.3,
        spot_outer_deg: [1.0, 10.0, 45.0, 89.95, 90.0, 120.0][rng.random_range(0..6)],
        ..LightSpec::default()
    };
    scene.lights = spec.generate(&scene).unwrap();
    let pick = |rng: &mut rand_pcg::Pcg64| {
        b.min
            + b.extent()
                * Vec3::new(
                    rng.random::<f32>(),
                    rng.random::<f32>(),
                    rng.random::<f32>(),
                )
    };
    let camera = if rng.random_bool(0.3) {
        scene.camera
    } else {
        let position = pick(&mut rng);
        let mut target = pick(&mut rng);
        if (target - position).length() < 1e-2 {
            target += Vec3::X;
        }
        let near = rng.random_range(0.05..0.5);
        let projection = if rng.random_bool(0.2) {
            Projection::Orthographic {
                height: ext * rng.random_range(0.2..1.0),
                near: -ext,
                far: ext * 3.0,
            }
        } else {
            Projection::Perspective {
                fov_y_deg: rng.random_range(30.0..110.0),
                near,
                far: ext * 3.0,
            }
        };
        let up = if (target - position).normalize().y.abs() > 0.99 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        Camera {
            position,
            target,
            up,
            projection,
        }
    };
    camera.validate().unwrap();
    let fwd = (camera.target - camera.position).normalize();
    let (near, _) = camera.near_far();
    let r = ext * 0.1;
    scene.lights.push(Light::point(
        camera.position + fwd * r * 0.3,
        r,
        Vec3::ONE,
        1.0,
    )); // contains the camera
    scene.lights.push(Light::point(
        camera.position - fwd * r * 0.6,
        r,
        Vec3::ONE,
        1.0,
    )); // centre behind
    scene.lights.push(Light::point(
        camera.position + fwd * near.max(0.01),
        near.max(0.01) * 0.8,
        Vec3::ONE,
        1.0,
    )); // crosses near
    scene.lights.push(Light {
        kind: LightKind::Spot {
            direction: fwd,
            inner_angle: 0.0,
            outer_angle: 0.3,
        },
        ..Light::point(camera.position - fwd * r * 0.2, r * 3.0, Vec3::ONE, 1.0)
    });
    scene.validate().unwrap();
    Case {
        label: format!("seed {seed} ({})", proc_scene.name()),
        scene,
        camera,
    }
}

pub(crate) struct Rendered {
    pub(crate) gpu_scene: manylights_gpu::GpuScene,
    pub(crate) depth_tex: wgpu::Texture,
    pub(crate) depth: Vec<f32>,
    pub(crate) frame: GpuFrame,
    pub(crate) lights: Vec<GpuLight>,
    pub(crate) exact: Vec<Option<Vec<u32>>>,
    pub(crate) w: u32,
    pub(crate) h: u32,
}

pub(crate) fn render(ctx: &GpuContext, case: &Case, w: u32, h: u32) -> Rendered {
    let (gpu_scene, depth_tex, depth) = common::depth_prepass(ctx, &case.scene, &case.camera, w, h);
    let frame = GpuFrame::new(&case.camera, w, h, case.scene.lights.len() as u32);
    let points = surface_points(&frame, &depth, w, h);
    let exact = exact_sets(&points, &case.scene.lights);
    let lights = case.scene.lights.iter().map(GpuLight::from).collect();
    Rendered {
        gpu_scene,
        depth_tex,
        depth,
        frame,
        lights,
        exact,
        w,
        h,
    }
}

pub(crate) fn params(r: &Rendered, case: &Case, s: &Strategy) -> GpuCullParams {
    s.params(
        r.w,
        r.h,
        r.lights.len() as u32,
        &CullSettings::for_camera(&case.camera),
    )
}

/// The CPU oracle's lists for a strategy, computed from the depth buffer alone.
pub(crate) fn oracle_lists(r: &Rendered, case: &Case, s: &Strategy) -> (GpuCullParams, BinLists) {
    let p = params(r, case, s);
    let lists = match s {
        Strategy::Clustered { .. } => cpu::clustered(
            &r.frame,
            &p,
            &r.lights,
            &cpu::occupancy(&r.frame, &p, &r.depth, r.w, r.h),
        ),
        Strategy::TiledScatter { .. } => cpu::scatter(
            &r.frame,
            &p,
            &r.lights,
            &cpu::depth_bounds(&r.frame, &p, &r.depth, r.w, r.h).0,
        ),
        Strategy::ZBin { .. } => cpu::zbin_lists(
            &r.frame,
            &p,
            &r.lights,
            &cpu::depth_bounds(&r.frame, &p, &r.depth, r.w, r.h).0,
            &cpu::zbin_order(&r.frame, &p, &r.lights),
        ),
        _ => cpu::gather(
            &r.frame,
            &p,
            &r.lights,
            &cpu::depth_bounds(&r.frame, &p, &r.depth, r.w, r.h).0,
        ),
    };
    (p, lists.to_bin_lists())
}

/// Z-binning's sorted lights from the GPU: every light once, sorted by the oracle's keys (a key
/// within a hair of a sub-bin boundary may be one off on the GPU; the sort's stability is
/// tests/sort.rs's).
pub(crate) fn check_zbin_order(what: &str, r: &Rendered, p: &GpuCullParams, order: &[u32]) {
    let mut seen = order.to_vec();
    seen.sort_unstable();
    assert!(
        seen.iter().copied().eq(0..r.lights.len() as u32),
        "{what}: zbin order is not a permutation of the lights"
    );
    let keys = cpu::zbin_keys(&r.frame, p, &r.lights);
    for w in order.windows(2) {
        let (a, b) = (keys[w[0] as usize], keys[w[1] as usize]);
        assert!(
            a <= b + 1,
            "{what}: zbin order puts light {} (key {a}) before {} (key {b})",
            w[0],
            w[1]
        );
    }
}

pub(crate) fn metrics(r: &Rendered, p: &GpuCullParams, lists: &BinLists) -> ListMetrics {
    evaluate(&r.frame, p, &r.depth, r.w, r.h, &r.exact, lists)
}

pub(crate) fn run_gpu(
    ctx: &GpuContext,
    culler: &Culler,
    r: &Rendered,
    case: &Case,
    s: &Strategy,
) -> manylights_cull::CullOutput {
    let mut timer = GpuTimer::new(ctx, 16);
    let out = culler
        .run(
            ctx,
            &r.gpu_scene,
            &r.depth_tex,
            s,
            &CullSettings::for_camera(&case.camera),
            &mut timer,
        )
        .unwrap();
    check_plan(
        &format!("{} {}", case.label, s.name()),
        &out.passes,
        timer.read(ctx).unwrap(),
        1,
    );
    out
}

/// A run's declared steps (`CullOutput::passes`): each pass's reads and writes are what its
/// entry point reads and writes (`global_use`), every buffer a pass reads is an input of the
/// run or written by an earlier step of it, and the timer recorded exactly the declared passes,
/// in order, `runs` times (besides the scan's and the sort's own).
pub(crate) fn check_plan(
    what: &str,
    passes: &[StepInfo],
    timed: Option<Vec<PassTiming>>,
    runs: usize,
) {
    assert!(
        passes.iter().any(|s| s.name.starts_with("cull.")),
        "{what}: no culling pass declared"
    );
    crate::global_use::check_global_use(what, passes);
    let mut written: HashSet<Buf> = Buf::INPUTS.into_iter().collect();
    for s in passes {
        for b in &s.reads {
            assert!(
                written.contains(b),
                "{what}: {} reads {} before any step writes it",
                s.name,
                b.name()
            );
        }
        written.extend(s.writes.iter().copied());
    }
    if let Some(timed) = timed {
        let declared: Vec<&str> = passes
            .iter()
            .map(|s| s.name.as_str())
            .filter(|n| !matches!(*n, "clear" | "scan" | "sort"))
            .collect::<Vec<_>>()
            .repeat(runs);
        let timed: Vec<&str> = timed
            .iter()
            .map(|p| p.label.as_str())
            .filter(|l| !l.starts_with("scan.") && !l.starts_with("sort."))
            .collect();
        assert_eq!(declared, timed, "{what}: passes declared and timed");
    }
}
