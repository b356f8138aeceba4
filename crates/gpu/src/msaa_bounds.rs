//! The depth culling takes its bounds from under MSAA (`MsaaBounds`).
//!
//! With MSAA the forward passes shade a fragment once, at its centroid, and look its list up
//! at that point's depth. The centroid lies on the fragment's plane within the pixel, and can
//! lie where another primitive hides the sample there, so its depth need not be any sample's:
//! bounds over the depth buffer's samples alone can miss it, and a cluster's list there can be
//! empty. So the prepass also keeps, at each sample a fragment wins, that fragment's depth range
//! over the pixel (`prepass.depth`, `shaders/common/depth_range.wgsl`, an `Rg32Float` target),
//! and `prepass.depth_bounds` (`shaders/common/depth_bounds.wgsl`) writes a multisampled depth
//! texture whose samples hold each covered pixel's nearest and farthest such depth. Culling
//! reads that texture; the shading pass tests against the depth buffer, and the exact oracle
//! checks the depth buffer's samples.

use crate::prepass::{DEPTH_FORMAT, PRIMITIVE, depth_target_msaa};
use crate::shaders::{FRAME, ShaderDef, VERTEX};
use crate::timing::GpuTimer;
use crate::{GpuContext, GpuScene, pipeline, shader_file};

/// Format of the prepass's per-sample depth ranges.
pub const RANGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// `prepass.depth` keeping each winning fragment's depth range over its pixel.
pub const PREPASS_RANGES: ShaderDef = ShaderDef {
    name: "prepass.depth",
    consts: &[],
    files: &[FRAME, VERTEX, shader_file!("common/depth_range.wgsl")],
};

/// `prepass.depth_bounds`.
pub const BOUNDS: ShaderDef = ShaderDef {
    name: "prepass.depth_bounds",
    consts: &[],
    files: &[shader_file!("common/depth_bounds.wgsl")],
};

/// Bytes a sample of the targets [`MsaaBounds`] adds: a depth range and a bounds depth.
pub const BYTES_PER_SAMPLE: u64 = 8 + 4;

/// The pipelines of the MSAA lookup bounds for one sample count.
pub struct MsaaBounds {
    prepass: wgpu::RenderPipeline,
    bounds: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    samples: u32,
}

/// A frame's targets of [`MsaaBounds`].
pub struct BoundsTargets {
    ranges: wgpu::TextureView,
    /// The depth texture culling reads (multisampled like the depth buffer).
    pub bounds: wgpu::Texture,
    bounds_view: wgpu::TextureView,
    group: wgpu::BindGroup,
}

impl MsaaBounds {
    /// The pipelines for scenes laid out as [`GpuScene`], at `samples` samples a pixel.
    pub fn new(ctx: &GpuContext, scene: &GpuScene, samples: u32) -> Self {
        let d = &ctx.device;
        let prepass = pipeline::raster_msaa(
            d,
            "prepass.depth",
            &PREPASS_RANGES.create(d),
            &[&scene.layout],
            Some(("fs_depth_range", &[pipeline::target(RANGE_FORMAT)])),
            pipeline::DepthTest::WriteLess,
            samples,
        );
        let fragment = wgpu::ShaderStages::FRAGMENT;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("prepass.depth_bounds"),
            entries: &[
                pipeline::entry(
                    0,
                    fragment,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: true,
                    },
                ),
                pipeline::entry(1, fragment, pipeline::depth_texture(samples)),
            ],
        });
        let module = BOUNDS.create(d);
        let bounds = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("prepass.depth_bounds"),
            layout: Some(&pipeline::layout(d, "prepass.depth_bounds", &[&layout])),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_screen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: PRIMITIVE,
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: wgpu::MultisampleState {
                count: samples,
                ..Default::default()
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_bounds"),
                compilation_options: Default::default(),
                targets: &[],
            }),
            multiview_mask: None,
            cache: None,
        });
        Self {
            prepass,
            bounds,
            layout,
            samples,
        }
    }

    /// The targets of a `width` x `height` frame whose depth buffer is `depth`.
    pub fn targets(
        &self,
        ctx: &GpuContext,
        (width, height): (u32, u32),
        depth: &wgpu::Texture,
    ) -> BoundsTargets {
        let ranges = pipeline::texture_2d_msaa(
            &ctx.device,
            "prepass.depth_ranges",
            (width, height),
            RANGE_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            self.samples,
        )
        .create_view(&Default::default());
        let bounds = depth_target_msaa(ctx, width, height, self.samples);
        let depth_only = depth.create_view(&wgpu::TextureViewDescriptor {
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        });
        let group = pipeline::group(
            &ctx.device,
            "prepass.depth_bounds",
            &self.layout,
            &[
                wgpu::BindingResource::TextureView(&ranges),
                wgpu::BindingResource::TextureView(&depth_only),
            ],
        );
        BoundsTargets {
            bounds_view: bounds.create_view(&Default::default()),
            bounds,
            ranges,
            group,
        }
    }

    /// The depth prepass into `depth` keeping the depth ranges, then `prepass.depth_bounds`.
    pub fn encode(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        depth: &wgpu::TextureView,
        targets: &BoundsTargets,
        timer: &mut GpuTimer,
    ) {
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("prepass.depth"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &targets.ranges,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(depth_attachment(depth)),
                timestamp_writes: timer.render_pass("prepass.depth"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.prepass);
            scene.draw(&mut pass);
        }
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("prepass.depth_bounds"),
            color_attachments: &[],
            depth_stencil_attachment: Some(depth_attachment(&targets.bounds_view)),
            timestamp_writes: timer.render_pass("prepass.depth_bounds"),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.bounds);
        pass.set_bind_group(0, &targets.group, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// A depth attachment cleared to the far plane and stored.
fn depth_attachment(view: &wgpu::TextureView) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(1.0),
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: None,
    }
}
