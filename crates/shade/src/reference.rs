//! The brute-force reference renderer (`shade.reference`): `prepass.depth`, then forward
//! shading of every light at every covered pixel, into an `Rgba32Float` HDR target, with the
//! surface position and shading normal of every pixel for the CPU oracles. With MSAA
//! ([`ReferenceRenderer::with_samples`]) a pixel one fragment covers entirely is shaded once,
//! at its centre, and every other pixel (an edge) at each covered sample's own position on its
//! triangle (`shade.reference_samples`), then resolved: what deferred lighting and the
//! visibility buffer compute, on any GPU. Forward shading with MSAA shades an edge's fragments once each, at a
//! centroid of the implementation's choice, and is measured against it (docs/STRATEGIES.md,
//! "MSAA").

use manylights_gpu::pipeline;
use manylights_gpu::prepass::{DepthPrepass, depth_target_msaa};
use manylights_gpu::shaders::{BRDF, BVH, FRAME, LIGHT, SCENE, SHADING, ShaderDef, VERTEX};
use manylights_gpu::timing::{GpuTimer, PassTiming};
use manylights_gpu::{GpuContext, GpuError, GpuScene, readback, shader_file};

use crate::HdrImage;
use crate::kinds::Shadows;

/// The reference shader.
pub const SHADER: ShaderDef = ShaderDef {
    name: "shade.reference",
    consts: &[],
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        BVH,
        BRDF,
        SHADING,
        VERTEX,
        shader_file!("render/reference.wgsl"),
    ],
};

/// `shade.reference_samples`: the MSAA reference's image at each sample, its edge samples lit
/// on their triangles as the visibility buffer lights them.
pub const SAMPLES_SHADER: ShaderDef = ShaderDef {
    name: "shade.reference_samples",
    consts: &[],
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        BVH,
        BRDF,
        SHADING,
        VERTEX,
        crate::shaders::SURFACE,
        shader_file!("render/reference_samples.wgsl"),
    ],
};

const HDR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// What one reference render returns.
#[derive(Clone, Debug)]
pub struct ReferenceFrame {
    /// Linear HDR radiance (alpha 1 where covered, 0 elsewhere).
    pub color: HdrImage,
    /// World position (w = 1 where covered).
    pub position: HdrImage,
    /// Shading normal (xyz), turned towards the viewer.
    pub normal: HdrImage,
    /// Depth buffer of the prepass, one f32 per pixel (1.0 = far plane / background); empty
    /// with MSAA (a multisampled texture cannot be copied: `Culler::depth_samples` reads its
    /// samples). With MSAA, `position` and `normal` are resolved: averages at edges.
    pub depth: Vec<f32>,
    /// GPU time per pass; `None` when the adapter has no timestamp queries.
    pub timings: Option<Vec<PassTiming>>,
}

/// With MSAA: the colour, position and normal targets multisampled, and the image at each
/// sample (the per-sample pass's, which the glass is blended into).
fn msaa_targets(ctx: &GpuContext, size: (u32, u32), samples: u32) -> [wgpu::TextureView; 4] {
    [
        "reference.color_msaa",
        "reference.position_msaa",
        "reference.normal_msaa",
        "reference.color_samples",
    ]
    .map(|label| {
        pipeline::texture_2d_msaa(
            &ctx.device,
            label,
            size,
            HDR,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            samples,
        )
        .create_view(&Default::default())
    })
}

/// A reference render pass: its colour attachments are (view, where it resolves, whether it is
/// cleared); `transparent`: it draws the transparent surfaces.
struct ReferencePass<'a> {
    label: &'a str,
    pipeline: &'a wgpu::RenderPipeline,
    groups: Vec<wgpu::BindGroup>,
    targets: Vec<(&'a wgpu::TextureView, Option<&'a wgpu::TextureView>, bool)>,
    transparent: bool,
}

impl ReferencePass<'_> {
    /// Encodes the pass over the depth buffer `depth`, timed.
    fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        scene: &GpuScene,
        depth: &wgpu::TextureView,
    ) {
        let attachments: Vec<_> = self
            .targets
            .iter()
            .map(|&(view, resolve_target, clear)| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target,
                    ops: wgpu::Operations {
                        load: if clear {
                            wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
                        } else {
                            wgpu::LoadOp::Load
                        },
                        store: wgpu::StoreOp::Store,
                    },
                })
            })
            .collect();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(self.label),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.render_pass(self.label),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(self.pipeline);
        for (k, group) in self.groups.iter().enumerate() {
            pass.set_bind_group(k as u32 + 1, group, &[]);
        }
        if self.transparent {
            scene.draw_transparent(&mut pass);
        } else {
            scene.draw(&mut pass);
        }
    }
}

/// `shade.reference_samples` and the layouts of what it reads: the opaque pass's multisampled
/// colour and position (group 1), the scene's vertices and indices (group 2, as the visibility
/// buffer's lighting binds them).
struct PerSample {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    geometry: wgpu::BindGroupLayout,
}

impl PerSample {
    fn new(ctx: &GpuContext, scene: &GpuScene, samples: u32, constants: &[(&str, f64)]) -> Self {
        let texture = wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: true,
        };
        let fragment = wgpu::ShaderStages::FRAGMENT;
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            ctx.device
                .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(label),
                    entries,
                })
        };
        let storage = wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let inputs = layout(
            "shade.reference_samples",
            &[
                pipeline::entry(0, fragment, texture),
                pipeline::entry(1, fragment, texture),
            ],
        );
        let geometry = layout(
            "shade.reference_samples.geometry",
            &[
                pipeline::entry(4, fragment, storage),
                pipeline::entry(5, fragment, storage),
            ],
        );
        let pipeline = pipeline::raster_with(
            &ctx.device,
            "shade.reference_samples",
            &SAMPLES_SHADER.create(&ctx.device),
            &[&scene.layout, &inputs, &geometry],
            Some(("fs_reference_samples", &[pipeline::target(HDR)])),
            pipeline::DepthTest::Equal,
            samples,
            constants,
        );
        Self {
            pipeline,
            layout: inputs,
            geometry,
        }
    }
}

/// Reference renderer pipelines for one uploaded scene layout.
pub struct ReferenceRenderer {
    prepass: DepthPrepass,
    pipeline: wgpu::RenderPipeline,
    /// The surfaces alone, no light evaluated (`fs_surface`).
    surface: wgpu::RenderPipeline,
    /// Transparent surfaces, blended into the colour target.
    transparent: wgpu::RenderPipeline,
    /// With MSAA: `shade.reference_samples`, the image at each sample.
    per_sample: Option<PerSample>,
    samples: u32,
    shadows: Shadows,
}

impl ReferenceRenderer {
    /// Builds the pipelines.
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Self {
        Self::build(ctx, scene, 1, Shadows::Off)
    }

    /// The renderer shading with `shadows` (its pipelines built again unless it already
    /// does): `Shadows::Exact`, a shadow ray for every light that adds radiance at a pixel (the
    /// shadowed reference at the scene's light ranges; its frames need the scene's BVH,
    /// `GpuScene::build_bvh`). A reference traces every light's ray: `Stochastic` shades as
    /// `Exact` ([`Shadows::truth`]).
    pub fn with_shadows(self, ctx: &GpuContext, scene: &GpuScene, shadows: Shadows) -> Self {
        let shadows = shadows.truth();
        if shadows == self.shadows {
            return self;
        }
        Self::build(ctx, scene, self.samples, shadows)
    }

    /// Whether its shading casts shadow rays.
    pub fn shadows(&self) -> Shadows {
        self.shadows
    }

    /// The pipelines for frames of `samples` samples a pixel (MSAA where more than one); an
    /// error names the counts the device supports. With MSAA the edge samples are lit on their
    /// triangles, which needs `@builtin(primitive_index)`.
    pub fn with_samples(
        ctx: &GpuContext,
        scene: &GpuScene,
        samples: u32,
    ) -> Result<Self, GpuError> {
        ctx.check_msaa_of(samples, &[manylights_gpu::prepass::DEPTH_FORMAT, HDR])?;
        if samples > 1 && !ctx.features.primitive_index {
            return Err(GpuError::Unsupported(format!(
                "the reference with MSAA lights an edge's samples on their triangles, which needs \
                 `@builtin(primitive_index)` (wgpu feature PRIMITIVE_INDEX; on Vulkan the \
                 geometryShader feature), which adapter {} does not offer: use one sample a pixel",
                ctx.info.name
            )));
        }
        Ok(Self::build(ctx, scene, samples, Shadows::Off))
    }

    fn build(ctx: &GpuContext, scene: &GpuScene, samples: u32, shadows: Shadows) -> Self {
        let module = SHADER.create(&ctx.device);
        let t = pipeline::target(HDR);
        let constants = shadows.constants();
        let pipeline = pipeline::raster_with(
            &ctx.device,
            "shade.reference",
            &module,
            &[&scene.layout],
            Some(("fs_reference", &[t.clone(), t.clone(), t.clone()])),
            pipeline::DepthTest::Equal,
            samples,
            &constants,
        );
        let surface = pipeline::raster_msaa(
            &ctx.device,
            "shade.reference_surface",
            &module,
            &[&scene.layout],
            Some(("fs_surface", &[t.clone(), t.clone(), t])),
            pipeline::DepthTest::Equal,
            samples,
        );
        // The position and normal targets keep the opaque surface's (nothing written).
        let masked = Some(wgpu::ColorTargetState {
            format: HDR,
            blend: None,
            write_mask: wgpu::ColorWrites::empty(),
        });
        // With MSAA the glass is blended into the per-sample image alone (the position and
        // normal are resolved by the opaque pass).
        let glass = [pipeline::blended_target(HDR), masked.clone(), masked];
        let transparent = pipeline::raster_with(
            &ctx.device,
            "shade.reference_transparent",
            &module,
            &[&scene.layout],
            Some((
                "fs_reference_transparent",
                &glass[..if samples > 1 { 1 } else { 3 }],
            )),
            pipeline::DepthTest::Less,
            samples,
            &constants,
        );
        let per_sample = (samples > 1).then(|| PerSample::new(ctx, scene, samples, &constants));
        Self {
            prepass: DepthPrepass::with_samples(ctx, scene, samples),
            pipeline,
            surface,
            transparent,
            per_sample,
            samples,
            shadows,
        }
    }

    /// Renders with the infinite-range falloff (no radius cut-off): the reference that measures
    /// what the cut-off itself costs. Sets the frame for `camera` at `width` x `height`, and
    /// restores the normal frame afterwards.
    pub fn render_infinite(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        camera: &manylights_scene::Camera,
        width: u32,
        height: u32,
    ) -> Result<ReferenceFrame, GpuError> {
        scene.set_view(
            ctx,
            camera,
            width,
            height,
            manylights_gpu::layout::FRAME_FLAG_INFINITE_RANGE,
        );
        let frame = self.render(ctx, scene, width, height);
        scene.set_view(ctx, camera, width, height, 0);
        frame
    }

    /// Renders `scene` (whose frame uniform is set for `width` x `height`) and reads back
    /// everything.
    pub fn render(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        width: u32,
        height: u32,
    ) -> Result<ReferenceFrame, GpuError> {
        self.render_with(ctx, scene, width, height, &self.pipeline)
    }

    /// The surfaces of the frame alone (`shade.reference_surface`: position, shading normal
    /// and material index a pixel; colour 0 where covered, no light evaluated): the input of
    /// [`crate::InfiniteReference`] where the windowed reference is not wanted. Transparent
    /// surfaces are not drawn.
    pub fn surfaces(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        width: u32,
        height: u32,
    ) -> Result<ReferenceFrame, GpuError> {
        self.render_with(ctx, scene, width, height, &self.surface)
    }

    /// The sample count the pipelines were built for.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    fn render_with(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        width: u32,
        height: u32,
        opaque: &wgpu::RenderPipeline,
    ) -> Result<ReferenceFrame, GpuError> {
        let surfaces_only = std::ptr::eq(opaque, &self.surface);
        ctx.check_resolution(width, height)?;
        if !surfaces_only {
            self.shadows.check_scene(scene, "the reference")?;
        }
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let target = |label| pipeline::texture_2d(&ctx.device, label, (width, height), HDR, usage);
        let (color, position, normal) = (
            target("reference.color"),
            target("reference.position"),
            target("reference.normal"),
        );
        let samples = self.samples;
        let depth = depth_target_msaa(ctx, width, height, samples);
        let views = [&color, &position, &normal].map(|t| t.create_view(&Default::default()));
        let msaa = (samples > 1).then(|| msaa_targets(ctx, (width, height), samples));
        let depth_view = depth.create_view(&Default::default());
        let mut timer = GpuTimer::new(ctx, 4);
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("reference"),
            });
        self.prepass
            .encode(&mut encoder, scene, &depth_view, &mut timer);
        let transparent = scene.has_transparent() && !surfaces_only;
        let label = if surfaces_only {
            "shade.reference_surface"
        } else {
            "shade.reference"
        };
        let per_sample = self.per_sample.as_ref().filter(|_| !surfaces_only);
        let mut passes: Vec<ReferencePass<'_>> = Vec::new();
        match (&msaa, per_sample) {
            (None, _) => {
                let all = |clear| views.iter().map(|v| (v, None, clear)).collect::<Vec<_>>();
                passes.push(ReferencePass {
                    label,
                    pipeline: opaque,
                    groups: Vec::new(),
                    targets: all(true),
                    transparent: false,
                });
                if transparent {
                    passes.push(ReferencePass {
                        label: "shade.reference_transparent",
                        pipeline: &self.transparent,
                        groups: Vec::new(),
                        targets: all(false),
                        transparent: true,
                    });
                }
            }
            // The surfaces alone: drawn multisampled and resolved.
            (Some(ms), None) => {
                passes.push(ReferencePass {
                    label,
                    pipeline: opaque,
                    groups: Vec::new(),
                    targets: (0..3).map(|k| (&ms[k], Some(&views[k]), true)).collect(),
                    transparent: false,
                });
            }
            // The fragments (their colour kept for the per-sample pass, the position and
            // normal resolved), the image at each sample, the glass over it, resolved.
            (Some(ms), Some(ps)) => {
                passes.push(ReferencePass {
                    label,
                    pipeline: opaque,
                    groups: Vec::new(),
                    targets: vec![
                        (&ms[0], None, true),
                        (&ms[1], Some(&views[1]), true),
                        (&ms[2], Some(&views[2]), true),
                    ],
                    transparent: false,
                });
                let group = pipeline::group(
                    &ctx.device,
                    "shade.reference_samples",
                    &ps.layout,
                    &[
                        wgpu::BindingResource::TextureView(&ms[0]),
                        wgpu::BindingResource::TextureView(&ms[1]),
                    ],
                );
                // Bindings 4 and 5, as surface.wgsl declares them.
                let geometry = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("shade.reference_samples.geometry"),
                    layout: &ps.geometry,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 4,
                            resource: scene.vertices.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 5,
                            resource: scene.indices.as_entire_binding(),
                        },
                    ],
                });
                let resolve = (!transparent).then_some(&views[0]);
                passes.push(ReferencePass {
                    label: "shade.reference_samples",
                    pipeline: &ps.pipeline,
                    groups: vec![group, geometry],
                    targets: vec![(&ms[3], resolve, true)],
                    transparent: false,
                });
                if transparent {
                    passes.push(ReferencePass {
                        label: "shade.reference_transparent",
                        pipeline: &self.transparent,
                        groups: Vec::new(),
                        targets: vec![(&ms[3], Some(&views[0]), false)],
                        transparent: true,
                    });
                }
            }
        }
        for pass in &passes {
            pass.encode(&mut encoder, &mut timer, scene, &depth_view);
        }
        timer.resolve(&mut encoder);
        ctx.submit_and_wait(encoder, "reference render")?;
        let read = |t: &wgpu::Texture| {
            readback::read_texture(ctx, t, wgpu::TextureAspect::All)
                .map(|b| HdrImage::from_bytes(width, height, &b))
        };
        let depth_bytes = if samples == 1 {
            readback::read_texture(ctx, &depth, wgpu::TextureAspect::DepthOnly)?
        } else {
            Vec::new()
        };
        Ok(ReferenceFrame {
            color: read(&color)?,
            position: read(&position)?,
            normal: read(&normal)?,
            depth: bytemuck::pod_collect_to_vec(&depth_bytes),
            timings: timer.read(ctx)?,
        })
    }
}
