//! Shared helpers of the integration tests.

#![allow(dead_code, reason = "each test binary uses a different subset")]

use manylights_gpu::{GpuContext, GpuOptions};

/// The test device. A test that needs a GPU and finds none fails with the adapter list and how
/// to install lavapipe; it never passes silently.
pub fn gpu() -> GpuContext {
    GpuContext::new(&GpuOptions::default()).unwrap_or_else(|e| {
        panic!("this test needs a Vulkan adapter (lavapipe is enough: `apt-get install mesa-vulkan-drivers libvulkan1`): {e}")
    })
}

/// Uploads `scene` with `camera`, runs the depth prepass at `w` x `h`, and returns the uploaded
/// scene, the depth texture and its values (rows from the top).
pub fn depth_prepass(
    ctx: &GpuContext,
    scene: &manylights_scene::Scene,
    camera: &manylights_scene::Camera,
    w: u32,
    h: u32,
) -> (manylights_gpu::GpuScene, wgpu::Texture, Vec<f32>) {
    use manylights_gpu::prepass::{DepthPrepass, depth_target};
    let gpu_scene = manylights_gpu::GpuScene::upload(ctx, scene, camera, w, h).unwrap();
    let depth = depth_target(ctx, w, h);
    let view = depth.create_view(&Default::default());
    let mut timer = manylights_gpu::timing::GpuTimer::new(ctx, 1);
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    DepthPrepass::new(ctx, &gpu_scene).encode(&mut enc, &gpu_scene, &view, &mut timer);
    ctx.submit_and_wait(enc, "test prepass").unwrap();
    let bytes = manylights_gpu::readback::read_texture(ctx, &depth, wgpu::TextureAspect::DepthOnly)
        .unwrap();
    (gpu_scene, depth, bytemuck::pod_collect_to_vec(&bytes))
}
