//! The frame, not the culling pass: culling and the deferred lighting pass that reads its lists,
//! timed together (`frame.cull_shade/<setting>`). The measured time is the sum of the GPU
//! timestamp deltas of every culling pass and `shade.deferred` of back-to-back frames
//! (`Culler::run_repeated_with`: lists sized from a first frame, each run followed by the
//! lighting pass, no host round trip), returned to criterion through `iter_custom`. The G-buffer
//! is drawn once, outside the measurement (a raster pass, slow on compute chips and the same
//! for every strategy). `frame.visibility` times the visibility pass alone (raster and compute)
//! and `frame.whole` the whole frame, geometry included.
//!
//! Settings: the Forward+ paper's configuration (3,072 light-field lights of
//! radius 2.5 m in the atrium, 1280 x 720) with gather's 8-pixel tiles and with clusters of 64
//! pixels x 24 slices; the CIS 5650 hall (`cis5650`) with 5,000 and 50,000 lights of radius 2 m
//! at 1920 x 1080, gather's 16-pixel tiles (at 5,000 also 24), and at 50,000 clusters too; 1M
//! lights of radius 0.5 m in the atrium at 1920 x 1080 with clusters without their order pass.
//! Z-binning (256 exponential bins) at the Forward+ configuration in 8-pixel tiles, in the
//! hall in 16-pixel tiles, and at 1M lights in 32- and 16-pixel tiles. At 1M lights also the
//! clusters `tune` picks there (32 px x 32 slices), ordered and not, and ordered at 24 px x 48
//! and x 32, and at 32 x 32 and 24 x 32 with the clusters' 2.5D cells (`<name>_cells`). The
//! Forward+ configuration and the hall at 5,000 lights (16 and 24 px) also into a
//! 16-bit float lit image (`<name>_f16`, `HdrFormat::F16`); every other setting's is 32-bit.
//!
//! `MANYLIGHTS_BENCH_SPANS=1` times each frame with one timestamp pair around its culling and
//! lighting instead (clears and gaps between passes included). `MANYLIGHTS_BENCH_QUICK=1`
//! shrinks everything for a smoke run on lavapipe; figures come only from the GPU machine.

mod common;

use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use manylights_cull::{CullSettings, Slicing, Strategy};
use manylights_gpu::GpuScene;
use manylights_gpu::timing::{GpuTimer, MAX_QUERIES};
use manylights_scene::procedural::ProceduralScene;
use manylights_scene::{LightGenerator, LightSpec, RadiusRule, Scene};
use manylights_shade::{Backend, HdrFormat, Renderer};

use common::{configure, gpu, quick};

/// The atrium with the lights of `spec`.
fn atrium(spec: LightSpec) -> Scene {
    let mut s = ProceduralScene::from_name("atrium")
        .unwrap()
        .build()
        .unwrap();
    s.lights = spec.generate(&s).unwrap();
    s
}

/// One setting: its name, scene, resolution, strategy and lit image's format.
struct Setting {
    name: &'static str,
    scene: Scene,
    size: (u32, u32),
    strategy: Strategy,
    hdr: HdrFormat,
}

fn settings() -> Vec<Setting> {
    let q = quick();
    let paper = || {
        atrium(LightSpec {
            generator: LightGenerator::LightField,
            count: if q { 256 } else { 3072 },
            seed: 2012,
            radius: RadiusRule::Fixed(2.5),
            intensity: 4.0,
            ..LightSpec::default()
        })
    };
    let grid = |tile_size, slices, ordered, cells| Strategy::Clustered {
        tile_size,
        slices,
        slicing: Slicing::Exponential,
        skip_empty: false,
        ordered,
        cells,
    };
    let clusters = |ordered| grid(64, 24, ordered, false);
    let million = || {
        atrium(LightSpec {
            generator: LightGenerator::Uniform,
            count: if q { 4096 } else { 1 << 20 },
            seed: 1,
            radius: RadiusRule::Fixed(0.5),
            intensity: 0.5,
            ..LightSpec::default()
        })
    };
    let zbin = |tile_size| Strategy::ZBin {
        tile_size,
        bins: manylights_cull::DEFAULT_ZBINS,
        slicing: Slicing::Exponential,
    };
    let paper_size = if q { (160, 90) } else { (1280, 720) };
    let full = if q { (160, 90) } else { (1920, 1080) };
    // The CIS 5650 course's setting: lights of radius 2 uniform in the hall's light box.
    let cis5650 = |count| {
        let mut s = ProceduralScene::from_name("cis5650")
            .unwrap()
            .build()
            .unwrap();
        s.lights = LightSpec {
            generator: LightGenerator::Uniform,
            count,
            seed: 5650,
            radius: RadiusRule::Fixed(2.0),
            intensity: 4.0,
            ..LightSpec::default()
        }
        .generate(&s)
        .unwrap();
        s
    };
    let mut v = vec![
        Setting {
            name: "harada2012_gather8",
            scene: paper(),
            size: paper_size,
            strategy: Strategy::tiled_gather(8),
            hdr: HdrFormat::F32,
        },
        Setting {
            name: "harada2012_clustered64x24",
            scene: paper(),
            size: paper_size,
            strategy: clusters(true),
            hdr: HdrFormat::F32,
        },
        Setting {
            name: "harada2012_zbin8",
            scene: paper(),
            size: paper_size,
            strategy: zbin(8),
            hdr: HdrFormat::F32,
        },
        // The CIS 5650 hall's clusters at 500 lights (the clusters' tile path).
        Setting {
            name: "cis5650_500_clustered64x24",
            scene: cis5650(500),
            size: full,
            strategy: clusters(true),
            hdr: HdrFormat::F32,
        },
        Setting {
            name: "cis5650_5k_gather",
            scene: cis5650(if q { 500 } else { 5000 }),
            size: full,
            strategy: Strategy::tiled_gather(16),
            hdr: HdrFormat::F32,
        },
        // The fastest tiles for gather there in `manylights run` (H100).
        Setting {
            name: "cis5650_5k_gather24",
            scene: cis5650(if q { 500 } else { 5000 }),
            size: full,
            strategy: Strategy::tiled_gather(24),
            hdr: HdrFormat::F32,
        },
        Setting {
            name: "cis5650_5k_zbin16",
            scene: cis5650(if q { 500 } else { 5000 }),
            size: full,
            strategy: zbin(16),
            hdr: HdrFormat::F32,
        },
        Setting {
            name: "cis5650_50k_gather",
            scene: cis5650(if q { 2000 } else { 50_000 }),
            size: full,
            strategy: Strategy::tiled_gather(16),
            hdr: HdrFormat::F32,
        },
        Setting {
            name: "cis5650_50k_clustered64x24",
            scene: cis5650(if q { 2000 } else { 50_000 }),
            size: full,
            strategy: clusters(true),
            hdr: HdrFormat::F32,
        },
        Setting {
            name: "cis5650_50k_zbin16",
            scene: cis5650(if q { 2000 } else { 50_000 }),
            size: full,
            strategy: zbin(16),
            hdr: HdrFormat::F32,
        },
        Setting {
            name: "atrium_1m_clustered_unordered",
            scene: million(),
            size: full,
            strategy: clusters(false),
            hdr: HdrFormat::F32,
        },
        // What `manylights tune` picks there: clusters of 32 px x 32 slices, ordered and not.
        Setting {
            name: "atrium_1m_clustered32x32",
            scene: million(),
            size: full,
            strategy: grid(32, 32, true, false),
            hdr: HdrFormat::F32,
        },
        Setting {
            name: "atrium_1m_clustered32x32_unordered",
            scene: million(),
            size: full,
            strategy: grid(32, 32, false, false),
            hdr: HdrFormat::F32,
        },
        // The fastest grids there in `manylights run` (H100): 24 px x 48 slices, and with the
        // lighting pass's test of each cluster's light against the box of a workgroup's pixels,
        // 24 x 32.
        Setting {
            name: "atrium_1m_clustered24x48",
            scene: million(),
            size: full,
            strategy: grid(24, 48, true, false),
            hdr: HdrFormat::F32,
        },
        Setting {
            name: "atrium_1m_clustered24x32",
            scene: million(),
            size: full,
            strategy: grid(24, 32, true, false),
            hdr: HdrFormat::F32,
        },
        // The same two grids with the clusters' 2.5D cells (`cells: true`).
        Setting {
            name: "atrium_1m_clustered32x32_cells",
            scene: million(),
            size: full,
            strategy: grid(32, 32, true, true),
            hdr: HdrFormat::F32,
        },
        Setting {
            name: "atrium_1m_clustered24x32_cells",
            scene: million(),
            size: full,
            strategy: grid(24, 32, true, true),
            hdr: HdrFormat::F32,
        },
        // Z-binning with its masks set a light at a time (`cull.zbin.scatter`): 255 MB of
        // masks in 32-pixel tiles, 1 GB in 16-pixel ones.
        Setting {
            name: "atrium_1m_zbin32",
            scene: million(),
            size: full,
            strategy: zbin(32),
            hdr: HdrFormat::F32,
        },
        Setting {
            name: "atrium_1m_zbin16",
            scene: million(),
            size: full,
            strategy: zbin(16),
            hdr: HdrFormat::F32,
        },
    ];
    // The lit image in 16-bit floats (`HdrFormat::F16`, as engines' HDR targets): the
    // Forward+ configuration and the hall at 5,000 lights.
    for (from, name) in [
        ("harada2012_gather8", "harada2012_gather8_f16"),
        ("cis5650_5k_gather", "cis5650_5k_gather_f16"),
        ("cis5650_5k_gather24", "cis5650_5k_gather24_f16"),
    ] {
        let s = v
            .iter()
            .find(|s| s.name == from)
            .expect("a setting of that name");
        v.push(Setting {
            name,
            scene: s.scene.clone(),
            size: s.size,
            strategy: s.strategy,
            hdr: HdrFormat::F16,
        });
    }
    v
}

fn spans() -> bool {
    std::env::var("MANYLIGHTS_BENCH_SPANS").is_ok_and(|v| v != "0")
}

fn cull_shade(c: &mut Criterion) {
    let ctx = gpu();
    let mut g = c.benchmark_group("frame.cull_shade");
    configure(&mut g);
    for s in settings() {
        let (w, h) = s.size;
        let gs = GpuScene::upload(&ctx, &s.scene, &s.scene.camera, w, h).unwrap();
        let renderer = Renderer::with_format(&ctx, &gs, 1, s.hdr).unwrap();
        let settings = CullSettings::for_camera(&s.scene.camera);
        let first = renderer
            .render(&ctx, &gs, Backend::Deferred, &s.strategy, &settings, (w, h))
            .unwrap();
        let lists = first.lists.as_ref().expect("deferred culls");
        // Passes a frame: the single frame's culling and lighting (back to back, at most as
        // many; the G-buffer pass is not repeated).
        let passes = first.timings.as_ref().expect("timestamps").len() as u64;
        let batch = (u64::from(MAX_QUERIES / 2) / passes.max(1)).clamp(1, 64);
        let mut pass = renderer.shade_pass(&ctx, &gs, &first).expect("deferred");
        let id = BenchmarkId::new(s.name, format!("{w}x{h}/{}", s.scene.lights.len()));
        g.bench_function(id, |b| {
            b.iter_custom(|iters| {
                let mut total = 0.0;
                let mut left = iters;
                while left > 0 {
                    let runs = left.min(batch);
                    let mut timer = if spans() {
                        GpuTimer::spans(&ctx, runs as u32).expect("timestamps between passes")
                    } else {
                        GpuTimer::new(&ctx, (runs * passes) as u32)
                    };
                    renderer
                        .culler
                        .run_repeated_with(
                            &ctx,
                            &gs,
                            &first.depth,
                            &s.strategy,
                            &settings,
                            lists,
                            runs as u32,
                            &mut timer,
                            &mut pass,
                        )
                        .unwrap();
                    let t = timer.read(&ctx).unwrap().expect("timestamps");
                    total += t.iter().map(|p| p.ms).sum::<f64>();
                    left -= runs;
                }
                Duration::from_secs_f64(total * 1e-3)
            })
        });
    }
    g.finish();
}

/// The visibility pass of the Forward+ configuration, the hall at 5,000 lights and the atrium at
/// a million lights, each frame timed as one span (`frame.visibility/<setting>_raster`: the
/// hardware pass, `shade.visibility`; `_compute`: `manylights_shade::vis_compute`, its clears
/// included), back to back in one submission: the two ways of drawing the visibility buffer
/// weighed against each other.
fn visibility(c: &mut Criterion) {
    use manylights_shade::vis_compute::{ComputeVisibility, Tiling};
    let ctx = gpu();
    let mut g = c.benchmark_group("frame.visibility");
    configure(&mut g);
    let all = settings();
    for name in [
        "harada2012_gather8",
        "cis5650_5k_gather",
        "atrium_1m_clustered32x32",
    ] {
        let Some(s) = all.iter().find(|s| s.name == name) else {
            continue;
        };
        let (w, h) = s.size;
        let gs = GpuScene::upload(&ctx, &s.scene, &s.scene.camera, w, h).unwrap();
        // The raster pass, as `visibility_pass: Raster` draws it.
        let mut renderer = Renderer::new(&ctx, &gs);
        renderer.visibility_pass = manylights_shade::VisibilityPass::Raster;
        let settings = CullSettings::for_camera(&s.scene.camera);
        let out = renderer
            .render(
                &ctx,
                &gs,
                Backend::Visibility,
                &s.strategy,
                &settings,
                (w, h),
            )
            .unwrap();
        let tilings = [(64, 256), (32, 256), (128, 256), (64, 64), (64, 1024)];
        for (block, small) in tilings {
            let cv = ComputeVisibility::with_tiling(&ctx, &gs, Tiling { block, small }).unwrap();
            let targets = cv.targets(&ctx, &gs, (w, h));
            if std::env::var("MANYLIGHTS_BENCH_PASSES").is_ok_and(|v| v != "0") {
                // Each pass of a few frames, printed: where the compute pass's time goes.
                let mut timer = GpuTimer::new(&ctx, 64);
                let mut enc = ctx.encoder("bench.visibility_compute.passes");
                for _ in 0..4 {
                    cv.encode(&mut enc, &mut timer, &gs, &targets);
                }
                timer.resolve(&mut enc);
                ctx.submit_and_wait(enc, "bench visibility compute passes")
                    .unwrap();
                for p in timer.read(&ctx).unwrap().expect("timestamps") {
                    eprintln!(
                        "{name} {w}x{h} b{block} s{small} {} {:.1} us",
                        p.label,
                        p.ms * 1e3
                    );
                }
            }
            let timed = |runs: u64, compute: bool| -> f64 {
                let mut timer =
                    GpuTimer::spans(&ctx, runs as u32).expect("timestamps between passes");
                if compute {
                    let mut enc = ctx.encoder("bench.visibility_compute");
                    for _ in 0..runs {
                        timer.span_begin(&mut enc, "visibility_compute");
                        cv.encode(&mut enc, &mut timer, &gs, &targets);
                    }
                    timer.span_end(&mut enc);
                    timer.resolve(&mut enc);
                    ctx.submit_and_wait(enc, "bench visibility compute")
                        .unwrap();
                } else {
                    renderer
                        .geometry_repeated(&ctx, &gs, &out, runs as u32, &mut timer)
                        .unwrap();
                }
                let t = timer.read(&ctx).unwrap().expect("timestamps");
                t.iter().map(|p| p.ms).sum::<f64>()
            };
            for (kind, compute) in [("raster", false), ("compute", true)] {
                if !compute && (block, small) != tilings[0] {
                    continue;
                }
                let kind = if compute {
                    format!("compute_b{block}_s{small}")
                } else {
                    kind.to_owned()
                };
                let id = BenchmarkId::new(format!("{name}_{kind}"), format!("{w}x{h}"));
                g.bench_function(id, |b| {
                    b.iter_custom(|iters| {
                        let mut total = 0.0;
                        let mut left = iters;
                        while left > 0 {
                            let runs = left.min(64);
                            total += timed(runs, compute);
                            left -= runs;
                        }
                        Duration::from_secs_f64(total * 1e-3)
                    })
                });
            }
        }
    }
    g.finish();
}

/// The whole frame in steady state, as experiments add up `gpu_ms_frame_steady`: each
/// iteration times `runs` frames' geometry back to back (a span each: the G-buffer
/// pass, or the visibility buffer rasterised in compute, or its raster pass), then `runs`
/// frames' culling and lighting back to back (a span each), and counts the sum of their
/// medians' worth: `frame.whole/<setting>_<strategy>_<backend>`, the backends `deferred`,
/// `visibility` (the compute rasteriser, its default) and `visibility_raster`. Criterion keeps
/// the GPU busy for seconds, where an experiment's cell times ten frames after a 200 ms warm-up:
/// these figures vary less from run to run.
fn whole(c: &mut Criterion) {
    use manylights_shade::VisibilityPass;
    let ctx = gpu();
    let mut g = c.benchmark_group("frame.whole");
    configure(&mut g);
    let all = settings();
    let gather16 = Strategy::tiled_gather(16);
    let clusters32 = Strategy::Clustered {
        tile_size: 32,
        slices: 32,
        slicing: Slicing::Exponential,
        skip_empty: false,
        ordered: true,
        cells: false,
    };
    let cases = [
        ("harada2012_gather8", "forward_plus", "gather16", gather16),
        (
            "harada2012_gather8",
            "forward_plus",
            "clusters32",
            clusters32,
        ),
        ("cis5650_5k_gather", "hall_5k", "gather16", gather16),
        ("cis5650_5k_gather", "hall_5k", "clusters32", clusters32),
        (
            "atrium_1m_clustered32x32",
            "atrium_1m",
            "clusters32",
            clusters32,
        ),
    ];
    let backends = [
        ("deferred", Backend::Deferred, VisibilityPass::Compute),
        ("visibility", Backend::Visibility, VisibilityPass::Compute),
        (
            "visibility_raster",
            Backend::Visibility,
            VisibilityPass::Raster,
        ),
    ];
    for (from, setting, label, strategy) in cases {
        let Some(s) = all.iter().find(|s| s.name == from) else {
            continue;
        };
        let (w, h) = s.size;
        let gs = GpuScene::upload(&ctx, &s.scene, &s.scene.camera, w, h).unwrap();
        let settings = CullSettings::for_camera(&s.scene.camera);
        let mut renderer = Renderer::new(&ctx, &gs);
        for (name, backend, pass) in backends {
            renderer.visibility_pass = pass;
            let renderer = &renderer;
            let first = renderer
                .render(&ctx, &gs, backend, &strategy, &settings, (w, h))
                .unwrap();
            let lists = first.lists.as_ref().expect("culled");
            let culler = &renderer.culler;
            let mut shade = renderer
                .shade_pass(&ctx, &gs, &first)
                .expect("lights in compute");
            let id = BenchmarkId::new(format!("{setting}_{label}_{name}"), format!("{w}x{h}"));
            g.bench_function(id, |b| {
                b.iter_custom(|iters| {
                    let mut total = 0.0;
                    let mut left = iters;
                    while left > 0 {
                        let runs = left.min(32) as u32;
                        let mut geometry = GpuTimer::spans(&ctx, runs).expect("timestamps");
                        renderer
                            .geometry_repeated(&ctx, &gs, &first, runs, &mut geometry)
                            .unwrap();
                        let mut frame = GpuTimer::spans(&ctx, runs).expect("timestamps");
                        culler
                            .run_repeated_with(
                                &ctx,
                                &gs,
                                &first.cull_depth,
                                &strategy,
                                &settings,
                                lists,
                                runs,
                                &mut frame,
                                &mut shade,
                            )
                            .unwrap();
                        for t in [geometry, frame] {
                            total += t
                                .read(&ctx)
                                .unwrap()
                                .expect("timestamps")
                                .iter()
                                .map(|p| p.ms)
                                .sum::<f64>();
                        }
                        left -= u64::from(runs);
                    }
                    Duration::from_secs_f64(total * 1e-3)
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, cull_shade, visibility, whole);
criterion_main!(benches);
