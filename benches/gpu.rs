//! GPU-side benchmarks: the measured time is the GPU timestamp delta of the named passes,
//! returned to criterion through `iter_custom`, so criterion's statistics apply to GPU time.
//! Set-up (scenes, uploads, the depth prepass) stays outside the measurement.
//!
//! Benchmarks are named after the passes they time:
//! - `cull.<strategy>/<width>x<height>/<lights>`: every culling pass of a strategy (its
//!   `cull.*`, `scan.*` and `sort.*` passes) over the atrium's depth buffer;
//! - `cull.tiled_gather_single/...`: gather without its coarse level, `cull.clustered_unordered/...`
//!   clusters without their order pass;
//! - `cull.harada2012/<variant>/3072`: the Forward+ paper's configuration (1280 x 720, 3,072
//!   lights, 8-pixel tiles), every strategy, gather with other chunks of lights a workgroup
//!   (`tiled_gather8_chunk<N>`), gather and 2.5D with tile masks stored by their count pass
//!   instead of their lines path (`*_stored`), and gather, 2.5D and scatter without tile masks
//!   (`*_unmasked`; scatter then sorts its pairs);
//! - `sort.radix/<keys>`, `sort.radix_portable/<keys>` and `sort.lampshade/<keys>`: (u32 key,
//!   u32 value) radix sorts of random 32-bit keys, ours (the default path, onesweep where the
//!   adapter takes it, and the portable 4-bit path) against the `lampshade` crate's on the same
//!   device; one more sort of each size is checked sorted and stable;
//! - `shade.<pass>/<backend>` and `frame.<backend>`: shading passes and whole frames at 4,096
//!   lights and 1920 x 1080, raster and compute passes apart.
//!
//! Culling runs go back to back in one submission after a run that sizes the lists (see
//! `cull_time`); `MANYLIGHTS_BENCH_ROUNDTRIP=1` times each run on its own instead.
//!
//! `MANYLIGHTS_BENCH_SORT_KEYS=N,M,...` picks the sorts' key counts.
//! `MANYLIGHTS_BENCH_GATHER_LINES=0` turns gather's and 2.5D's lines path off everywhere.
//! `MANYLIGHTS_SORT_MAX_SPIN=N` sets the onesweep sort's polls before its look-back falls back.
//!
//! `MANYLIGHTS_BENCH_QUICK=1` shrinks everything (light counts, resolutions, key counts) so the
//! benches can be smoke-run on lavapipe; figures come only from the GPU machine.

mod common;

use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use manylights_cull::radix_sort::{RadixSort, SortPath, SortedIn};
use manylights_cull::scan::ScanPath;
use manylights_cull::{CullSettings, Culler, Strategy};
use manylights_gpu::prepass::{DepthPrepass, depth_target};
use manylights_gpu::timing::{GpuTimer, MAX_QUERIES};
use manylights_gpu::{GpuContext, GpuScene, readback};
use manylights_scene::procedural::ProceduralScene;
use manylights_scene::{LightGenerator, LightSpec, RadiusRule, Scene};
use manylights_shade::{Backend, Renderer};

use common::{configure, gpu, quick};
use rand::{RngExt, SeedableRng};

/// `MANYLIGHTS_BENCH_ROUNDTRIP=1` (anything but `0`): culling runs timed one at a time, with
/// the host waiting for each, instead of back to back.
pub fn round_trip() -> bool {
    std::env::var("MANYLIGHTS_BENCH_ROUNDTRIP").is_ok_and(|v| v != "0")
}

/// Whether `MANYLIGHTS_BENCH_SPANS` asks for one pair of timestamps a culling run (see
/// [`cull_time`]).
pub fn spans() -> bool {
    std::env::var("MANYLIGHTS_BENCH_SPANS").is_ok_and(|v| v != "0")
}

/// A culler; `MANYLIGHTS_BENCH_GATHER_LINES=0` turns gather's and 2.5D's lines path off (their
/// count pass then stores tile masks and the fill expands them), to compare both in one run.
fn new_culler(ctx: &GpuContext, gs: &GpuScene) -> Culler {
    let mut c = Culler::new(ctx, gs);
    c.gather_lines = !std::env::var("MANYLIGHTS_BENCH_GATHER_LINES").is_ok_and(|v| v == "0");
    c
}

/// The atrium with `n` uniformly placed lights of radius 0.5 m (as experiments/scaling-1m.ron).
fn atrium(n: u32) -> Scene {
    atrium_with(LightSpec {
        generator: LightGenerator::Uniform,
        count: n,
        seed: 1,
        radius: RadiusRule::Fixed(0.5),
        intensity: 0.5,
        ..LightSpec::default()
    })
}

/// The atrium with the lights of `spec`.
fn atrium_with(spec: LightSpec) -> Scene {
    let mut s = ProceduralScene::from_name("atrium")
        .unwrap()
        .build()
        .unwrap();
    s.lights = spec.generate(&s).unwrap();
    s
}

/// `scene` uploaded for a `w` x `h` target, and its depth buffer from the prepass.
fn prepared(ctx: &GpuContext, scene: &Scene, w: u32, h: u32) -> (GpuScene, wgpu::Texture) {
    let gs = GpuScene::upload(ctx, scene, &scene.camera, w, h).unwrap();
    let depth = depth_target(ctx, w, h);
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    DepthPrepass::new(ctx, &gs).encode(
        &mut enc,
        &gs,
        &depth.create_view(&Default::default()),
        &mut GpuTimer::new(ctx, 1),
    );
    ctx.submit_and_wait(enc, "bench prepass").unwrap();
    (gs, depth)
}

fn ms(t: &[manylights_gpu::timing::PassTiming], pick: impl Fn(&str) -> bool) -> f64 {
    t.iter().filter(|p| pick(&p.label)).map(|p| p.ms).sum()
}

fn cull(c: &mut Criterion) {
    let ctx = gpu();
    let (counts, sizes): (Vec<u32>, Vec<(u32, u32)>) = if quick() {
        (vec![1024, 4096], vec![(160, 90)])
    } else {
        (
            vec![1024, 4096, 16_384, 65_536, 262_144, 1_048_576],
            vec![(1920, 1080), (3840, 2160)],
        )
    };
    for &(w, h) in &sizes {
        for &n in &counts {
            let scene = atrium(n);
            let (gs, depth) = prepared(&ctx, &scene, w, h);
            let culler = new_culler(&ctx, &gs);
            let settings = CullSettings::for_camera(&scene.camera);
            // The defaults; clusters without their order pass (what ordering costs); gather
            // without its coarse level (what coarse-to-fine saves).
            let unordered = Strategy::Clustered {
                tile_size: 64,
                slices: 24,
                slicing: manylights_cull::Slicing::Exponential,
                skip_empty: false,
                ordered: false,
                cells: false,
            };
            let single = Strategy::TiledGather {
                tile_size: 16,
                coarse: 0,
            };
            for strategy in Strategy::defaults().into_iter().chain([unordered, single]) {
                // Z-binning's masks grow as tiles x lights (1 GB at 1M lights and 1080p).
                if matches!(strategy, Strategy::ZBin { .. }) && n > 65_536 {
                    continue;
                }
                let name = match strategy {
                    Strategy::Clustered { ordered: false, .. } => "clustered_unordered",
                    Strategy::TiledGather { coarse: 0, .. } => "tiled_gather_single",
                    _ => strategy.name(),
                };
                let mut g = c.benchmark_group(format!("cull.{name}"));
                configure(&mut g);
                g.throughput(Throughput::Elements(u64::from(n)));
                g.bench_with_input(BenchmarkId::new(format!("{w}x{h}"), n), &n, |b, _| {
                    b.iter_custom(|iters| {
                        cull_time(&ctx, &culler, &gs, &depth, &strategy, &settings, iters)
                    })
                });
                g.finish();
            }
        }
    }
}

/// The GPU time of `iters` runs of `strategy`: every `cull.*`, `scan.*` and `sort.*` pass.
///
/// The runs go back to back, as frames do: a first, untimed run sizes the lists, then batches
/// of runs are each one submission with no host round trip inside ([`Culler::run_repeated`]).
/// (Both methods gave the same figures on the H200: docs/bench/HISTORY.md, Method.) `MANYLIGHTS_BENCH_ROUNDTRIP=1` times each run
/// on its own instead (two submissions and a readback of the list size each, the GPU idle in
/// between), the method of the oldest figures in docs/bench/HISTORY.md. `MANYLIGHTS_BENCH_SPANS=1`
/// times each back-to-back run with one pair of timestamps around all its passes instead of a
/// pair per pass ([`GpuTimer::spans`]): the run's time including the gaps between its passes,
/// without the passes' own timestamps.
fn cull_time(
    ctx: &GpuContext,
    culler: &Culler,
    gs: &GpuScene,
    depth: &wgpu::Texture,
    strategy: &Strategy,
    settings: &CullSettings,
    iters: u64,
) -> Duration {
    let culling =
        |l: &str| l.starts_with("cull.") || l.starts_with("scan.") || l.starts_with("sort.");
    let timed = |timer: &GpuTimer| {
        let t = timer
            .read(ctx)
            .unwrap()
            .expect("the benchmarks need timestamp queries");
        (ms(&t, culling), t.len() as u64)
    };
    let run = |timer: &mut GpuTimer| {
        culler
            .run(ctx, gs, depth, strategy, settings, timer)
            .unwrap()
    };
    let mut total = 0.0;
    if round_trip() {
        for _ in 0..iters {
            let mut timer = GpuTimer::new(ctx, 256);
            run(&mut timer);
            total += timed(&timer).0;
        }
        return Duration::from_secs_f64(total * 1e-3);
    }
    let mut timer = GpuTimer::new(ctx, 256);
    let first = run(&mut timer);
    let passes = timed(&timer).1.max(1);
    let batch = (u64::from(MAX_QUERIES / 2) / passes).clamp(1, 64);
    let mut left = iters;
    while left > 0 {
        let runs = left.min(batch);
        let mut timer = if spans() {
            GpuTimer::spans(ctx, runs as u32)
                .expect("MANYLIGHTS_BENCH_SPANS needs timestamps between passes")
        } else {
            GpuTimer::new(ctx, (runs * passes) as u32)
        };
        culler
            .run_repeated(
                ctx,
                gs,
                depth,
                strategy,
                settings,
                &first,
                runs as u32,
                &mut timer,
            )
            .unwrap();
        total += timed(&timer).0;
        left -= runs;
    }
    Duration::from_secs_f64(total * 1e-3)
}

/// The Forward+ paper's configuration, as experiments/harada2012.ron: the atrium with 3,072
/// light-field lights of radius 2.5 m at 1280 x 720. `cull.harada2012/<variant>/3072` times
/// every culling pass of: gather and 2.5D with 8-pixel tiles, with and without the coarse level
/// and with and without tile masks; gather with other chunk sizes; scatter with 8-pixel tiles,
/// with and without tile masks; clusters (16-pixel tiles, 16 exponential slices), ordered and
/// not.
fn cull_paper(c: &mut Criterion) {
    let ctx = gpu();
    let (w, h, n) = if quick() {
        (160, 90, 256)
    } else {
        (1280, 720, 3072)
    };
    let scene = atrium_with(LightSpec {
        generator: LightGenerator::LightField,
        count: n,
        seed: 2012,
        radius: RadiusRule::Fixed(2.5),
        intensity: 4.0,
        ..LightSpec::default()
    });
    let (gs, depth) = prepared(&ctx, &scene, w, h);
    let culler = new_culler(&ctx, &gs);
    let settings = CullSettings::for_camera(&scene.camera);
    let clusters = |ordered| Strategy::Clustered {
        tile_size: 16,
        slices: 16,
        slicing: manylights_cull::Slicing::Exponential,
        skip_empty: false,
        ordered,
        cells: false,
    };
    let variants = [
        ("tiled_gather8", Strategy::tiled_gather(8)),
        (
            "tiled_gather8_single",
            Strategy::TiledGather {
                tile_size: 8,
                coarse: 0,
            },
        ),
        ("depth_mask8", Strategy::depth_mask(8)),
        (
            "depth_mask8_single",
            Strategy::DepthMask {
                tile_size: 8,
                coarse: 0,
            },
        ),
        ("tiled_scatter8", Strategy::TiledScatter { tile_size: 8 }),
        ("clustered16x16", clusters(true)),
        ("clustered16x16_unordered", clusters(false)),
    ];
    let mut g = c.benchmark_group("cull.harada2012");
    configure(&mut g);
    let mut culler = culler;
    for (label, strategy) in variants {
        let culler = &culler;
        g.bench_with_input(BenchmarkId::new(label, n), &n, |b, _| {
            b.iter_custom(|iters| cull_time(&ctx, culler, &gs, &depth, &strategy, &settings, iters))
        });
    }
    // Gather and 2.5D with tile masks stored by their count pass and expanded by their fill,
    // not their lines path.
    culler.gather_lines = false;
    for (label, strategy) in [
        ("tiled_gather8_stored", Strategy::tiled_gather(8)),
        ("depth_mask8_stored", Strategy::depth_mask(8)),
    ] {
        let culler = &culler;
        g.bench_with_input(BenchmarkId::new(label, n), &n, |b, _| {
            b.iter_custom(|iters| cull_time(&ctx, culler, &gs, &depth, &strategy, &settings, iters))
        });
    }
    // Gather with other chunks of lights a workgroup (with stored tile masks, which have
    // chunks): smaller ones give more workgroups, larger ones less repeated set-up.
    for chunk in [64, 128, 512, 1024] {
        culler.gather_min_chunk = chunk;
        culler.gather_min_chunk_masked = chunk;
        let strategy = Strategy::tiled_gather(8);
        let culler = &culler;
        g.bench_with_input(
            BenchmarkId::new(format!("tiled_gather8_chunk{chunk}"), n),
            &n,
            |b, _| {
                b.iter_custom(|iters| {
                    cull_time(&ctx, culler, &gs, &depth, &strategy, &settings, iters)
                })
            },
        );
    }
    // Gather and 2.5D without tile masks (the fill tests every light again), and scatter
    // without them (its pairs and their radix sort).
    culler.gather_min_chunk = manylights_cull::MIN_CHUNK;
    culler.gather_min_chunk_masked = manylights_cull::MIN_CHUNK_MASKED;
    culler.mask_budget = 0;
    for (label, strategy) in [
        ("tiled_gather8_unmasked", Strategy::tiled_gather(8)),
        ("depth_mask8_unmasked", Strategy::depth_mask(8)),
        (
            "tiled_scatter8_unmasked",
            Strategy::TiledScatter { tile_size: 8 },
        ),
    ] {
        let culler = &culler;
        g.bench_with_input(BenchmarkId::new(label, n), &n, |b, _| {
            b.iter_custom(|iters| cull_time(&ctx, culler, &gs, &depth, &strategy, &settings, iters))
        });
    }
    g.finish();
}

fn buffer(ctx: &GpuContext, data: &[u32]) -> wgpu::Buffer {
    let b = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: (data.len() as u64 * 4).max(4),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    ctx.queue.write_buffer(&b, 0, bytemuck::cast_slice(data));
    b
}

/// Panics unless the pairs in (`k`, `v`) are `keys` (with values 0..n, their positions) sorted
/// stably: keys in order, equal keys in input order, every value once with its own key. With
/// replaced shaders (`MANYLIGHTS_SHADER_DIR`, an ablation) it prints the failure instead.
fn check_sorted(ctx: &GpuContext, name: &str, keys: &[u32], k: &wgpu::Buffer, v: &wgpu::Buffer) {
    let n = keys.len();
    match sorted_stably(ctx, keys, k, v) {
        Ok(()) => eprintln!("{name}/{n}: checked, sorted and stable"),
        Err(e) if std::env::var_os(manylights_gpu::shaders::SHADER_DIR_ENV).is_some() => {
            eprintln!("{name}/{n}: NOT SORTED with replaced shaders: {e}");
        }
        Err(e) => panic!("{name}/{n}: {e}"),
    }
}

fn sorted_stably(
    ctx: &GpuContext,
    keys: &[u32],
    k: &wgpu::Buffer,
    v: &wgpu::Buffer,
) -> Result<(), String> {
    let n = keys.len();
    let read = |b: &wgpu::Buffer| -> Vec<u32> {
        bytemuck::pod_collect_to_vec(&readback::read_buffer(ctx, b, 0, n as u64 * 4).unwrap())
    };
    let (sk, sv) = (read(k), read(v));
    let mut seen = vec![false; n];
    for i in 0..n {
        let j = sv[i] as usize;
        if j >= n || seen[j] {
            return Err(format!("value {j} at {i} out of range or repeated"));
        }
        seen[j] = true;
        if sk[i] != keys[j] {
            return Err(format!("key at {i} is not its value's key"));
        }
        if i > 0 && (sk[i - 1], sv[i - 1]) >= (sk[i], sv[i]) {
            return Err(format!("pairs {} and {i} out of order or unstable", i - 1));
        }
    }
    Ok(())
}

/// Sorts timed in one submission (each sort's passes fit a timer: the portable path's 32-bit
/// sort has fewer than 64 passes).
const SORT_BATCH: u64 = 16;

fn sort(c: &mut Criterion) {
    let ctx = gpu();
    let sizes: Vec<usize> = if let Ok(list) = std::env::var("MANYLIGHTS_BENCH_SORT_KEYS") {
        list.split(',')
            .map(|v| {
                v.trim().parse().unwrap_or_else(|_| {
                    panic!("MANYLIGHTS_BENCH_SORT_KEYS={list}: {v:?} is not a key count")
                })
            })
            .collect()
    } else if quick() {
        vec![1 << 16]
    } else {
        vec![1 << 20, 1 << 22, 1 << 24, 1 << 26]
    };
    // The default sort (onesweep where the adapter takes it) and the portable 4-bit one.
    let mut sorts = vec![("sort.radix", RadixSort::new(&ctx))];
    if let Ok(v) = std::env::var("MANYLIGHTS_SORT_MAX_SPIN") {
        let spin: u32 = v.trim().parse().unwrap_or_else(|_| {
            panic!("MANYLIGHTS_SORT_MAX_SPIN={v:?}: expected a poll count (0 to 4294967295)")
        });
        eprintln!("sort.radix: onesweep max_spin {spin} (MANYLIGHTS_SORT_MAX_SPIN)");
        sorts[0].1.max_spin = spin;
    }
    if sorts[0].1.path() != SortPath::Portable {
        sorts.push((
            "sort.radix_portable",
            RadixSort::with_scan_path(
                &ctx,
                if ctx.features.subgroups {
                    ScanPath::Subgroup
                } else {
                    ScanPath::Portable
                },
            )
            .expect("scan path"),
        ));
    }
    let mut lamp = lampshade::KeyValueSorter::new(&ctx.device, &ctx.queue);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
    for n in sizes {
        let keys: Vec<u32> = (0..n).map(|_| rng.random::<u32>()).collect();
        let vals: Vec<u32> = (0..n as u32).collect();
        let (k0, v0, k, v, kt, vt) = (
            buffer(&ctx, &keys),
            buffer(&ctx, &vals),
            buffer(&ctx, &keys),
            buffer(&ctx, &vals),
            buffer(&ctx, &vals),
            buffer(&ctx, &vals),
        );
        for (name, ours) in &sorts {
            // `count` sorts back to back in one submission, each from a fresh copy of the
            // input (copies outside the timed passes): the GPU stays busy, as in CUB's
            // measurement, instead of idling while the host uploads. Their passes' timings.
            let sorts_back_to_back = |count: u64| {
                let mut timer = GpuTimer::new(&ctx, MAX_QUERIES / 2);
                let mut enc = ctx.device.create_command_encoder(&Default::default());
                for _ in 0..count {
                    enc.copy_buffer_to_buffer(&k0, 0, &k, 0, None);
                    enc.copy_buffer_to_buffer(&v0, 0, &v, 0, None);
                    let at = ours
                        .encode(&ctx, &mut enc, &k, &v, &kt, &vt, n as u32, 32, &mut timer)
                        .unwrap();
                    assert_eq!(at, SortedIn::Input, "32 bits: an even number of passes");
                }
                timer.resolve(&mut enc);
                ctx.submit_and_wait(enc, "bench sort").unwrap();
                timer.read(&ctx).unwrap().expect("timestamps")
            };
            let mut g = c.benchmark_group(*name);
            configure(&mut g);
            g.throughput(Throughput::Elements(n as u64));
            g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
                b.iter_custom(|iters| {
                    let mut total = 0.0;
                    let mut left = iters;
                    while left > 0 {
                        let batch = left.min(SORT_BATCH);
                        left -= batch;
                        total += ms(&sorts_back_to_back(batch), |_| true);
                    }
                    Duration::from_secs_f64(total * 1e-3)
                })
            });
            g.finish();
            // Four more sorts; the last one checked, and its passes summed by label: where the
            // time goes at this size.
            let t = sorts_back_to_back(4);
            check_sorted(&ctx, name, &keys, &k, &v);
            let t = t[t.len() / 4 * 3..].to_vec();
            let mut labels: Vec<&str> = t.iter().map(|p| p.label.as_str()).collect();
            labels.sort_unstable();
            labels.dedup();
            for label in labels {
                let each: Vec<String> = t
                    .iter()
                    .filter(|p| p.label == label)
                    .map(|p| format!("{:.1}", p.ms * 1e3))
                    .collect();
                eprintln!(
                    "{name}/{n} passes: {label} {:.1} µs in all ({} µs)",
                    ms(&t, |l| l == label) * 1e3,
                    each.join(", ")
                );
            }
        }
        let pairs: Vec<u32> = keys.iter().zip(&vals).flat_map(|(&a, &b)| [a, b]).collect();
        let (inp, out) = (buffer(&ctx, &pairs), buffer(&ctx, &pairs));
        let mut g = c.benchmark_group("sort.lampshade");
        configure(&mut g);
        g.throughput(Throughput::Elements(n as u64));
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    // The sum of its passes' GPU times, as ours is measured.
                    total += pollster::block_on(lamp.profile_sort_gpu_to_gpu(&inp, &out, n as u32))
                        .expect("lampshade profile")
                        .dispatch_time;
                }
                total
            })
        });
        g.finish();
    }
}

fn shade(c: &mut Criterion) {
    let ctx = gpu();
    let ((w, h), n) = if quick() {
        ((160, 90), 256)
    } else {
        ((1920, 1080), 4096)
    };
    let scene = atrium_with(LightSpec {
        generator: LightGenerator::LightField,
        count: n,
        seed: 4,
        radius: RadiusRule::Fixed(2.0),
        intensity: 4.0,
        ..LightSpec::default()
    });
    let gs = GpuScene::upload(&ctx, &scene, &scene.camera, w, h).unwrap();
    let renderer = Renderer::new(&ctx, &gs);
    let settings = CullSettings::for_camera(&scene.camera);
    let strategy = Strategy::tiled_gather(16);
    for backend in Backend::ALL {
        let frame = |iters: u64, pick: &dyn Fn(&str) -> bool| {
            let mut total = 0.0;
            for _ in 0..iters {
                let out = renderer
                    .render(&ctx, &gs, backend, &strategy, &settings, (w, h))
                    .unwrap();
                total += ms(&out.timings.expect("timestamps"), pick);
            }
            Duration::from_secs_f64(total * 1e-3)
        };
        let mut g = c.benchmark_group(format!("frame.{}", backend.name()));
        configure(&mut g);
        g.bench_function(BenchmarkId::from_parameter(format!("{w}x{h}/{n}")), |b| {
            b.iter_custom(|iters| frame(iters, &|_| true))
        });
        g.finish();
        for pass in [
            "prepass.depth",
            "shade.gbuffer",
            "shade.forward",
            "shade.deferred",
            "shade.naive",
            "shade.visibility",
        ] {
            let used = match backend {
                Backend::Forward => ["prepass.depth", "shade.forward"].contains(&pass),
                Backend::Deferred | Backend::DeferredStoredPosition => {
                    ["shade.gbuffer", "shade.deferred"].contains(&pass)
                }
                Backend::NaiveForward => ["prepass.depth", "shade.naive"].contains(&pass),
                Backend::Visibility => ["shade.visibility", "shade.deferred"].contains(&pass),
            };
            if used {
                let mut g = c.benchmark_group(pass);
                configure(&mut g);
                g.bench_function(
                    BenchmarkId::new(backend.name(), format!("{w}x{h}/{n}")),
                    |b| b.iter_custom(|iters| frame(iters, &|l| l == pass)),
                );
                g.finish();
            }
        }
    }
}

criterion_group!(benches, cull_paper, cull, sort, shade);
criterion_main!(benches);
