//! The lit image in 16-bit floats (`HdrFormat::F16`): every backend, on each form of lists
//! deferred lighting reads (a workgroup's tile list, a cluster's lists a workgroup at a time, a
//! pixel's bin list) and with MSAA over glass, gives the 32-bit image rounded to half precision:
//! each channel within 2^-10 of its value (one rounding, to nearest or towards zero, both of
//! which Vulkan allows: lavapipe's render targets measured up to 2 of round-to-nearest's 2^-11),
//! plus half's smallest step near zero. Where glass is blended into it and samples are resolved,
//! each blend and the resolve round, each in proportion to what it blends: there within 2^-9
//! of the image's peak (measured on lavapipe: 8.0e-4, 2^-10.3).

use manylights_cull::layout::CLUSTER_GROUP_MIN_LIGHTS;
use manylights_cull::{CullSettings, Slicing, Strategy};
use manylights_gpu::GpuScene;
use manylights_shade::{Backend, HdrFormat, HdrImage, Renderer};

use super::cluster_group::atrium_lights;
use super::transparent::glass_scene;
use super::{CULLED, common, scene};

/// The largest error of `half` against `full`, each channel's in units of its bound
/// (`relative` of the 32-bit value, at least half's subnormal step): at most 1 where they agree.
fn worst(full: &HdrImage, half: &HdrImage, relative: f32) -> f32 {
    assert_eq!(full.data.len(), half.data.len());
    full.data
        .iter()
        .zip(&half.data)
        .flat_map(|(p, q)| (0..4).map(move |c| (p[c], q[c])))
        .map(|(a, b)| {
            assert!(
                b.is_finite(),
                "a non-finite 16-bit channel where 32 bits have {a}"
            );
            (a - b).abs() / (a.abs() * relative).max(6.0e-8)
        })
        .fold(0.0f32, f32::max)
}

#[test]
fn the_16_bit_image_is_the_32_bit_image_rounded() {
    let ctx = common::gpu();
    let size = (72, 48);
    // The tests' lights (spots among them: the general shading path), and point lights past
    // CLUSTER_GROUP_MIN_LIGHTS (the POINT_LIGHTS pipelines; clusters take their workgroup path).
    for s in [
        scene("atrium"),
        atrium_lights(CLUSTER_GROUP_MIN_LIGHTS + 1, 0.05),
    ] {
        let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, size.0, size.1).unwrap();
        let full = Renderer::new(&ctx, &gpu_scene);
        let half = Renderer::with_format(&ctx, &gpu_scene, 1, HdrFormat::F16).unwrap();
        assert_eq!(half.hdr_format(), HdrFormat::F16);
        let settings = CullSettings::for_camera(&s.camera);
        // Gather in 8-pixel tiles (the tile path), clusters in 16-pixel tiles, and 12-pixel
        // tiles (a pixel's own list).
        let clusters = Strategy::Clustered {
            tile_size: 16,
            slices: 16,
            slicing: Slicing::Exponential,
            skip_empty: false,
            ordered: true,
            cells: false,
        };
        for strategy in [
            Strategy::tiled_gather(8),
            clusters,
            Strategy::tiled_gather(12),
        ] {
            for backend in CULLED.into_iter().chain([Backend::NaiveForward]) {
                let [a, b] = [&full, &half].map(|r| {
                    r.render(&ctx, &gpu_scene, backend, &strategy, &settings, size)
                        .unwrap()
                });
                let w = worst(&a.color, &b.color, 2f32.powi(-10));
                let what = format!(
                    "{} lights, {} {}",
                    s.lights.len(),
                    backend.name(),
                    strategy.name()
                );
                println!("{what}: worst {w:.3} of the bound");
                assert!(w <= 1.0, "{what}: {w} of the bound");
            }
        }
    }
}

#[test]
fn the_16_bit_image_with_msaa_over_glass() {
    let ctx = common::gpu();
    let size = (64, 40);
    let s = glass_scene("atrium");
    let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, size.0, size.1).unwrap();
    let full = Renderer::with_samples(&ctx, &gpu_scene, 4).unwrap();
    let half = Renderer::with_format(&ctx, &gpu_scene, 4, HdrFormat::F16).unwrap();
    let settings = CullSettings::for_camera(&s.camera);
    let strategy = Strategy::tiled_gather(16);
    for backend in [Backend::Forward, Backend::Deferred, Backend::NaiveForward] {
        let [a, b] = [&full, &half].map(|r| {
            r.render(&ctx, &gpu_scene, backend, &strategy, &settings, size)
                .unwrap()
        });
        assert!(b.msaa_target_bytes < a.msaa_target_bytes || backend == Backend::Deferred);
        let peak = a.color.peak();
        let w = a
            .color
            .data
            .iter()
            .zip(&b.color.data)
            .flat_map(|(p, q)| (0..4).map(move |c| (p[c], q[c])))
            .map(|(x, y)| {
                assert!(
                    y.is_finite(),
                    "a non-finite 16-bit channel where 32 bits have {x}"
                );
                (x - y).abs() / peak
            })
            .fold(0.0f32, f32::max);
        println!(
            "{} with MSAA over glass: worst {w:e} of the peak",
            backend.name()
        );
        assert!(w <= 2f32.powi(-9), "{}: {w} of the peak", backend.name());
    }
}
