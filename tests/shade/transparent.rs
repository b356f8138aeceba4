//! Transparent surfaces (glass panes: the atrium's gallery railings, a pane before the pillars'
//! far wall), blended back to front over the opaque surfaces as the reference does: by forward
//! and deferred (without and with MSAA) over lists culled over the lookup bounds, with no false
//! negative at any glass fragment, and by naive forward.

use manylights_cull::CullSettings;
use manylights_cull::metrics::from_gpu_counts;
use manylights_gpu::GpuScene;
use manylights_scene::procedural::{AtriumParams, PillarsParams, ProceduralScene};
use manylights_shade::accuracy::compare;
use manylights_shade::{Backend, ReferenceRenderer, Renderer};

use super::{check_timings, common, naive_against, scene, strategies, within_tolerance};

/// `name` with its glass panes and the tests' lights.
pub(crate) fn glass_scene(name: &str) -> manylights_scene::Scene {
    let mut s = scene(name);
    let glass = match name {
        "atrium" => ProceduralScene::Atrium(AtriumParams {
            glass: true,
            ..AtriumParams::default()
        }),
        _ => ProceduralScene::Pillars(PillarsParams {
            glass: true,
            ..PillarsParams::default()
        }),
    }
    .build()
    .unwrap();
    s.primitives = glass.primitives;
    s.materials = glass.materials;
    s
}

/// `backend` (deferred or visibility) with MSAA over `name` without its glass, against the
/// reference: its own error (its edges lit apart, tests/shade/msaa.rs).
fn deferred_msaa_error_without_glass(
    ctx: &manylights_gpu::GpuContext,
    name: &str,
    backend: Backend,
    (w, h): (u32, u32),
) -> manylights_shade::accuracy::ImageError {
    let s = scene(name);
    let gpu_scene = GpuScene::upload(ctx, &s, &s.camera, w, h).unwrap();
    let reference = ReferenceRenderer::with_samples(ctx, &gpu_scene, 4)
        .unwrap()
        .render(ctx, &gpu_scene, w, h)
        .unwrap()
        .color;
    let out = Renderer::with_samples(ctx, &gpu_scene, 4)
        .unwrap()
        .render(
            ctx,
            &gpu_scene,
            backend,
            &strategies()[0],
            &CullSettings::for_camera(&s.camera),
            (w, h),
        )
        .unwrap();
    compare(&out.color, &reference, 1.0)
}

/// Every strategy, forward, deferred and visibility, with one and 4 samples a pixel, over glass: the image
/// within forward's (deferred's) tolerance of the reference (forward with MSAA within its edges'
/// difference, tests/shade/msaa.rs), and the exact oracle, which checks
/// every visible transparent fragment as well as the opaque samples, finds no false negative:
/// culling over the lookup bounds reaches to the nearest glass. Deferred with MSAA draws the
/// glass into a layer of its own first, which its lighting composites over each sample as the
/// reference blends it: the glass adds no error to deferred's own (the same scene without it).
#[test]
fn forward_and_deferred_shade_glass_over_exact_lists() {
    let ctx = common::gpu();
    let (w, h) = (96, 54);
    for name in ["atrium", "pillars"] {
        let s = glass_scene(name);
        let own = [Backend::Deferred, Backend::Visibility]
            .map(|b| deferred_msaa_error_without_glass(&ctx, name, b, (w, h)));
        let frame = manylights_gpu::layout::GpuFrame::new(&s.camera, w, h, s.lights.len() as u32);
        for samples in [1, 4] {
            let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
            let reference = ReferenceRenderer::with_samples(&ctx, &gpu_scene, samples)
                .unwrap()
                .render(&ctx, &gpu_scene, w, h)
                .unwrap()
                .color;
            let renderer = Renderer::with_samples(&ctx, &gpu_scene, samples).unwrap();
            let settings = CullSettings::for_camera(&s.camera);
            for backend in [Backend::Forward, Backend::Deferred, Backend::Visibility] {
                let own = own[usize::from(backend == Backend::Visibility)];
                for strategy in strategies() {
                    let what = format!("{name} {samples}x {} {}", backend.name(), strategy.name());
                    let out = renderer
                        .render(&ctx, &gpu_scene, backend, &strategy, &settings, (w, h))
                        .unwrap_or_else(|e| panic!("{what}: {e}"));
                    check_timings(&out, &what, backend);
                    let e = compare(&out.color, &reference, 1.0);
                    if backend.lights_in_compute() && samples > 1 {
                        // Edges lit a sample at a time (tests/shade/msaa.rs).
                        // The glass adds none of its own (blended over each sample's average
                        // instead, it added 2.5e-3 on pillars).
                        assert!(
                            e.flip_mean < 0.06 && e.flip_mean <= own.flip_mean + 5e-4,
                            "{what}: {e:?}, without the glass {own:?}"
                        );
                    } else if samples > 1 {
                        // Forward lights an edge's fragments at their centroids, the reference
                        // each sample (tests/shade/msaa.rs; measured 0.041 in the atrium).
                        assert!(e.flip_mean < 0.08, "{what}: {e:?}");
                    } else {
                        assert!(within_tolerance(&e, backend), "{what}: {e:?}");
                    }
                    let t = out.timings.as_ref().unwrap();
                    for pass in [
                        "prepass.transparent_near",
                        "prepass.depth_bounds",
                        "shade.forward_transparent",
                    ] {
                        assert!(
                            t.iter().any(|p| p.label == pass),
                            "{what}: no {pass} in {t:?}"
                        );
                    }
                    let lists = out.lists.as_ref().unwrap();
                    let counts = renderer
                        .culler
                        .exact_counts(
                            &ctx,
                            &gpu_scene,
                            &out.depth,
                            lists,
                            frame.clip_from_world.inverse(),
                            1,
                        )
                        .unwrap();
                    let m = from_gpu_counts(&counts, &lists.bin_lengths(&ctx).unwrap());
                    assert_eq!(m.false_negatives, 0, "{what}: false negatives");
                    let pixels = counts.iter().filter(|c| c[3] > 0).count() as u64;
                    let samples_covered: u64 = counts.iter().map(|c| u64::from(c[3])).sum();
                    assert!(
                        samples_covered > pixels * u64::from(samples),
                        "{what}: {samples_covered} points over {pixels} pixels: no glass fragment counted"
                    );
                }
            }
        }
    }
}

#[test]
fn naive_forward_blends_glass_as_the_reference_does() {
    let ctx = common::gpu();
    let (w, h) = (96, 54);
    for name in ["atrium", "pillars"] {
        let plain = scene(name);
        let s = glass_scene(name);
        assert!(s.materials.iter().any(|m| m.is_transparent()));
        for samples in [1, 4] {
            let what = format!("{name} with glass, {samples} samples");
            let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
            assert!(gpu_scene.has_transparent(), "{what}");
            let reference = ReferenceRenderer::with_samples(&ctx, &gpu_scene, samples)
                .unwrap()
                .render(&ctx, &gpu_scene, w, h)
                .unwrap();
            let t = reference.timings.as_ref().unwrap();
            assert!(
                t.iter().any(|p| p.label == "shade.reference_transparent"),
                "{t:?}"
            );
            let renderer = Renderer::with_samples(&ctx, &gpu_scene, samples).unwrap();
            let settings = CullSettings::for_camera(&s.camera);
            let (_, e) = naive_against(
                &ctx,
                &renderer,
                &gpu_scene,
                &settings,
                (w, h),
                &reference.color,
            );
            // With MSAA naive forward lights an edge's fragments at their centroids, the
            // reference each sample (tests/shade/msaa.rs).
            if samples > 1 {
                assert!(e.flip_mean < 0.08, "{what}: {e:?}");
            } else {
                assert!(within_tolerance(&e, Backend::Forward), "{what}: {e:?}");
            }
            // The glass shows: pixels differ from the scene without it.
            let plain_scene = GpuScene::upload(&ctx, &plain, &plain.camera, w, h).unwrap();
            let without = ReferenceRenderer::with_samples(&ctx, &plain_scene, samples)
                .unwrap()
                .render(&ctx, &plain_scene, w, h)
                .unwrap();
            let changed = without
                .color
                .data
                .iter()
                .zip(&reference.color.data)
                .filter(|(a, b)| a != b)
                .count();
            assert!(changed > 20, "{what}: the glass changed {changed} pixels");
        }
    }
}
