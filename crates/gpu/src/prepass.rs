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
    pipeline::texture_2d(
        &ctx.device,
        "depth",
        (width, height),
        DEPTH_FORMAT,
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
    )
}

/// The depth prepass pipeline.
pub struct DepthPrepass {
    pipeline: wgpu::RenderPipeline,
}

impl DepthPrepass {
    /// Builds the pipeline for scenes laid out as [`GpuScene`].
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Self {
        let module = shaders::PREPASS.create(&ctx.device);
        let pipeline = pipeline::raster(
            &ctx.device,
            "prepass.depth",
            &module,
            &[&scene.layout],
            None,
            pipeline::DepthTest::WriteLess,
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
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("prepass.depth"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.render_pass("prepass.depth"),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        scene.draw(&mut pass);
    }
}
