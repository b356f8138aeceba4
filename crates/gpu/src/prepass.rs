//! The depth prepass (`prepass.depth`): the shared vertex stage into a `Depth32Float` target that
//! culling strategies read and that later raster passes test against with `Equal`.

use crate::timing::GpuTimer;
use crate::{GpuContext, GpuScene, pipeline, shaders};

/// Depth format of every raster pass.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The primitive state of every raster pass: triangle lists, no culling (surfaces are two-sided).
pub const PRIMITIVE: wgpu::PrimitiveState = wgpu::PrimitiveState {
    topology: wgpu::PrimitiveTopology::TriangleList,
    strip_index_format: None,
    front_face: wgpu::FrontFace::Ccw,
    cull_mode: None,
    unclipped_depth: false,
    polygon_mode: wgpu::PolygonMode::Fill,
    conservative: false,
};

/// A depth texture that can be rendered, sampled by compute passes, and read back.
pub fn depth_target(ctx: &GpuContext, width: u32, height: u32) -> wgpu::Texture {
    depth_target_msaa(ctx, width, height, 1)
}

/// A depth texture of `samples` samples a pixel (MSAA where more than one) that can be
/// rendered and read by compute passes; one of a single sample can also be copied back (a
/// multisampled texture cannot be copied: `cull::per_pixel` reads its samples in a pass).
pub fn depth_target_msaa(ctx: &GpuContext, width: u32, height: u32, samples: u32) -> wgpu::Texture {
    let copy = if samples == 1 {
        wgpu::TextureUsages::COPY_SRC
    } else {
        wgpu::TextureUsages::empty()
    };
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("depth"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: samples,
        dimension: wgpu::TextureDimension::D2,
        format: DEPTH_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING | copy,
        view_formats: &[],
    })
}

/// The depth prepass pipeline.
pub struct DepthPrepass {
    pipeline: wgpu::RenderPipeline,
}

impl DepthPrepass {
    /// Builds the pipeline for scenes laid out as [`GpuScene`].
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Self {
        Self::with_samples(ctx, scene, 1)
    }

    /// The pipeline into a depth buffer of `samples` samples a pixel (MSAA where more than
    /// one; `GpuContext::check_msaa` says which counts the device has).
    pub fn with_samples(ctx: &GpuContext, scene: &GpuScene, samples: u32) -> Self {
        let module = shaders::PREPASS.create(&ctx.device);
        let pipeline = pipeline::raster_msaa(
            &ctx.device,
            "prepass.depth",
            &module,
            &[&scene.layout],
            None,
            pipeline::DepthTest::WriteLess,
            samples,
        );
        Self { pipeline }
    }

    /// Clears `depth` to the far plane (1.0) and draws the scene into it.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        depth: &wgpu::TextureView,
        timer: &mut GpuTimer,
    ) {
        let writes = timer.render_pass("prepass.depth");
        let mut pass = begin_depth_pass(encoder, "prepass.depth", depth, writes);
        pass.set_pipeline(&self.pipeline);
        scene.draw(&mut pass);
    }
}

/// A render pass `label` with no colour target that clears `depth` to the far plane (1.0) and
/// stores what it draws, timed by `timestamp_writes` (the depth prepass; the compute
/// visibility pass's depth copy).
pub fn begin_depth_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    depth: &wgpu::TextureView,
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}
