//! The depth culling takes its bounds from where a forward pass looks lists up elsewhere than
//! at the depth buffer's samples (`LookupBounds`).
//!
//! - **MSAA.** The forward passes shade a fragment once, at its centroid, and look its list up
//!   at that point's depth. The centroid lies on the fragment's plane within the pixel, and can
//!   lie where another primitive hides the sample there, so its depth need not be any sample's:
//!   bounds over the depth buffer's samples alone can miss it, and a cluster's list there can
//!   be empty. So the prepass also keeps, at each sample a fragment wins, that fragment's depth
//!   range over the pixel (`prepass.depth`, `shaders/common/depth_range.wgsl`, an `Rg32Float`
//!   target).
//! - **Transparent surfaces** lie in front of the opaque depth, where bounds over it exclude
//!   the lights that reach them (failure case 16). Their nearest and farthest depth ranges go
//!   into two depth targets (`prepass.transparent_near`, `prepass.transparent_far`).
//!
//! `prepass.depth_bounds` (`shaders/common/depth_bounds.wgsl`, a compute pass) then writes each
//! covered pixel's nearest and farthest lookup depth into an `Rg32Float` texture
//! ([`BOUNDS_FORMAT`]). Culling reads that texture (`Culler::with_bounds`) in place of the depth
//! buffer; the shading passes test against the depth buffer, and the exact oracle checks the
//! depth buffer's samples and the transparent fragments. (The pass was a full-screen raster pass
//! writing a multisampled depth texture until the H100 measured raster work there ~35x dearer
//! than compute: docs/bench/HISTORY.md.)

use crate::prepass::depth_target_msaa;
use crate::shaders::{FRAME, ShaderDef, VERTEX};
use crate::timing::GpuTimer;
use crate::{GpuContext, GpuScene, pipeline, shader_file};

/// Format of the prepass's per-sample depth ranges.
pub const RANGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// `prepass.depth` keeping each winning fragment's depth range over its pixel, and the
/// transparent surfaces' nearest and farthest depth ranges.
pub const PREPASS_RANGES: ShaderDef = ShaderDef {
    name: "prepass.depth",
    consts: &[],
    files: &[FRAME, VERTEX, shader_file!("common/depth_range.wgsl")],
};

/// `prepass.depth_bounds` at one sample a pixel.
pub const BOUNDS: ShaderDef = ShaderDef {
    name: "prepass.depth_bounds",
    consts: &[],
    files: &[
        shader_file!("common/depth_bounds_inputs.wgsl"),
        shader_file!("common/depth_bounds.wgsl"),
    ],
};

/// `prepass.depth_bounds` with MSAA: its inputs multisampled.
pub const BOUNDS_MSAA: ShaderDef = ShaderDef {
    name: "prepass.depth_bounds",
    consts: &[],
    files: &[
        shader_file!("common/depth_bounds_inputs_msaa.wgsl"),
        shader_file!("common/depth_bounds.wgsl"),
    ],
};

/// Format of the lookup bounds culling reads: a pixel's nearest lookup depth in x, its farthest
/// in y.
pub const BOUNDS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// The pipelines of the lookup bounds for one sample count and scene.
pub struct LookupBounds {
    /// MSAA: the prepass keeping depth ranges.
    prepass: Option<wgpu::RenderPipeline>,
    /// Transparent surfaces: their nearest and farthest depth.
    transparent: Option<[wgpu::RenderPipeline; 2]>,
    /// `prepass.depth_bounds` over the depth alone, and over the prepass's depth ranges.
    bounds: [wgpu::ComputePipeline; 2],
    layout: wgpu::BindGroupLayout,
    samples: u32,
}

/// A frame's targets of [`LookupBounds`].
pub struct BoundsTargets {
    ranges: wgpu::TextureView,
    near: wgpu::TextureView,
    far: wgpu::TextureView,
    /// The lookup bounds culling reads ([`BOUNDS_FORMAT`]).
    pub bounds: wgpu::Texture,
    group: wgpu::BindGroup,
    /// Bytes of its targets.
    pub bytes: u64,
}

impl LookupBounds {
    /// The pipelines for `scene` (its transparent surfaces, if any) at `samples` samples a
    /// pixel.
    pub fn new(ctx: &GpuContext, scene: &GpuScene, samples: u32) -> Self {
        let d = &ctx.device;
        let module = PREPASS_RANGES.create(d);
        let raster = |label, entry, targets: &[Option<wgpu::ColorTargetState>], test| {
            pipeline::raster_msaa(
                d,
                label,
                &module,
                &[&scene.layout],
                Some((entry, targets)),
                test,
                samples,
            )
        };
        let prepass = (samples > 1).then(|| {
            raster(
                "prepass.depth",
                "fs_depth_range",
                &[pipeline::target(RANGE_FORMAT)],
                pipeline::DepthTest::WriteLess,
            )
        });
        let transparent = scene.has_transparent().then(|| {
            [
                raster(
                    "prepass.transparent_near",
                    "fs_transparent_near",
                    &[],
                    pipeline::DepthTest::WriteLess,
                ),
                raster(
                    "prepass.transparent_far",
                    "fs_transparent_far",
                    &[],
                    pipeline::DepthTest::WriteGreater,
                ),
            ]
        });
        let compute = wgpu::ShaderStages::COMPUTE;
        let multisampled = samples > 1;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("prepass.depth_bounds"),
            entries: &[
                pipeline::entry(
                    0,
                    compute,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled,
                    },
                ),
                pipeline::entry(1, compute, pipeline::depth_texture(samples)),
                pipeline::entry(2, compute, pipeline::depth_texture(samples)),
                pipeline::entry(3, compute, pipeline::depth_texture(samples)),
                pipeline::entry(
                    4,
                    compute,
                    wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: BOUNDS_FORMAT,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                ),
            ],
        });
        let pipeline_layout = pipeline::layout(d, BOUNDS.name, &[&layout]);
        // With MSAA, one pipeline over the forward prepass's depth ranges and one over the
        // depth alone (deferred's G-buffer keeps no ranges); without, over the depth.
        let module = if multisampled { &BOUNDS_MSAA } else { &BOUNDS }.create(d);
        let bounds_with = |ranges: bool| {
            let on = |b: bool| f64::from(u8::from(b));
            let mut constants = vec![
                ("RANGES", on(ranges)),
                ("TRANSPARENT", on(scene.has_transparent())),
            ];
            if multisampled {
                constants.push(("DEPTH_SAMPLES", f64::from(samples)));
            }
            let options = wgpu::PipelineCompilationOptions {
                constants: &constants,
                ..Default::default()
            };
            pipeline::compute_with(d, &module, &pipeline_layout, "depth_bounds", &options)
        };
        let bounds = [bounds_with(false), bounds_with(multisampled)];
        Self {
            prepass,
            transparent,
            bounds,
            layout,
            samples,
        }
    }

    /// Whether the forward prepass is this one's ([`LookupBounds::encode_prepass`]: with MSAA).
    pub fn has_prepass(&self) -> bool {
        self.prepass.is_some()
    }

    /// The targets of a `width` x `height` frame whose depth buffer is `depth`; with `ranges`
    /// (forward with MSAA) the prepass's depth ranges.
    pub fn targets(
        &self,
        ctx: &GpuContext,
        (width, height): (u32, u32),
        depth: &wgpu::Texture,
        ranges: bool,
    ) -> BoundsTargets {
        let d = &ctx.device;
        let samples = self.samples;
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let depth_only = |t: &wgpu::Texture| {
            t.create_view(&wgpu::TextureViewDescriptor {
                aspect: wgpu::TextureAspect::DepthOnly,
                ..Default::default()
            })
        };
        // Where a target is not drawn (no MSAA: no ranges; no transparent surfaces: no
        // near and far), a 1 x 1 one (or the depth buffer) stands in for its binding.
        let with_ranges = ranges && self.prepass.is_some();
        let (rw, rh) = if with_ranges { (width, height) } else { (1, 1) };
        let ranges = view(&pipeline::texture_2d_msaa(
            d,
            "prepass.depth_ranges",
            (rw, rh),
            RANGE_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            samples,
        ));
        let transparent = self.transparent.is_some();
        let (near, far) = if transparent {
            (
                depth_target_msaa(ctx, width, height, samples),
                depth_target_msaa(ctx, width, height, samples),
            )
        } else {
            (depth.clone(), depth.clone())
        };
        let bounds = pipeline::texture_2d(
            d,
            "prepass.depth_bounds",
            (width, height),
            BOUNDS_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        let group = pipeline::group(
            d,
            "prepass.depth_bounds",
            &self.layout,
            &[
                wgpu::BindingResource::TextureView(&ranges),
                wgpu::BindingResource::TextureView(&depth_only(depth)),
                wgpu::BindingResource::TextureView(&depth_only(&near)),
                wgpu::BindingResource::TextureView(&depth_only(&far)),
                wgpu::BindingResource::TextureView(&view(&bounds)),
            ],
        );
        let pixels = u64::from(width) * u64::from(height);
        let bytes = pixels
            * (8 + if with_ranges {
                u64::from(samples) * 8
            } else {
                0
            } + if transparent {
                u64::from(samples) * 8
            } else {
                0
            });
        BoundsTargets {
            bounds,
            ranges,
            near: view(&near),
            far: view(&far),
            group,
            bytes,
        }
    }

    /// With MSAA, the depth prepass into `depth` keeping the depth ranges (in place of
    /// `DepthPrepass::encode`).
    pub fn encode_prepass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        depth: &wgpu::TextureView,
        targets: &BoundsTargets,
        timer: &mut GpuTimer,
    ) {
        let Some(prepass) = &self.prepass else {
            return;
        };
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
            depth_stencil_attachment: Some(depth_attachment(depth, 1.0)),
            timestamp_writes: timer.render_pass("prepass.depth"),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(prepass);
        scene.draw(&mut pass);
    }

    /// After the geometry pass: the transparent surfaces' nearest and farthest depth, where the
    /// scene has some, then `prepass.depth_bounds`, over the depth ranges of
    /// [`LookupBounds::encode_prepass`] where it ran (`ranges`).
    pub fn encode_bounds(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        targets: &BoundsTargets,
        ranges: bool,
        timer: &mut GpuTimer,
    ) {
        if let Some([near, far]) = &self.transparent {
            for (label, pipeline, view, clear) in [
                ("prepass.transparent_near", near, &targets.near, 1.0),
                ("prepass.transparent_far", far, &targets.far, 0.0),
            ] {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some(label),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(depth_attachment(view, clear)),
                    timestamp_writes: timer.render_pass(label),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(pipeline);
                scene.draw_transparent(&mut pass);
            }
        }
        let (width, height) = (targets.bounds.width(), targets.bounds.height());
        pipeline::dispatch(
            enc,
            timer,
            BOUNDS.name,
            &self.bounds[usize::from(ranges && self.prepass.is_some())],
            &[&targets.group],
            (width.div_ceil(8), height.div_ceil(8)),
        );
    }
}

/// A depth attachment cleared to `clear` and stored.
fn depth_attachment(
    view: &wgpu::TextureView,
    clear: f32,
) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(clear),
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: None,
    }
}
