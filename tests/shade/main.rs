//! The shading backends over every culling strategy, against the brute-force reference, on a
//! real Vulkan device (lavapipe in CI).
//!
//! Tolerances, with mean FLIP < 1e-3 for every backend:
//! - forward and naive forward: maximum absolute error <= 1e-4 of the reference's peak. They
//!   evaluate the same f32 expressions at the same interpolated points as the reference, summing
//!   fewer (exactly zero) terms in another order (measured on lavapipe: 2e-8 of the peak).
//! - deferred_stored_position: the same bound; its G-buffer stores the interpolated position.
//! - deferred: <= 5e-3 of the peak. It rebuilds the surface point from the G-buffer's view depth
//!   and the pixel centre, which differs from the interpolated world position the reference
//!   shades: by a few ulps of the world coordinates on lavapipe (measured: up to 7.5e-5 of the
//!   peak), and by the rasteriser's own interpolation error on NVIDIA (measured on an H200,
//!   driver 580.159.04: 2.6e-3 of the peak at 64 x 48, where a light 0.1 m from a
//!   wall makes the peak; mean FLIP 0.001). Next to a light the inverse-square falloff amplifies
//!   position differences, so this is the real cost of rebuilding positions; the stored-position
//!   variant shows it is nothing else. The measured maxima are printed.

mod cluster_group;
#[path = "../common/mod.rs"]
mod common;
mod hdr_f16;
mod materials;
mod msaa;
mod point_lights;
mod shadows;
mod shadows_stochastic;
mod steady;
mod transparent;
mod visibility;
mod walked;

use manylights_cull::{CullSettings, Slicing, Strategy};
use manylights_gpu::timing::{Category, GpuTimer, PassKind, PassTiming};
use manylights_gpu::{GpuContext, GpuScene};
use manylights_scene::procedural::ProceduralScene;
use manylights_scene::{LightGenerator, LightSpec, RadiusRule, Scene};
use manylights_shade::accuracy::{ImageError, compare};
use manylights_shade::frame_plan::{Resource, Role};
use manylights_shade::{
    Backend, HdrImage, ReferenceRenderer, Renderer, ShadeOutput, VisibilityPass,
};

const CULLED: [Backend; 4] = [
    Backend::Forward,
    Backend::Deferred,
    Backend::DeferredStoredPosition,
    Backend::Visibility,
];

fn scene(name: &str) -> Scene {
    let mut s = ProceduralScene::from_name(name).unwrap().build().unwrap();
    let r = s.light_bounds.extent().max_element() / 8.0;
    s.lights = LightSpec {
        generator: LightGenerator::LightField,
        count: 160,
        seed: 3,
        radius: RadiusRule::Fixed(r),
        intensity: r * r * 0.5,
        spot_fraction: 0.25,
        spot_outer_deg: 40.0,
        ..LightSpec::default()
    }
    .generate(&s)
    .unwrap();
    s
}

fn strategies() -> [Strategy; 6] {
    [
        Strategy::tiled_gather(16),
        Strategy::TiledScatter { tile_size: 8 },
        Strategy::depth_mask(16),
        Strategy::Clustered {
            tile_size: 16,
            slices: 16,
            slicing: Slicing::Exponential,
            skip_empty: true,
            ordered: true,
            cells: false,
        },
        // Deferred lighting walks z-binning's masks a workgroup at a time where its 8 x 8 pixels
        // lie in one tile, and a pixel at a time otherwise: both.
        Strategy::ZBin {
            tile_size: 8,
            bins: 64,
            slicing: Slicing::Exponential,
        },
        Strategy::ZBin {
            tile_size: 12,
            bins: 64,
            slicing: Slicing::Linear,
        },
    ]
}

fn tolerance(backend: Backend) -> f64 {
    if matches!(backend, Backend::Deferred | Backend::Visibility) {
        5e-3
    } else {
        1e-4
    }
}

/// Naive forward's frame of `gpu_scene` by `renderer` at `w` x `h` (the strategy unused), and
/// its error against `reference`.
fn naive_against(
    ctx: &GpuContext,
    renderer: &Renderer,
    gpu_scene: &GpuScene,
    settings: &CullSettings,
    (w, h): (u32, u32),
    reference: &HdrImage,
) -> (ShadeOutput, ImageError) {
    let naive = renderer
        .render(
            ctx,
            gpu_scene,
            Backend::NaiveForward,
            &strategies()[0],
            settings,
            (w, h),
        )
        .unwrap();
    let e = compare(&naive.color, reference, 1.0);
    (naive, e)
}

fn within_tolerance(e: &ImageError, backend: Backend) -> bool {
    e.max_abs_error <= tolerance(backend) * e.peak && e.flip_mean < 1e-3
}

/// `out`'s frame shaded again by `pass` after culling it once more with `strategy` (as the
/// benches drive `Renderer::shade_pass`): the image read back.
fn shade_again(
    ctx: &GpuContext,
    renderer: &Renderer,
    gpu_scene: &GpuScene,
    out: &ShadeOutput,
    strategy: &Strategy,
    settings: &CullSettings,
    pass: &mut impl manylights_cull::ListPass,
) -> HdrImage {
    renderer
        .culler
        .run_repeated_with(
            ctx,
            gpu_scene,
            &out.depth,
            strategy,
            settings,
            out.lists.as_ref().unwrap(),
            1,
            &mut GpuTimer::new(ctx, 64),
            pass,
        )
        .unwrap();
    out.read_color(ctx).unwrap()
}

fn check_timings(out: &ShadeOutput, what: &str, backend: Backend) {
    let t = out.timings.as_ref().unwrap_or_else(|| {
        panic!("{what}: no timings (lavapipe and NVIDIA have timestamp queries)")
    });
    let raster: &[&str] = match backend {
        Backend::Forward => &["prepass.depth", "shade.forward"],
        Backend::Deferred | Backend::DeferredStoredPosition => &["shade.gbuffer"],
        Backend::Visibility if out.computed_visibility() => &[],
        Backend::Visibility => &["shade.visibility"],
        Backend::NaiveForward => &["prepass.depth", "shade.naive"],
    };
    if out.computed_visibility() {
        for name in ["triangles", "scan", "blocks", "resolve"] {
            let name = format!("shade.visibility_compute.{name}");
            assert!(
                t.iter()
                    .any(|p| p.label == name && p.kind == PassKind::Compute),
                "{what}: no compute pass {name} in {t:?}"
            );
        }
    }
    for name in raster {
        assert!(
            t.iter()
                .any(|p| p.label == *name && p.kind == PassKind::Raster),
            "{what}: no raster pass {name} in {t:?}"
        );
    }
    if backend.lights_in_compute() {
        assert!(
            t.iter()
                .any(|p| p.label == "shade.deferred" && p.kind == PassKind::Compute),
            "{what}: no compute lighting pass"
        );
    }
    if backend != Backend::NaiveForward {
        assert!(
            t.iter()
                .any(|p| p.label.starts_with("cull.") && p.kind == PassKind::Compute),
            "{what}: no culling pass"
        );
    }
    for p in t {
        assert!(
            p.ms > 0.0 && p.ms.is_finite(),
            "{what}: pass {} took {} ms",
            p.label,
            p.ms
        );
    }
    check_plan(out, t, what);
}

/// The frame's passes as its plan declares them: every resource a pass reads is an input or
/// written by an earlier pass; the passes are timed in their entry's category, the geometry's
/// before culling's before the shading's; the checks' passes are not timed; a culling run
/// between geometry and shading unless naive forward.
fn check_plan(out: &ShadeOutput, t: &[PassTiming], what: &str) {
    let mut written: Vec<Resource> = Resource::INPUTS.to_vec();
    for p in &out.passes {
        for r in &p.reads {
            assert!(
                written.contains(r),
                "{what}: {} reads {r:?}, which no earlier pass writes: {:?}",
                p.name,
                out.passes
            );
        }
        written.extend(&p.writes);
    }
    let culls = out.passes.iter().filter(|p| p.name == "cull").count();
    assert_eq!(
        culls,
        usize::from(out.backend != Backend::NaiveForward),
        "{what}: {:?}",
        out.passes
    );
    let phase = |c: Category| match c {
        Category::LightUpdate => 0,
        Category::Prepass => 1,
        Category::Cull => 2,
        Category::Shade => 3,
    };
    assert!(
        t.windows(2)
            .all(|w| phase(w[0].category) <= phase(w[1].category)),
        "{what}: passes out of their categories' order: {t:?}"
    );
    for timing in t {
        let culling = ["cull.", "scan.", "sort."]
            .iter()
            .any(|p| timing.label.starts_with(p));
        match out.passes.iter().find(|p| p.name == timing.label) {
            Some(p) => {
                assert_eq!(p.role, Role::Frame, "{what}: {} is timed", p.name);
                assert_eq!(timing.category, p.category, "{what}: {}", p.name);
            }
            None if culling => assert_eq!(timing.category, Category::Cull, "{what}: {timing:?}"),
            // The passes of a step named by its main pass (the glass's bounds).
            None => assert_eq!(timing.category, Category::Prepass, "{what}: {timing:?}"),
        }
    }
    if out.computed_visibility() {
        let depth = out
            .passes
            .iter()
            .find(|p| p.name == "shade.visibility_depth");
        assert_eq!(depth.map(|p| p.role), Some(Role::Checks), "{what}");
    }
}

/// Every strategy x backend (and naive forward) renders `atrium` and `pillars` within the
/// tolerance of the reference, at 64 x 48 (a multiple of every tile size) and 70 x 45 (of none);
/// forward and deferred agree within it; every pass is timed.
#[test]
fn every_strategy_and_backend_matches_the_reference() {
    let ctx = common::gpu();
    let mut worst = [0.0f64; 5];
    // The visibility backend twice: the compute rasteriser (its default) and the raster pass.
    let variants = CULLED
        .into_iter()
        .map(|b| (b, VisibilityPass::Compute))
        .chain([(Backend::Visibility, VisibilityPass::Raster)]);
    for name in ["atrium", "pillars"] {
        let s = scene(name);
        for (w, h) in [(64, 48), (70, 45)] {
            let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
            let reference = ReferenceRenderer::new(&ctx, &gpu_scene)
                .render(&ctx, &gpu_scene, w, h)
                .unwrap()
                .color;
            assert!(reference.peak() > 0.0, "{name}: the reference is black");
            let mut renderer = Renderer::new(&ctx, &gpu_scene);
            let settings = CullSettings::for_camera(&s.camera);
            let (naive, e) =
                naive_against(&ctx, &renderer, &gpu_scene, &settings, (w, h), &reference);
            assert!(
                within_tolerance(&e, Backend::NaiveForward),
                "{name} {w}x{h} naive: {e:?}"
            );
            check_timings(&naive, &format!("{name} naive"), Backend::NaiveForward);
            for strategy in strategies() {
                let mut images = Vec::new();
                for (k, (backend, pass)) in variants.clone().enumerate() {
                    renderer.visibility_pass = pass;
                    let what = format!(
                        "{name} {w}x{h} {} {} {}",
                        strategy.name(),
                        backend.name(),
                        pass.name()
                    );
                    let out = renderer
                        .render(&ctx, &gpu_scene, backend, &strategy, &settings, (w, h))
                        .unwrap();
                    let e = compare(&out.color, &reference, 1.0);
                    worst[k] = worst[k].max(e.max_abs_error / e.peak);
                    assert!(within_tolerance(&e, backend), "{what}: {e:?}");
                    assert_eq!(out.color.non_finite_count(), 0, "{what}: NaN or Inf");
                    assert_eq!(out.lists.as_ref().unwrap().dropped, 0, "{what}");
                    check_timings(&out, &what, backend);
                    assert_eq!(
                        out.computed_visibility(),
                        backend == Backend::Visibility && pass == VisibilityPass::Compute,
                        "{what}: lavapipe has 64-bit atomic max"
                    );
                    let per_pixel = match backend {
                        Backend::Deferred => 24,
                        Backend::DeferredStoredPosition => 40,
                        // A 64-bit key, an id and a depth.
                        Backend::Visibility if out.computed_visibility() => 16,
                        Backend::Visibility => 8,
                        _ => 0,
                    };
                    assert_eq!(
                        out.gbuffer_bytes,
                        u64::from(w * h) * per_pixel,
                        "{what}: G-buffer bytes"
                    );
                    images.push(out.color);
                }
                for (k, backend) in [
                    (1, Backend::Deferred),
                    (2, Backend::DeferredStoredPosition),
                    (3, Backend::Visibility),
                    (4, Backend::Visibility),
                ] {
                    let e = compare(&images[k], &images[0], 1.0);
                    assert!(
                        within_tolerance(&e, backend),
                        "{name} {w}x{h} {}: {} vs forward {e:?}",
                        strategy.name(),
                        backend.name()
                    );
                }
            }
        }
    }
    println!(
        "worst max abs error of the peak: forward {:.2e}, deferred {:.2e}, deferred_stored_position {:.2e}, visibility {:.2e} (raster pass {:.2e})",
        worst[0], worst[1], worst[2], worst[3], worst[4]
    );
}

/// A deliberate capacity drops lights; the results say how many, and the loss is visible as
/// image error.
#[test]
fn capacity_cap_reports_dropped_lights_and_error() {
    let ctx = common::gpu();
    let s = scene("atrium");
    let (w, h) = (64, 48);
    let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
    let reference = ReferenceRenderer::new(&ctx, &gpu_scene)
        .render(&ctx, &gpu_scene, w, h)
        .unwrap()
        .color;
    let renderer = Renderer::new(&ctx, &gpu_scene);
    let settings = CullSettings {
        capacity: Some(2),
        ..CullSettings::for_camera(&s.camera)
    };
    for backend in CULLED {
        let out = renderer
            .render(
                &ctx,
                &gpu_scene,
                backend,
                &Strategy::tiled_gather(16),
                &settings,
                (w, h),
            )
            .unwrap();
        let dropped = out.lists.as_ref().unwrap().dropped;
        let e = compare(&out.color, &reference, 1.0);
        assert!(
            dropped > 0,
            "{}: a capacity of 2 must drop lights here",
            backend.name()
        );
        assert!(
            e.max_abs_error > 1e-2 * e.peak,
            "{}: {dropped} dropped lights but no visible error: {e:?}",
            backend.name()
        );
    }
}

/// The infinite-range reference differs from the windowed one (the cut-off has a cost), and
/// only by adding light.
#[test]
fn infinite_range_reference_measures_the_cutoff() {
    let ctx = common::gpu();
    let s = scene("pillars");
    let (w, h) = (48, 32);
    let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
    let r = ReferenceRenderer::new(&ctx, &gpu_scene);
    let windowed = r.render(&ctx, &gpu_scene, w, h).unwrap().color;
    let infinite = r
        .render_infinite(&ctx, &gpu_scene, &s.camera, w, h)
        .unwrap()
        .color;
    let again = r.render(&ctx, &gpu_scene, w, h).unwrap().color;
    assert_eq!(
        windowed.data, again.data,
        "the frame flags must be restored"
    );
    let e = compare(&windowed, &infinite, 1.0);
    assert!(e.max_abs_error > 0.0 && e.psnr_db.is_finite(), "{e:?}");
    for (a, b) in windowed.data.iter().zip(&infinite.data) {
        for c in 0..3 {
            assert!(
                b[c] >= a[c] * (1.0 - 1e-5),
                "infinite range must not darken a pixel: {a:?} vs {b:?}"
            );
        }
    }
}

/// Every strategy's lists come out in light order (gather and 2.5D fill in order, scatter sorts
/// stably, clusters sort each list after their atomic fill): the same lists, order included,
/// and bit-identical images on every run. (Where each list sits in the index buffer may
/// differ: gather with tile masks places a tile's list with an atomic add.) The small, mid and big cases' clusters hold at most
/// 512, 1,000 and over 2,048 lights, so that, on the clusters' per-light passes (the tile path,
/// which these light counts would take, fills its lists in order), `cull.clustered.order_short`
/// and `cull.clustered.order_bits` (the bitmap's rank sort) run, and, with
/// `Culler::cluster_order_bits` off, `order_short`'s network alone and both paths of
/// `cull.clustered.order` (workgroup memory and in place), and gather's
/// tiles take their coarse tile's candidates in more than one chunk of 2,048.
#[test]
fn ordered_strategies_render_bit_identical_frames() {
    let ctx = common::gpu();
    let (w, h) = (70, 45);
    let small = scene("atrium");
    // 2,100 lights that each cover the whole view: every cluster's list is longer than the
    // order pass's workgroup memory.
    let covering = |count: u32| {
        let mut s = scene("atrium");
        s.lights = LightSpec {
            generator: LightGenerator::LightField,
            count,
            seed: 4,
            radius: RadiusRule::Fixed(s.light_bounds.extent().length() * 2.0),
            intensity: 0.05,
            spot_fraction: 0.0,
            spot_outer_deg: 40.0,
            ..LightSpec::default()
        }
        .generate(&s)
        .unwrap();
        s
    };
    let big = covering(2100);
    // Lists of 1,000: longer than the short lists' pass takes, within workgroup memory.
    let mid = covering(1000);
    let clusters = Strategy::Clustered {
        tile_size: 16,
        slices: 8,
        slicing: Slicing::Exponential,
        skip_empty: false,
        ordered: true,
        cells: false,
    };
    let zbin = Strategy::ZBin {
        tile_size: 8,
        bins: 16,
        slicing: Slicing::Linear,
    };
    // The same clusters on the per-light passes and their order passes (the tile path is off
    // for this strategy below: 12 slices).
    let per_light = Strategy::Clustered {
        tile_size: 16,
        slices: 12,
        slicing: Slicing::Exponential,
        skip_empty: false,
        ordered: true,
        cells: false,
    };
    let cases = [
        (&small, zbin),
        (&big, zbin),
        (&small, Strategy::tiled_gather(8)),
        (&small, Strategy::depth_mask(16)),
        (&small, Strategy::TiledScatter { tile_size: 8 }),
        (&small, clusters),
        (&mid, clusters),
        (&big, clusters),
        (&small, per_light),
        (&mid, per_light),
        (&big, per_light),
        // Gather's coarse level hands each tile its candidates 2,048 at a time.
        (
            &big,
            Strategy::TiledGather {
                tile_size: 8,
                coarse: 8,
            },
        ),
    ];
    // The per-light passes' order passes both ways: by the bitmap of light indices (these runs
    // have at most 65,536 lights) and by the bitonic network.
    let runs = cases.into_iter().flat_map(|(s, strategy)| {
        let bits: &[bool] = if strategy == per_light {
            &[true, false]
        } else {
            &[true]
        };
        bits.iter().map(move |&bits| (s, strategy, bits))
    });
    // One scene and renderer a light set (building every pipeline is most of a case's time
    // on lavapipe), its culler set for each case.
    let scenes = [&small, &mid, &big];
    let mut uploaded: Vec<_> = scenes
        .iter()
        .map(|s| {
            let gpu_scene = GpuScene::upload(&ctx, s, &s.camera, w, h).unwrap();
            let renderer = Renderer::new(&ctx, &gpu_scene);
            (gpu_scene, renderer)
        })
        .collect();
    for (s, strategy, order_bits) in runs {
        let at = scenes.iter().position(|&x| std::ptr::eq(x, s)).unwrap();
        let (gpu_scene, renderer) = &mut uploaded[at];
        renderer.culler.cluster_tiles_max_lights = if strategy == per_light {
            0
        } else {
            manylights_cull::CLUSTER_TILES_MAX_LIGHTS
        };
        renderer.culler.cluster_order_bits = order_bits;
        let settings = CullSettings::for_camera(&s.camera);
        let mut longest = 0;
        for backend in [Backend::Forward, Backend::Deferred] {
            let runs: Vec<_> = (0..2)
                .map(|_| {
                    let out = renderer
                        .render(&ctx, gpu_scene, backend, &strategy, &settings, (w, h))
                        .unwrap();
                    let lists = out.lists.as_ref().unwrap().read(&ctx).unwrap();
                    (out.color.data, lists)
                })
                .collect();
            let (a, b) = (&runs[0].1, &runs[1].1);
            assert!(
                a.ranges.len() == b.ranges.len()
                    && (0..a.ranges.len()).all(|bin| a.list(bin) == b.list(bin)),
                "{} {}: lists differ between runs (order bits: {})",
                strategy.name(),
                backend.name(),
                order_bits
            );
            assert!(
                runs[0].0 == runs[1].0,
                "{} {}: images differ between runs (order bits: {})",
                strategy.name(),
                backend.name(),
                order_bits
            );
            for b in 0..runs[0].1.ranges.len() {
                let l = runs[0].1.list(b);
                longest = longest.max(l.len());
                // (Z-binning's cells of bins outside a tile's depth bounds, which no pixel reads,
                // hold only the part of the tile's mask it computes.)
                let per_tile =
                    !matches!(strategy, Strategy::Clustered { .. } | Strategy::ZBin { .. });
                if std::ptr::eq(s, &big) && per_tile {
                    // Every light covers the whole view: a tile with geometry keeps them all.
                    assert!(
                        l.is_empty() || l.len() == big.lights.len(),
                        "{} bin {b}: {} of {} lights",
                        strategy.name(),
                        l.len(),
                        big.lights.len()
                    );
                }
                // (Z-binning's lists are in depth order, the same on every run, as checked.)
                assert!(
                    matches!(strategy, Strategy::ZBin { .. }) || l.windows(2).all(|p| p[0] < p[1]),
                    "{} bin {b}: not in light order",
                    strategy.name()
                );
            }
        }
        if std::ptr::eq(s, &big) {
            assert!(
                longest > 2048,
                "the big case must exceed workgroup memory: {longest}"
            );
        }
    }
}

/// A lost device is a clear error, not a panic: after `Device::destroy`, rendering (culling,
/// shading, readback) returns an error that says the device was lost.
#[test]
fn lost_device_is_an_error_not_a_panic() {
    let ctx = common::gpu();
    let s = scene("atrium");
    let (w, h) = (32, 18);
    let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
    let renderer = Renderer::new(&ctx, &gpu_scene);
    let settings = CullSettings::for_camera(&s.camera);
    let strategy = Strategy::tiled_gather(16);
    renderer
        .render(
            &ctx,
            &gpu_scene,
            Backend::Forward,
            &strategy,
            &settings,
            (w, h),
        )
        .expect("renders before the loss");
    ctx.device.destroy();
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        renderer.render(
            &ctx,
            &gpu_scene,
            Backend::Forward,
            &strategy,
            &settings,
            (w, h),
        )
    }));
    let err = match result {
        Err(_) => panic!("rendering on a lost device panicked"),
        Ok(Ok(_)) => panic!("rendering on a lost device succeeded"),
        Ok(Err(e)) => e.to_string(),
    };
    assert!(err.to_lowercase().contains("lost"), "{err}");
}

/// Culling back to back with the shading pass after each run (`Culler::run_repeated_with`, what
/// `gpu_ms_cull_shade` times): every run's passes are timed, the culling passes and then the
/// shading pass, and the last frame shaded equals the single frame, for every strategy and
/// forward and deferred shading.
#[test]
fn culling_and_shading_back_to_back_equal_a_single_frame() {
    let ctx = common::gpu();
    let (w, h) = (64, 48);
    let s = scene("atrium");
    let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
    let renderer = Renderer::new(&ctx, &gpu_scene);
    let settings = CullSettings::for_camera(&s.camera);
    for strategy in strategies() {
        for backend in [Backend::Forward, Backend::Deferred] {
            let what = format!("{} {}", strategy.name(), backend.name());
            let out = renderer
                .render(&ctx, &gpu_scene, backend, &strategy, &settings, (w, h))
                .unwrap();
            let lists = out.lists.as_ref().unwrap();
            let mut pass = renderer.shade_pass(&ctx, &gpu_scene, &out).unwrap();
            let mut timer = GpuTimer::new(&ctx, 256);
            let runs = 3;
            renderer
                .culler
                .run_repeated_with(
                    &ctx, &gpu_scene, &out.depth, &strategy, &settings, lists, runs, &mut timer,
                    &mut pass,
                )
                .unwrap();
            let shade = if backend == Backend::Forward {
                "shade.forward"
            } else {
                "shade.deferred"
            };
            if let Some(t) = timer.read(&ctx).unwrap() {
                let shaded: Vec<usize> = (0..t.len()).filter(|&i| t[i].label == shade).collect();
                assert_eq!(shaded.len(), runs as usize, "{what}: a shading pass a run");
                let per_run = t.len() / runs as usize;
                assert_eq!(t.len(), per_run * runs as usize, "{what}: runs alike");
                for (k, &i) in shaded.iter().enumerate() {
                    assert_eq!(i, (k + 1) * per_run - 1, "{what}: shading ends each run");
                    assert!(
                        t[k * per_run..i]
                            .iter()
                            .all(|p| p.label.starts_with("cull.")
                                || p.label.starts_with("scan.")
                                || p.label.starts_with("sort.")),
                        "{what}: culling before shading: {t:?}"
                    );
                }
            }
            let again = out.read_color(&ctx).unwrap();
            assert!(
                again.data == out.color.data,
                "{what}: the frame shaded after back-to-back culling differs from the single frame"
            );
        }
    }
}
