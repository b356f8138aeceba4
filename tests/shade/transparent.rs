//! Transparent surfaces (glass panes: the atrium's gallery railings, a pane before the pillars'
//! far wall): naive forward blends them back to front over the opaque surfaces as the reference
//! does, without and with MSAA; the backends over lists refuse them until culling covers
//! transparent surfaces, rather than render them with lists that may miss their lights.

use manylights_cull::CullSettings;
use manylights_gpu::GpuScene;
use manylights_scene::procedural::{AtriumParams, PillarsParams, ProceduralScene};
use manylights_shade::accuracy::compare;
use manylights_shade::{Backend, ReferenceRenderer, Renderer};

use super::{common, scene, strategies, within_tolerance};

/// `name` with its glass panes and the tests' lights.
fn glass_scene(name: &str) -> manylights_scene::Scene {
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
            let naive = renderer
                .render(
                    &ctx,
                    &gpu_scene,
                    Backend::NaiveForward,
                    &strategies()[0],
                    &settings,
                    (w, h),
                )
                .unwrap();
            let e = compare(&naive.color, &reference.color, 1.0);
            assert!(within_tolerance(&e, Backend::Forward), "{what}: {e:?}");
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
            // Forward and deferred refuse it, naming why.
            for backend in [Backend::Forward, Backend::Deferred] {
                let e = renderer
                    .render(
                        &ctx,
                        &gpu_scene,
                        backend,
                        &strategies()[0],
                        &settings,
                        (w, h),
                    )
                    .err()
                    .unwrap_or_else(|| panic!("{what}: {} rendered glass", backend.name()))
                    .to_string();
                assert!(e.contains("transparent surfaces"), "{e}");
            }
        }
    }
}
