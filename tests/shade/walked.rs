//! The lights shading walks (`GpuScene::count_lights_walked`, the lab's
//! `lights_walked_per_pixel_mean`): a pixel's loop over its list walks every light of it, so the
//! count is the lists' own lengths summed over the pixels; over the clusters' lists a workgroup
//! at a time (`shade_parts_list`) a pixel walks only the lights whose sphere meets the box of the
//! surface points of its 8 x 8 block's pixels in its slice, which a model on the host (the same
//! test in f64 over the surface points rebuilt from the depth buffer) brackets; and never fewer
//! than the lights the pixel needs.

use glam::DVec3;
use manylights_cull::geometry::bin_of;
use manylights_cull::layout::{CLUSTER_GROUP_MIN_LIGHTS, ZBIN_ROUNDS_MIN_LIGHTS};
use manylights_cull::metrics::{exact_sets, surface_points};
use manylights_cull::{BinLists, CullOutput, ListForm};
use manylights_gpu::layout::GpuFrame;
use manylights_scene::Light;

use super::cluster_group::{atrium_lights, clusters};
use super::*;

/// The frame's walked lights counted on the GPU, its image, and the lists' lengths summed over
/// its covered pixels.
fn walked_and_listed(
    ctx: &GpuContext,
    (renderer, gpu_scene, s): (&Renderer, &GpuScene, &Scene),
    backend: Backend,
    strategy: &Strategy,
    (w, h): (u32, u32),
) -> (u64, ShadeOutput, u64) {
    let settings = CullSettings::for_camera(&s.camera);
    let render = || renderer.render(ctx, gpu_scene, backend, strategy, &settings, (w, h));
    let walked = gpu_scene
        .count_lights_walked(ctx, (&s.camera, w, h), || render().map(|_| ()))
        .unwrap();
    let out = render().unwrap();
    let listed = match &out.lists {
        Some(lists) => renderer
            .culler
            .lights_per_pixel(ctx, gpu_scene, &out.depth, lists)
            .unwrap()
            .iter()
            .map(|&n| u64::from(n))
            .sum(),
        None => {
            let covered = out.color.data.iter().filter(|p| p[3] > 0.0).count() as u64;
            covered * s.lights.len() as u64
        }
    };
    (walked, out, listed)
}

/// Every loop that walks a pixel's whole list (the loop a pixel, a list a tile a workgroup at a
/// time, z-binning's cells in one walk, forward's fragments, naive forward's every light)
/// counts exactly the lists' lengths; a frame not counted counts nothing.
#[test]
fn shading_walks_every_light_of_a_whole_list() {
    let ctx = common::gpu();
    let (w, h) = (70, 45);
    for s in [atrium_lights(300, 0.05), atrium_lights(1500, 0.03)] {
        let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
        let renderer = Renderer::new(&ctx, &gpu_scene);
        let zbin = |tile_size| Strategy::ZBin {
            tile_size,
            bins: 32,
            slicing: Slicing::Exponential,
        };
        let cases = [
            (
                Backend::Deferred,
                Strategy::tiled_gather(12),
                ListForm::Bins,
            ),
            (
                Backend::Deferred,
                Strategy::tiled_gather(16),
                ListForm::Tiles,
            ),
            (
                Backend::Visibility,
                Strategy::tiled_gather(16),
                ListForm::Tiles,
            ),
            (Backend::Deferred, clusters(12, 16), ListForm::Bins),
            (Backend::Deferred, zbin(16), ListForm::ZBin),
            (Backend::Deferred, zbin(12), ListForm::ZBin),
            (
                Backend::Forward,
                Strategy::tiled_gather(16),
                ListForm::Tiles,
            ),
            (Backend::Forward, zbin(16), ListForm::ZBin),
            (
                Backend::NaiveForward,
                Strategy::tiled_gather(16),
                ListForm::Tiles,
            ),
        ];
        for (backend, strategy, form) in cases {
            let what = format!(
                "{} {} {} lights",
                backend.name(),
                strategy.name(),
                s.lights.len()
            );
            let (walked, out, listed) = walked_and_listed(
                &ctx,
                (&renderer, &gpu_scene, &s),
                backend,
                &strategy,
                (w, h),
            );
            if let Some(lists) = &out.lists {
                assert_eq!(lists.form(), form, "{what}");
            }
            assert!(listed > 1000, "{what}: {listed} lights listed");
            assert_eq!(
                walked, listed,
                "{what}: lights walked against the lists' lengths"
            );
        }
        // Counted only where asked.
        let settings = CullSettings::for_camera(&s.camera);
        let strategy = Strategy::tiled_gather(16);
        let none = gpu_scene
            .count_rays(&ctx, (&s.camera, w, h), || {
                renderer
                    .render(
                        &ctx,
                        &gpu_scene,
                        Backend::Deferred,
                        &strategy,
                        &settings,
                        (w, h),
                    )
                    .map(|_| ())
            })
            .unwrap();
        assert_eq!(
            none, 0,
            "a frame counting rays without shadows counted lights"
        );
    }
}

/// The depth values of `out`, its surface points (f64, rebuilt from them) and the lights its
/// pixels need (their exact sets' sizes summed).
fn needed(
    ctx: &GpuContext,
    s: &Scene,
    out: &ShadeOutput,
    (w, h): (u32, u32),
) -> (Vec<f32>, Vec<Option<DVec3>>, u64) {
    let depth: Vec<f32> = bytemuck::pod_collect_to_vec(
        &manylights_gpu::readback::read_texture(ctx, &out.depth, wgpu::TextureAspect::DepthOnly)
            .unwrap(),
    );
    let frame = GpuFrame::new(&s.camera, w, h, s.lights.len() as u32);
    let points = surface_points(&frame, &depth, w, h);
    let needed = exact_sets(&points, &s.lights)
        .iter()
        .flatten()
        .map(|set| set.len() as u64)
        .sum();
    (depth, points, needed)
}

/// The host's model of `shade_parts_list`: for each 8 x 8 block, the box of the surface points of
/// its covered pixels in each slice; each pixel walks the lights of its cluster's list whose
/// sphere meets its slice's box.
/// Each light is counted where it meets the box with its radius scaled by `1 - margin` (`lo`)
/// and by `1 + margin` (`hi`), so that the GPU's f32 box and its relative margin of 1e-4 lie
/// between the two.
fn parts_model(
    (frame, lists, params): (
        &GpuFrame,
        &BinLists,
        &manylights_cull::layout::GpuCullParams,
    ),
    (depth, points): (&[f32], &[Option<DVec3>]),
    lights: &[Light],
    (w, h): (u32, u32),
    margin: f64,
) -> (u64, u64) {
    let (mut lo, mut hi) = (0u64, 0u64);
    for by in (0..h).step_by(8) {
        for bx in (0..w).step_by(8) {
            let pixels: Vec<(u32, u32)> = (by..(by + 8).min(h))
                .flat_map(|y| (bx..(bx + 8).min(w)).map(move |x| (x, y)))
                .filter(|&(x, y)| points[(y * w + x) as usize].is_some())
                .collect();
            // A box of each slice's pixels (`SLICE_BOXES`: where the block has one slice, the
            // whole block's).
            let mut boxes: Vec<(usize, DVec3, DVec3)> = Vec::new();
            for &(x, y) in &pixels {
                let z = depth[(y * w + x) as usize];
                let bin = bin_of(frame, params, [x, y], z) as usize;
                let p = points[(y * w + x) as usize].unwrap();
                match boxes.iter_mut().find(|b| b.0 == bin) {
                    Some(b) => (b.1, b.2) = (b.1.min(p), b.2.max(p)),
                    None => boxes.push((bin, p, p)),
                }
            }
            for &(x, y) in &pixels {
                let z = depth[(y * w + x) as usize];
                let bin = bin_of(frame, params, [x, y], z) as usize;
                let &(_, min, max) = boxes.iter().find(|b| b.0 == bin).unwrap();
                for &i in lists.list(bin) {
                    let l = &lights[i as usize];
                    let c = l.position.as_dvec3();
                    let q = c - c.clamp(min, max);
                    let r = f64::from(l.radius);
                    let d2 = q.length_squared();
                    lo += u64::from(d2 <= (r * (1.0 - margin)).powi(2));
                    hi += u64::from(d2 <= (r * (1.0 + margin)).powi(2));
                }
            }
        }
    }
    (lo, hi)
}

/// Over the clusters' lists a workgroup at a time, the pixels walk what the host's model of the
/// block box test walks, fewer lights than the lists hold and no fewer than they need, in
/// deferred (the model's own surface points, rebuilt from depth) and, bounded, with stored
/// positions and the visibility buffer.
#[test]
fn the_clusters_block_box_narrows_what_pixels_walk() {
    let ctx = common::gpu();
    let (w, h) = (96, 64);
    let s = atrium_lights(CLUSTER_GROUP_MIN_LIGHTS + 2000, 0.015);
    let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
    let renderer = Renderer::new(&ctx, &gpu_scene);
    for strategy in [clusters(32, 16), clusters(16, 32)] {
        for backend in [
            Backend::Deferred,
            Backend::DeferredStoredPosition,
            Backend::Visibility,
        ] {
            let what = format!("{} {}", backend.name(), strategy.name());
            let (walked, out, listed) = walked_and_listed(
                &ctx,
                (&renderer, &gpu_scene, &s),
                backend,
                &strategy,
                (w, h),
            );
            let lists: &CullOutput = out.lists.as_ref().unwrap();
            assert_eq!(lists.form(), ListForm::Clusters, "{what}");
            let (depth, points, needed) = needed(&ctx, &s, &out, (w, h));
            let frame = GpuFrame::new(&s.camera, w, h, s.lights.len() as u32);
            println!("{what}: needed {needed}, walked {walked}, listed {listed}");
            assert!(needed > 500, "{what}: {needed} lights needed");
            assert!(
                needed <= walked && walked * 10 < listed * 9,
                "{what}: lights needed {needed}, walked {walked}, listed {listed}"
            );
            if backend == Backend::Deferred {
                let read = lists.read(&ctx).unwrap();
                let (lo, hi) = parts_model(
                    (&frame, &read, &lists.params),
                    (&depth, &points),
                    &s.lights,
                    (w, h),
                    1e-3,
                );
                println!("{what}: the model's bracket {lo} ..= {hi}");
                assert!(
                    lo <= walked && walked <= hi && (hi - lo) * 100 < walked,
                    "{what}: walked {walked} outside the model's {lo} ..= {hi}"
                );
            }
        }
    }
    // Z-binning's rounds (from ZBIN_ROUNDS_MIN_LIGHTS lights, tiles of a multiple of 8 pixels)
    // test the same box as each light is loaded.
    let s = atrium_lights(ZBIN_ROUNDS_MIN_LIGHTS + 100, 0.01);
    let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
    let renderer = Renderer::new(&ctx, &gpu_scene);
    let strategy = Strategy::ZBin {
        tile_size: 16,
        bins: 32,
        slicing: Slicing::Exponential,
    };
    let (walked, out, listed) = walked_and_listed(
        &ctx,
        (&renderer, &gpu_scene, &s),
        Backend::Deferred,
        &strategy,
        (w, h),
    );
    assert_eq!(out.lists.as_ref().unwrap().form(), ListForm::ZBin);
    let (_, _, needed) = needed(&ctx, &s, &out, (w, h));
    println!("z-binning's rounds: needed {needed}, walked {walked}, listed {listed}");
    assert!(
        needed > 500 && needed <= walked && walked * 10 < listed * 9,
        "z-binning's rounds: lights needed {needed}, walked {walked}, listed {listed}"
    );
}

/// With MSAA 4 and every light in every list, each shading point (a pixel's centre, a sample,
/// a fragment) walks every light once: the count is the light count times the points, between
/// one and four a covered pixel, in deferred and the visibility buffer (which light several
/// points in one invocation) and forward.
#[test]
fn msaa_shading_points_walk_every_light_once() {
    let ctx = common::gpu();
    let (w, h) = (96, 54);
    let s = scene("pillars");
    let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
    let renderer = Renderer::with_samples(&ctx, &gpu_scene, 4).unwrap();
    let every = CullSettings {
        slack: 1e4,
        ..CullSettings::for_camera(&s.camera)
    };
    let strategy = Strategy::tiled_gather(16);
    let lights = s.lights.len() as u64;
    for backend in [Backend::Deferred, Backend::Visibility, Backend::Forward] {
        let render = || renderer.render(&ctx, &gpu_scene, backend, &strategy, &every, (w, h));
        let walked = gpu_scene
            .count_lights_walked(&ctx, (&s.camera, w, h), || render().map(|_| ()))
            .unwrap();
        let out = render().unwrap();
        let covered = out.color.data.iter().filter(|p| p[3] > 0.0).count() as u64;
        let points = walked / lights;
        println!(
            "{} MSAA 4: {points} shading points for {covered} covered pixels",
            backend.name()
        );
        assert_eq!(walked % lights, 0, "{}: {walked} walked", backend.name());
        assert!(
            covered <= points && points <= 4 * covered && points > covered,
            "{}: {points} points, {covered} pixels",
            backend.name()
        );
    }
}
