//! Per-pixel consumers of the lists (`shaders/cull/per_pixel/`), a thread a pixel through the
//! shared lookup: `cull.lights_per_pixel` (the lengths behind the heatmaps, checked against the
//! CPU's lookup) and `cull.exact` (the exact per-pixel oracle on the GPU, for images too large
//! for the CPU's O(pixels x lights); [`crate::metrics`]), and over transparent surfaces
//! `cull.exact_transparent`, a raster pass adding each visible transparent fragment's counts.

use crate::Kernel;
use manylights_gpu::{GpuContext, GpuError, GpuScene, pipeline, readback};

use crate::program::{DepthInput, Program};
use crate::shaders::{
    EXACT, EXACT_TRANSPARENT, LIGHTS_PER_PIXEL, create_over_samples, sample_constants,
};
use crate::{CullOutput, Culler};

/// The consumers' pipelines, over group 1 of [`Culler::lists_layout`].
pub(crate) struct PerPixel {
    lights_per_pixel: Kernel,
    exact: Kernel,
    depth_samples: Kernel,
    /// `cull.exact_transparent`, over the transparent geometry.
    exact_transparent: wgpu::RenderPipeline,
}

impl PerPixel {
    /// Their pipelines over the scene's group and the lists' group.
    pub fn new(
        d: &wgpu::Device,
        samples: u32,
        scene_layout: &wgpu::BindGroupLayout,
        lists_layout: &wgpu::BindGroupLayout,
    ) -> Self {
        let program = |def| {
            Program::new(
                d,
                def,
                DepthInput::Samples(samples),
                scene_layout,
                lists_layout,
            )
        };
        Self {
            lights_per_pixel: program(&LIGHTS_PER_PIXEL).pipeline(d, "lights_per_pixel"),
            depth_samples: program(&LIGHTS_PER_PIXEL).pipeline(d, "depth_samples"),
            exact: program(&EXACT).pipeline(d, "exact_counts"),
            exact_transparent: pipeline::raster_with(
                d,
                "cull.exact_transparent",
                &create_over_samples(d, &EXACT_TRANSPARENT, samples, &[]),
                &[scene_layout, lists_layout],
                Some(("fs_exact_transparent", &[])),
                pipeline::DepthTest::Less,
                samples,
                &sample_constants(samples),
            ),
        }
    }
}

impl Culler {
    /// The length of the list each pixel reads through the shared lookup (0 for background;
    /// with MSAA, the longest of its covered samples' lists).
    pub fn lights_per_pixel(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::Texture,
        lists: &CullOutput,
    ) -> Result<Vec<u32>, GpuError> {
        self.per_pixel(
            ctx,
            scene,
            depth,
            lists,
            &self.per_pixel.lights_per_pixel,
            1,
            bytemuck::bytes_of(&[0u32; 4]),
            None,
        )
    }

    /// Every sample's depth of each pixel (row by row, [`Culler::samples`] a pixel): how the
    /// host reads a multisampled depth buffer, which cannot be copied. `lists` are any run's
    /// over `depth` (the pass binds them and reads none).
    pub fn depth_samples(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::Texture,
        lists: &CullOutput,
    ) -> Result<Vec<f32>, GpuError> {
        let words = self.per_pixel(
            ctx,
            scene,
            depth,
            lists,
            &self.per_pixel.depth_samples,
            u64::from(self.samples),
            bytemuck::bytes_of(&[0u32; 4]),
            None,
        )?;
        Ok(words.into_iter().map(f32::from_bits).collect())
    }

    /// The exact per-pixel oracle on the GPU: per pixel `[evaluated, needed, found, points]`
    /// (see `shaders/cull/per_pixel/exact_point.wgsl`), summed over the points shaded there:
    /// its covered samples (one without MSAA) and its visible transparent fragments, `points`
    /// counting them; `world_from_clip` is the inverse of the frame's `clip_from_world`; only
    /// pixels on a grid of `stride` are evaluated (1: all).
    pub fn exact_counts(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::Texture,
        lists: &CullOutput,
        world_from_clip: glam::Mat4,
        stride: u32,
    ) -> Result<Vec<[u32; 4]>, GpuError> {
        self.exact_counts_with(ctx, scene, depth, lists, world_from_clip, stride, false)
    }

    /// As [`Culler::exact_counts`], with `shadowed` the exact set shadowed: a light is needed
    /// where it reaches the point and its shadow ray (from the point lifted towards it, through
    /// the scene's BVH, `GpuScene::build_bvh`) is clear, as culling by visibility is tested
    /// against (`crate::blocks::occlusion`).
    #[expect(
        clippy::too_many_arguments,
        reason = "exact_counts' inputs and the shadowed set"
    )]
    pub fn exact_counts_with(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::Texture,
        lists: &CullOutput,
        world_from_clip: glam::Mat4,
        stride: u32,
        shadowed: bool,
    ) -> Result<Vec<[u32; 4]>, GpuError> {
        if shadowed && !shadowed_exact_fits(ctx, scene.light_count) {
            return Err(GpuError::Unsupported(format!(
                "the shadowed exact oracle at {} lights: its rays' loops would pass the driver's \
                 silent loop limit ({:?} iterations an invocation; at most {} lights at {} \
                 traversal steps a ray)",
                scene.light_count,
                ctx.loop_limit,
                ctx.loop_light_limit().unwrap_or(0) / SHADOWED_EXACT_STEPS,
                SHADOWED_EXACT_STEPS
            )));
        }
        let params = crate::layout::GpuExactParams {
            world_from_clip,
            stride: stride.max(1),
            shadows: u32::from(shadowed),
            _pad: [0; 2],
        };
        let flat = self.per_pixel(
            ctx,
            scene,
            depth,
            lists,
            &self.per_pixel.exact,
            4,
            bytemuck::bytes_of(&params),
            Some(&self.per_pixel.exact_transparent),
        )?;
        Ok(flat
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect())
    }

    /// Runs a one-thread-per-pixel consumer of the lists with `uniform` at binding 5 and reads
    /// back its `stride` u32 per pixel; then, where the scene has transparent surfaces,
    /// `transparent` over them into the same output, the depth buffer read only.
    #[expect(
        clippy::too_many_arguments,
        reason = "the lists, their consumer and its one parameter"
    )]
    fn per_pixel(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::Texture,
        lists: &CullOutput,
        pipeline: &Kernel,
        stride: u64,
        uniform: &[u8],
        transparent: Option<&wgpu::RenderPipeline>,
    ) -> Result<Vec<u32>, GpuError> {
        let (w, h) = (depth.width(), depth.height());
        let d = &ctx.device;
        let bytes = u64::from(w) * u64::from(h) * 4 * stride;
        ctx.check_storage("per-pixel output", bytes)?;
        let out = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("cull.per_pixel"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let exact = pipeline::uniform_buffer(d, "cull.exact.params", uniform);
        let view = depth.create_view(&wgpu::TextureViewDescriptor {
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        });
        let [params, ranges, indices] = lists.list_bindings();
        let group = pipeline::group(
            d,
            "lists.group1",
            &self.lists_layout,
            &[
                params,
                ranges,
                indices,
                wgpu::BindingResource::TextureView(&view),
                out.as_entire_binding(),
                exact.as_entire_binding(),
            ],
        );
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("cull.per_pixel"),
        });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("cull.per_pixel"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&pipeline.pipeline);
            pass.set_bind_group(0, &scene.bind_group, &[]);
            pass.set_bind_group(1, &group, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        if let Some(raster) = transparent.filter(|_| scene.has_transparent()) {
            let attachment = depth.create_view(&Default::default());
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("cull.exact_transparent"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &attachment,
                    depth_ops: None,
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(raster);
            pass.set_bind_group(1, &group, &[]);
            scene.draw_transparent(&mut pass);
        }
        ctx.submit_and_wait(enc, "per-pixel list consumer")?;
        Ok(bytemuck::pod_collect_to_vec(&readback::read_buffer(
            ctx, &out, 0, bytes,
        )?))
    }
}

/// The traversal steps a shadow ray of the shadowed exact oracle is budgeted under a driver's
/// loop limit ([`shadowed_exact_fits`]).
pub const SHADOWED_EXACT_STEPS: u64 = 128;

/// Whether the shadowed exact oracle ([`Culler::exact_counts_with`]) fits the driver's loop
/// limit at `lights` lights: everywhere without one; under llvmpipe's, where every light's ray
/// at [`SHADOWED_EXACT_STEPS`] steps, over every light and then a list, stays within it (a loop
/// past it stops short silently and would miscount).
pub fn shadowed_exact_fits(ctx: &GpuContext, lights: u32) -> bool {
    ctx.loop_light_limit()
        .is_none_or(|l| u64::from(lights) * SHADOWED_EXACT_STEPS <= l)
}
