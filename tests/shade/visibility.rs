//! The visibility buffer: its triangle ids against the G-buffer the same raster pipeline state
//! writes, and the surface an id stands for (the f64 oracle of `manylights_shade::visibility`)
//! against the rasterised attributes; and the device feature it needs.

use manylights_cull::{CullSettings, Strategy};
use manylights_gpu::GpuScene;
use manylights_gpu::layout::GpuFrame;
use manylights_scene::Model;
use manylights_shade::visibility::{read_geometry, read_surfaces, triangle_surface};
use manylights_shade::{Backend, Renderer, VisibilityPass};

use super::{common, scene};

/// At every pixel of `atrium` and `pillars` (five material models mixed), at 64 x 48 and
/// 70 x 45, with the compute rasteriser and with the raster pass: a pixel holds a triangle id
/// exactly where the G-buffer pass covers it; the id names
/// an opaque triangle; and the oracle's surface for it, where the pixel centre's ray meets that
/// triangle, is the rasterised one: the position within 1e-4 of the distance to the eye of the
/// interpolated position `deferred_stored_position` stores, the normal within 1e-3 of the
/// G-buffer's, the material the G-buffer's, and the point on the triangle (barycentrics within
/// [-1e-2, 1 + 1e-2]: the rasteriser covers a pixel centre from vertices snapped to its
/// sub-pixel grid, so a centre just outside the exact triangle may be covered; measured
/// -2.9e-3 on lavapipe).
#[test]
fn triangle_ids_give_the_rasterised_surface() {
    let ctx = common::gpu();
    let (mut worst_p, mut worst_n) = (0.0f64, 0.0f64);
    for name in ["atrium", "pillars"] {
        let mut s = scene(name);
        s.assign_models(&Model::ALL);
        for (w, h) in [(64, 48), (70, 45)] {
            let what = format!("{name} {w}x{h}");
            let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
            let mut renderer = Renderer::new(&ctx, &gpu_scene);
            let settings = CullSettings::for_camera(&s.camera);
            let strategy = Strategy::tiled_gather(16);
            let g = read_surfaces(
                &ctx,
                &renderer
                    .render(
                        &ctx,
                        &gpu_scene,
                        Backend::DeferredStoredPosition,
                        &strategy,
                        &settings,
                        (w, h),
                    )
                    .unwrap(),
            )
            .unwrap();
            let (vertices, indices) = read_geometry(&ctx, &gpu_scene).unwrap();
            let frame = GpuFrame::new(&s.camera, w, h, s.lights.len() as u32);
            let opaque = gpu_scene.opaque_index_count / 3;
            for pass in [VisibilityPass::Compute, VisibilityPass::Raster] {
                renderer.visibility_pass = pass;
                let out = renderer
                    .render(
                        &ctx,
                        &gpu_scene,
                        Backend::Visibility,
                        &strategy,
                        &settings,
                        (w, h),
                    )
                    .unwrap();
                let ids = read_surfaces(&ctx, &out).unwrap().ids;
                let what = format!("{what} {}", pass.name());
                let mut covered = 0;
                for y in 0..h {
                    for x in 0..w {
                        let k = (y * w + x) as usize;
                        let at = format!("{what} pixel ({x}, {y})");
                        let gb_covered = g.normal_depth[k][3] != 0.0;
                        assert_eq!(ids[k] != 0, gb_covered, "{at}: id {}", ids[k]);
                        if ids[k] == 0 {
                            continue;
                        }
                        covered += 1;
                        assert!(
                            ids[k] <= opaque,
                            "{at}: id {} of {opaque} triangles",
                            ids[k]
                        );
                        let t = triangle_surface(&vertices, &indices, &frame, (x, y), ids[k])
                            .unwrap_or_else(|| panic!("{at}: the ray misses the triangle's plane"));
                        assert!(
                            t.barycentrics.min_element() >= -1e-2
                                && t.barycentrics.max_element() <= 1.0 + 1e-2,
                            "{at}: barycentrics {}",
                            t.barycentrics
                        );
                        let stored = glam::Vec3::from_slice(&g.position[k][..3]).as_dvec3();
                        let eye = frame.eye.truncate().as_dvec3();
                        let dp = (t.position - stored).length() / (stored - eye).length();
                        let normal = glam::Vec3::from_slice(&g.normal_depth[k][..3]).as_dvec3();
                        let dn = (t.normal - normal).length();
                        worst_p = worst_p.max(dp);
                        worst_n = worst_n.max(dn);
                        assert!(dp <= 1e-4, "{at}: position {} against {stored}", t.position);
                        assert!(dn <= 1e-3, "{at}: normal {} against {normal}", t.normal);
                        assert_eq!(t.material, g.ids[k], "{at}: material");
                    }
                }
                assert!(
                    covered > (w * h) as usize / 2,
                    "{what}: {covered} pixels covered"
                );
            }
        }
    }
    println!(
        "visibility oracle against the rasterised surface: position {worst_p:.2e} of the distance, normal {worst_n:.2e}"
    );
}

/// A small frame of `name` (32 x 24): its scene on the GPU and a renderer for it.
fn small_frame(ctx: &manylights_gpu::GpuContext, name: &str) -> (GpuScene, Renderer, CullSettings) {
    let s = scene(name);
    let gpu_scene = GpuScene::upload(ctx, &s, &s.camera, 32, 24).unwrap();
    let renderer = Renderer::new(ctx, &gpu_scene);
    (gpu_scene, renderer, CullSettings::for_camera(&s.camera))
}

/// `backend`'s frame of `small_frame`, or its error in words.
fn small_render(
    ctx: &manylights_gpu::GpuContext,
    (gpu_scene, renderer, settings): &(GpuScene, Renderer, CullSettings),
    backend: Backend,
) -> Result<(), String> {
    renderer
        .render(
            ctx,
            gpu_scene,
            backend,
            &Strategy::tiled_gather(16),
            settings,
            (32, 24),
        )
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// Where the device lacks `@builtin(primitive_index)`, the visibility backend's raster pass is
/// an error that names the feature and the adapter, and the other backends still render; the
/// compute rasteriser, which does not need it, renders (where the device has 64-bit atomic
/// max; without both, the error again).
#[test]
fn visibility_without_primitive_index_is_an_error() {
    let mut ctx = common::gpu();
    assert!(
        ctx.features.primitive_index && ctx.features.int64_atomics,
        "lavapipe and NVIDIA offer PRIMITIVE_INDEX and 64-bit atomic max: the visibility \
         backend's tests need both"
    );
    ctx.features.primitive_index = false;
    let mut frame = small_frame(&ctx, "atrium");
    small_render(&ctx, &frame, Backend::Visibility).expect("the compute rasteriser renders");
    frame.1.visibility_pass = VisibilityPass::Raster;
    let err = small_render(&ctx, &frame, Backend::Visibility)
        .expect_err("the raster pass without PRIMITIVE_INDEX");
    assert!(
        err.contains("PRIMITIVE_INDEX") && err.contains(&ctx.info.name),
        "{err}"
    );
    small_render(&ctx, &frame, Backend::Deferred).unwrap();
    ctx.features.int64_atomics = false;
    let frame = small_frame(&ctx, "atrium");
    let err = small_render(&ctx, &frame, Backend::Visibility)
        .expect_err("neither PRIMITIVE_INDEX nor 64-bit atomics");
    assert!(err.contains("PRIMITIVE_INDEX"), "{err}");
}

/// The compute rasteriser binds its keys (8 bytes a pixel) and its queue (128 bytes a
/// triangle) as storage buffers: past the device's binding limit `render` says which and how
/// to draw the frame instead (the raster pass), which then renders.
#[test]
fn compute_visibility_past_the_binding_limit_is_an_error() {
    let mut ctx = common::gpu();
    let mut frame = small_frame(&ctx, "pillars");
    // Room for the index buffer, not for the queue (ten times its bytes).
    ctx.limits.max_storage_buffer_binding_size = frame.0.indices.size();
    let err = small_render(&ctx, &frame, Backend::Visibility).expect_err("a queue past the limit");
    assert!(
        err.contains("queue") && err.contains("--visibility-pass raster"),
        "{err}"
    );
    frame.1.visibility_pass = VisibilityPass::Raster;
    small_render(&ctx, &frame, Backend::Visibility).unwrap();
}

/// The visibility buffer's lighting binds the scene's index buffer as one storage buffer: where
/// it is larger than the device's binding limit, `render` says so, naming the limit (here the
/// limit is lowered after the upload, as a device with a small one would have it).
#[test]
fn an_index_buffer_past_the_binding_limit_is_an_error() {
    let mut ctx = common::gpu();
    let frame = small_frame(&ctx, "pillars");
    ctx.limits.max_storage_buffer_binding_size = frame.0.indices.size() - 4;
    let err = small_render(&ctx, &frame, Backend::Visibility)
        .expect_err("an index buffer past the limit");
    assert!(
        err.contains("index buffer bytes") && err.contains("max_storage_buffer_binding_size"),
        "{err}"
    );
}

/// The visibility pass rasterised in compute (`manylights_shade::vis_compute`) against the
/// hardware pass (`VisibilityPass::Raster`) on the same frame: at least 99.95% of pixels hold
/// the same triangle id (both snap vertices to 1/256 pixel and take ties by the top-left rule;
/// measured 100% but 5 of 57,600 pixels of `atrium` at 320 x 180, near-plane-clipped triangles
/// whose clipped vertices round apart), the same NDC depth to 1e-4 where they agree (measured
/// 5.3e-5), and no large triangle dropped; at 320 x 180 large triangles take the blocks' path;
/// another tiling (8-pixel blocks, 16-pixel small triangles) gives the same frame.
#[test]
fn the_compute_visibility_pass_matches_the_hardware_pass() {
    use manylights_shade::vis_compute::{ComputeVisibility, Tiling};
    let ctx = common::gpu();
    for name in ["atrium", "pillars"] {
        let s = scene(name);
        // At 640 x 360 8-pixel blocks number more than the blocks' pass has workgroups (a
        // full-frame triangle alone has 3,600), so that each takes a run of blocks that spans
        // several triangles.
        for (w, h) in [(64, 48), (70, 45), (320, 180), (640, 360)] {
            let what = format!("{name} {w}x{h}");
            let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
            let mut renderer = Renderer::new(&ctx, &gpu_scene);
            renderer.visibility_pass = VisibilityPass::Raster;
            let settings = CullSettings::for_camera(&s.camera);
            let out = renderer
                .render(
                    &ctx,
                    &gpu_scene,
                    Backend::Visibility,
                    &Strategy::tiled_gather(16),
                    &settings,
                    (w, h),
                )
                .unwrap();
            let ids = read_surfaces(&ctx, &out).unwrap().ids;
            let depth_bytes = manylights_gpu::readback::read_texture(
                &ctx,
                &out.depth,
                wgpu::TextureAspect::DepthOnly,
            )
            .unwrap();
            let depth: &[f32] = bytemuck::cast_slice(&depth_bytes);
            let cv = ComputeVisibility::new(&ctx, &gpu_scene).unwrap();
            let t = cv.targets(&ctx, &gpu_scene, (w, h));
            let f = cv.run(&ctx, &gpu_scene, &t).unwrap();
            // Other tilings give the same frame (they share out the same keys).
            let other = ComputeVisibility::with_tiling(
                &ctx,
                &gpu_scene,
                Tiling {
                    block: 8,
                    small: 16,
                },
            )
            .unwrap();
            let o = other
                .run(&ctx, &gpu_scene, &other.targets(&ctx, &gpu_scene, (w, h)))
                .unwrap();
            assert!(
                o.ids == f.ids && o.depth == f.depth,
                "{what}: another tiling's frame differs"
            );
            assert_eq!(f.dropped, 0, "{what}");
            if w >= 320 {
                assert!(f.queued > 0, "{what}: no triangle took the blocks' path");
            }
            let n = ids.len();
            let same = (0..n).filter(|&k| ids[k] == f.ids[k]).count();
            assert!(
                same * 10_000 >= n * 9_995,
                "{what}: {same} of {n} ids agree"
            );
            let worst = (0..n)
                .filter(|&k| ids[k] == f.ids[k])
                .map(|k| (depth[k] - f.depth[k]).abs())
                .fold(0.0f32, f32::max);
            assert!(worst <= 1e-4, "{what}: depth within {worst}");
            println!("{what}: {same} of {n} ids agree, depth within {worst:e}");
        }
    }
}

/// Culling over the compute rasteriser's `R32Float` depth (the renderer's one culler, over its
/// pipelines for a float depth) builds, for every strategy, the very lists that culling over a
/// depth buffer of the same depths builds (the depth buffer the untimed
/// `shade.visibility_depth` pass writes, whose lists the CPU oracles check in tests/cull): the
/// two depth inputs are one culling. And the culler's knobs reach the compute frames: z-binning's
/// masks take the path `zbin_scatter_min_lights` picks.
#[test]
fn culling_over_the_compute_depth_equals_culling_over_the_depth_buffer() {
    let ctx = common::gpu();
    for name in ["atrium", "pillars"] {
        let s = scene(name);
        let (w, h) = (70, 45);
        let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
        let mut renderer = Renderer::new(&ctx, &gpu_scene);
        let settings = CullSettings::for_camera(&s.camera);
        for (min_lights, pass) in [(0, "cull.zbin.scatter"), (u32::MAX, "cull.zbin.masks")] {
            renderer.culler.zbin_scatter_min_lights = min_lights;
            let out = renderer
                .render(
                    &ctx,
                    &gpu_scene,
                    Backend::Visibility,
                    &Strategy::ZBin {
                        tile_size: 8,
                        bins: 64,
                        slicing: manylights_cull::Slicing::Exponential,
                    },
                    &settings,
                    (w, h),
                )
                .unwrap();
            assert!(out.computed_visibility(), "{name}");
            let t = out.timings.as_ref().expect("timestamp queries");
            assert!(
                t.iter().any(|p| p.label == pass),
                "{name}: zbin_scatter_min_lights {min_lights} did not reach the compute frame's \
                 culling ({pass} not among {:?})",
                t.iter().map(|p| &p.label).collect::<Vec<_>>()
            );
        }
        renderer.culler.zbin_scatter_min_lights = manylights_cull::ZBIN_SCATTER_MIN_LIGHTS;
        for strategy in super::strategies() {
            let what = format!("{name} {}", strategy.name());
            let out = renderer
                .render(
                    &ctx,
                    &gpu_scene,
                    Backend::Visibility,
                    &strategy,
                    &settings,
                    (w, h),
                )
                .unwrap();
            assert!(
                out.computed_visibility(),
                "{what}: lavapipe has 64-bit atomic max"
            );
            let over_float = out.lists.as_ref().unwrap().read(&ctx).unwrap();
            let mut timer = manylights_gpu::timing::GpuTimer::new(&ctx, 64);
            let over_depth = renderer
                .culler
                .run(
                    &ctx, &gpu_scene, &out.depth, &strategy, &settings, &mut timer,
                )
                .unwrap()
                .read(&ctx)
                .unwrap();
            assert!(
                !over_float.indices.is_empty(),
                "{what}: the lists hold no light"
            );
            assert_eq!(over_float.ranges.len(), over_depth.ranges.len(), "{what}");
            // Each bin's set of lights (an unordered strategy may append them in any order).
            for b in 0..over_float.ranges.len() {
                assert_eq!(
                    over_float.sorted(b),
                    over_depth.sorted(b),
                    "{what}: bin {b}"
                );
            }
        }
    }
}

/// The compute rasteriser's geometry back to back (`Renderer::geometry_repeated`, what the
/// steady-state frame repeats): its four passes a run, timed, no raster pass, and the same ids
/// after as before.
#[test]
fn compute_visibility_geometry_repeats_the_frame() {
    let ctx = common::gpu();
    let frame = small_frame(&ctx, "atrium");
    let (gpu_scene, renderer, settings) = &frame;
    let out = renderer
        .render(
            &ctx,
            gpu_scene,
            Backend::Visibility,
            &Strategy::tiled_gather(16),
            settings,
            (32, 24),
        )
        .unwrap();
    assert!(out.computed_visibility());
    let before = read_surfaces(&ctx, &out).unwrap().ids;
    let mut timer = manylights_gpu::timing::GpuTimer::new(&ctx, 64);
    renderer
        .geometry_repeated(&ctx, gpu_scene, &out, 3, &mut timer)
        .unwrap();
    let labels: Vec<String> = timer
        .read(&ctx)
        .unwrap()
        .expect("timestamps (lavapipe has them)")
        .into_iter()
        .map(|p| p.label)
        .collect();
    let compute = labels
        .iter()
        .filter(|l| l.starts_with("shade.visibility_compute."))
        .count();
    assert_eq!(compute, 3 * 4, "{labels:?}");
    assert!(
        !labels.iter().any(|l| l == "shade.visibility"),
        "{labels:?}"
    );
    assert_eq!(read_surfaces(&ctx, &out).unwrap().ids, before);
}

/// Coplanar surfaces, tie by tie: every opaque triangle of `atrium` and `pillars` drawn twice
/// (each primitive again, the same vertices and material), so that every covered pixel holds
/// two triangles at exactly the same depth. The raster pass keeps the first one drawn (its depth
/// test is `Less`) and the compute rasteriser the smaller id at equal depth: at no pixel do the
/// two passes name different copies of one triangle, and they agree where the uncopied scene's
/// passes do (at least 99.95% of pixels; with the larger id kept at ties, almost none agree).
#[test]
fn coplanar_copies_keep_the_first_triangle_in_both_visibility_passes() {
    let ctx = common::gpu();
    for name in ["atrium", "pillars"] {
        let mut s = scene(name);
        let copies = s.primitives.clone();
        s.primitives.extend(copies);
        for (w, h) in [(64, 48), (70, 45)] {
            let what = format!("{name} twice {w}x{h}");
            let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
            let mut renderer = Renderer::new(&ctx, &gpu_scene);
            let settings = CullSettings::for_camera(&s.camera);
            let mut ids = Vec::new();
            for pass in [VisibilityPass::Raster, VisibilityPass::Compute] {
                renderer.visibility_pass = pass;
                let out = renderer
                    .render(
                        &ctx,
                        &gpu_scene,
                        Backend::Visibility,
                        &Strategy::tiled_gather(16),
                        &settings,
                        (w, h),
                    )
                    .unwrap();
                assert_eq!(
                    out.computed_visibility(),
                    pass == VisibilityPass::Compute,
                    "{what}: {pass:?}"
                );
                ids.push(read_surfaces(&ctx, &out).unwrap().ids);
            }
            let (vertices, indices) = read_geometry(&ctx, &gpu_scene).unwrap();
            let corners = |id: u32| -> [[u32; 3]; 3] {
                let t = (id - 1) as usize;
                [0, 1, 2].map(|k| {
                    bytemuck::cast::<_, [u32; 3]>(vertices[indices[3 * t + k] as usize].position)
                })
            };
            let (raster, compute) = (&ids[0], &ids[1]);
            let n = raster.len();
            let mut covered = 0;
            for k in 0..n {
                let (a, b) = (raster[k], compute[k]);
                if a == 0 || b == 0 || a == b {
                    covered += usize::from(a != 0);
                    continue;
                }
                assert!(
                    corners(a) != corners(b),
                    "{what}: pixel {k}: the raster pass keeps triangle {} and the compute \
                     rasteriser its copy {} at the same depth",
                    a - 1,
                    b - 1
                );
            }
            let same = (0..n).filter(|&k| raster[k] == compute[k]).count();
            assert!(
                covered > n / 4,
                "{what}: only {covered} of {n} pixels covered"
            );
            assert!(
                same * 10_000 >= n * 9_995,
                "{what}: {same} of {n} ids agree"
            );
        }
    }
}
