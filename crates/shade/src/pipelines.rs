//! The pipelines of every backend (`Renderer::build`), from the shaders of [`crate::shaders`].

use manylights_cull::Culler;
use manylights_cull::shaders::{create_over_samples, sample_constants};
use manylights_gpu::lookup_bounds::LookupBounds;
use manylights_gpu::pipeline;
use manylights_gpu::prepass::DepthPrepass;
use manylights_gpu::{GpuContext, GpuScene};
use std::sync::OnceLock;

use crate::backends::{
    Backend, GB_MATERIAL, GB_NORMAL_DEPTH, GB_POSITION, HdrFormat, Renderer, VISIBILITY_ID,
};
use crate::kinds::{Shadows, VisibilityPass};
use crate::shaders::{
    DEFERRED, DEFERRED_MSAA, FORWARD, GBUFFER, GBUFFER_IDS, VISIBILITY, deferred_swaps,
};
pub use crate::shaders::{LIST_SHADING, SURFACE};

fn lists_entries(visibility: wgpu::ShaderStages) -> Vec<wgpu::BindGroupLayoutEntry> {
    vec![
        pipeline::entry(0, visibility, pipeline::UNIFORM),
        pipeline::entry(1, visibility, pipeline::storage(true)),
        pipeline::entry(2, visibility, pipeline::storage(true)),
    ]
}

fn texture(sample_type: wgpu::TextureSampleType, samples: u32) -> wgpu::BindingType {
    wgpu::BindingType::Texture {
        sample_type,
        view_dimension: wgpu::TextureViewDimension::D2,
        multisampled: samples > 1,
    }
}

impl Renderer {
    pub(crate) fn build(ctx: &GpuContext, scene: &GpuScene, samples: u32, hdr: HdrFormat) -> Self {
        let d = &ctx.device;
        let color = hdr.texture_format();
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            })
        };
        let compute = wgpu::ShaderStages::COMPUTE;
        let forward_lists = layout(
            "shade.forward.lists",
            &lists_entries(wgpu::ShaderStages::FRAGMENT),
        );
        let mut entries = lists_entries(compute);
        entries.push(pipeline::entry(
            3,
            compute,
            pipeline::depth_texture(samples),
        ));
        let deferred_lists = layout("shade.deferred.lists", &entries);
        // The visibility buffer's compute rasteriser: the depth an R32Float texture.
        let mut entries = lists_entries(compute);
        entries.push(pipeline::entry(
            3,
            compute,
            texture(wgpu::TextureSampleType::Float { filterable: false }, 1),
        ));
        let deferred_float_lists = layout("shade.deferred.float_lists", &entries);
        let float = || {
            texture(
                wgpu::TextureSampleType::Float { filterable: false },
                samples,
            )
        };
        let deferred_gbuffer = layout(
            "shade.deferred.gbuffer",
            &[
                pipeline::entry(0, compute, float()),
                pipeline::entry(1, compute, texture(wgpu::TextureSampleType::Uint, samples)),
                pipeline::entry(
                    2,
                    compute,
                    wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: color,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                ),
                // The stored position; with MSAA, the glass layer lighting composites.
                pipeline::entry(3, compute, float()),
                // The scene's vertices and indices, which the visibility buffer's lighting
                // interpolates.
                pipeline::entry(4, compute, pipeline::storage(true)),
                pipeline::entry(5, compute, pipeline::storage(true)),
            ],
        );
        // POINT_LIGHTS, STOCHASTIC_POINTS and BAND_POINTS (shading.wgsl) from the scene's path.
        let light_path = scene.light_path();
        let transparent = scene.has_transparent();
        let lookup_bounds =
            (samples > 1 || transparent).then(|| LookupBounds::new(ctx, scene, samples));
        let pipelines = Pipelines {
            device: d.clone(),
            scene_layout: scene.layout.clone(),
            samples,
            hdr,
            opaque_models: scene.opaque_models.iter().map(|&(m, _)| m).collect(),
            opaque_model_mask: scene.opaque_model_mask(),
            lights: light_path.constants(),
            shadows: Shadows::Off,
            glass_layer: samples > 1 && transparent,
            gbuffer_ids: samples > 1 && ctx.features.primitive_index,
            forward_lists,
            deferred_lists,
            deferred_float_lists,
            deferred_gbuffer,
            forward_module: OnceLock::new(),
            deferred_module: OnceLock::new(),
            deferred_float_module: OnceLock::new(),
            forward: OnceLock::new(),
            glass: OnceLock::new(),
            naive: OnceLock::new(),
            deferred: Default::default(),
        };
        Self {
            culler: if lookup_bounds.is_some() {
                Culler::with_bounds(ctx, scene, samples)
            } else {
                Culler::with_samples(ctx, scene, samples)
            },
            samples,
            hdr,
            light_path,
            prepass: DepthPrepass::with_samples(ctx, scene, samples),
            transparent,
            visibility_pass: VisibilityPass::default(),
            int64_atomics: ctx.features.int64_atomics,
            compute_visibility: OnceLock::new(),
            shadows: Shadows::Off,
            lookup_bounds,
            pipelines,
        }
    }
}

/// Forward's pipelines over the opaque triangles: a pipeline a material model, each shading its
/// model alone (`MATERIAL_MODELS`, brdf.wgsl), drawn a model at a time.
pub(crate) struct Forward {
    /// Over a list a bin (a tile's, a cluster's).
    pub bins: Vec<wgpu::RenderPipeline>,
    /// Over z-binning's lists.
    pub zbin: Vec<wgpu::RenderPipeline>,
}

/// `shade.forward_transparent` over transparent surfaces (a list a bin, and z-binning's).
pub(crate) struct Glass {
    /// Blended into the colour target: forward's, and deferred's after its lighting.
    pub blended: [wgpu::RenderPipeline; 2],
    /// Deferred with MSAA: into a layer of their own ([`crate::backends::Loads::GlassLayer`]),
    /// which the lighting composites.
    pub layer: Option<[wgpu::RenderPipeline; 2]>,
}

/// Naive forward: `shade.naive`, and `shade.naive_transparent` blended over it.
pub(crate) struct Naive {
    pub opaque: wgpu::RenderPipeline,
    pub transparent: wgpu::RenderPipeline,
}

/// What deferred lighting reads a pixel's surface from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Surfaces {
    /// A G-buffer, the position rebuilt from its view depth.
    Rebuilt,
    /// A G-buffer with the position stored (no MSAA).
    Stored,
    /// A visibility buffer: each pixel's triangle, interpolated at the pixel.
    Visibility,
    /// A visibility buffer of the compute rasteriser (`crate::vis_compute`): the same, its
    /// depth read from an `R32Float` texture.
    VisibilityCompute,
}

impl Surfaces {
    /// Those of `backend` (one whose lights are shaded in compute), `compute` where the
    /// visibility buffer is rasterised in compute.
    pub fn of(backend: Backend, compute: bool) -> Self {
        match backend {
            Backend::DeferredStoredPosition => Self::Stored,
            Backend::Visibility if compute => Self::VisibilityCompute,
            Backend::Visibility => Self::Visibility,
            _ => Self::Rebuilt,
        }
    }

    /// The raster pass that writes them (none for the compute rasteriser's).
    pub fn pass_name(self) -> &'static str {
        match self {
            Self::Rebuilt | Self::Stored => "shade.gbuffer",
            Self::Visibility => "shade.visibility",
            Self::VisibilityCompute => "shade.visibility_compute",
        }
    }
}

/// A deferred backend's G-buffer (or visibility buffer) pass and lighting passes, a pass a form
/// of lists.
pub(crate) struct Deferred {
    /// The raster pass: `shade.gbuffer` or `shade.visibility`; none where the visibility
    /// buffer is rasterised in compute (the renderer's `ComputeVisibility`).
    pub gbuffer: Option<wgpu::RenderPipeline>,
    /// Over a list a bin.
    pub bins: wgpu::ComputePipeline,
    /// Over z-binning's lists; then the same in rounds (`shade_zbin_rounds_group`, for a
    /// point-light pipeline with at least `ZBIN_ROUNDS_MIN_LIGHTS` lights; with MSAA twice the
    /// one pipeline).
    pub zbin: [wgpu::ComputePipeline; 2],
    /// Over a list a tile of a multiple of 8 pixels.
    pub tiles: wgpu::ComputePipeline,
    /// Over a list a cluster, a workgroup's slices' lists one after another
    /// (`ListForm::Clusters`).
    pub clusters: wgpu::ComputePipeline,
}

/// Every backend's pipelines, each family built at its first use: a renderer that never draws
/// a backend need not compile it (on lavapipe a renderer's every pipeline took 1.96 s to
/// build, most tests draw one or two backends).
pub(crate) struct Pipelines {
    device: wgpu::Device,
    scene_layout: wgpu::BindGroupLayout,
    samples: u32,
    hdr: HdrFormat,
    /// With MSAA, the G-buffer holds each sample's triangle id in the material's place
    /// (`GBUFFER_IDS`): where the device has `PRIMITIVE_INDEX`.
    gbuffer_ids: bool,
    /// The material model of each of the scene's opaque draws (`GpuScene::opaque_models`).
    opaque_models: Vec<u32>,
    opaque_model_mask: u32,
    /// `POINT_LIGHTS`, `STOCHASTIC_POINTS` and `BAND_POINTS`, as the renderer was built for.
    lights: [(&'static str, f64); 3],
    /// Whether the shading casts shadow rays (`SHADOWS`, shading.wgsl).
    shadows: Shadows,
    /// With MSAA over transparent surfaces: deferred composites them from a layer of their own.
    glass_layer: bool,
    pub forward_lists: wgpu::BindGroupLayout,
    pub deferred_lists: wgpu::BindGroupLayout,
    /// As `deferred_lists`, the depth an `R32Float` texture (`Surfaces::VisibilityCompute`).
    pub deferred_float_lists: wgpu::BindGroupLayout,
    pub deferred_gbuffer: wgpu::BindGroupLayout,
    forward_module: OnceLock<wgpu::ShaderModule>,
    deferred_module: OnceLock<wgpu::ShaderModule>,
    /// The deferred lighting module reading its depth from an `R32Float` texture.
    deferred_float_module: OnceLock<wgpu::ShaderModule>,
    forward: OnceLock<Forward>,
    glass: OnceLock<Glass>,
    naive: OnceLock<Naive>,
    /// By [`Surfaces`], in its order.
    deferred: [OnceLock<Deferred>; 4],
}

impl Pipelines {
    /// The same pipelines, none built yet, shading with `shadows`.
    pub fn with_shadows(&mut self, shadows: Shadows) {
        self.shadows = shadows;
        self.forward = OnceLock::new();
        self.glass = OnceLock::new();
        self.naive = OnceLock::new();
        self.deferred = Default::default();
    }

    /// Builds what a frame of `backend` draws with, where not built yet: before a frame's
    /// encoder opens, so that its recording time holds no compiling.
    pub fn prepare(&self, backend: Backend, transparent: bool, compute: bool) {
        match backend {
            Backend::Forward => {
                self.forward();
            }
            Backend::Deferred | Backend::DeferredStoredPosition | Backend::Visibility => {
                self.deferred(Surfaces::of(backend, compute));
            }
            Backend::NaiveForward => {
                self.naive();
                return;
            }
        }
        if transparent {
            self.glass();
        }
    }

    /// The shading passes' override constants: the light path's, `SHADOWS` and `SHADOW_RAYS`.
    fn shading_constants(&self) -> [(&'static str, f64); 5] {
        let [a, b, c] = self.lights;
        let [s, k] = self.shadows.constants();
        [a, b, c, s, k]
    }

    fn color(&self) -> wgpu::TextureFormat {
        self.hdr.texture_format()
    }

    fn forward_module(&self) -> &wgpu::ShaderModule {
        self.forward_module
            .get_or_init(|| create_over_samples(&self.device, &FORWARD, self.samples, &[]))
    }

    /// A forward raster pipeline over the lists, of `entry` into `targets`.
    fn forward_raster(
        &self,
        label: &str,
        entry: &str,
        targets: &[Option<wgpu::ColorTargetState>],
        depth: pipeline::DepthTest,
        constants: &[(&str, f64)],
    ) -> wgpu::RenderPipeline {
        pipeline::raster_with(
            &self.device,
            label,
            self.forward_module(),
            &[&self.scene_layout, &self.forward_lists],
            Some((entry, targets)),
            depth,
            self.samples,
            &[constants, &sample_constants(self.samples)].concat(),
        )
    }

    pub fn forward(&self) -> &Forward {
        self.forward.get_or_init(|| {
            let by_model = |entry| {
                self.opaque_models
                    .iter()
                    .map(|&model| {
                        let mut constants = vec![("MATERIAL_MODELS", f64::from(1u32 << model))];
                        constants.extend(self.shading_constants());
                        self.forward_raster(
                            "shade.forward",
                            entry,
                            &[pipeline::target(self.color())],
                            pipeline::DepthTest::Equal,
                            &constants,
                        )
                    })
                    .collect()
            };
            Forward {
                bins: by_model("fs_forward"),
                zbin: by_model("fs_forward_zbin"),
            }
        })
    }

    pub fn glass(&self) -> &Glass {
        self.glass.get_or_init(|| {
            let with = |target: Option<wgpu::ColorTargetState>| {
                ["fs_forward_transparent", "fs_forward_transparent_zbin"].map(|entry| {
                    self.forward_raster(
                        "shade.forward_transparent",
                        entry,
                        std::slice::from_ref(&target),
                        pipeline::DepthTest::Less,
                        &self.shading_constants(),
                    )
                })
            };
            Glass {
                blended: with(pipeline::blended_target(self.color())),
                layer: self
                    .glass_layer
                    .then(|| with(pipeline::layer_target(self.color()))),
            }
        })
    }

    pub fn naive(&self) -> &Naive {
        self.naive.get_or_init(|| {
            let raster = |label, entry, target, depth| {
                pipeline::raster_with(
                    &self.device,
                    label,
                    self.forward_module(),
                    &[&self.scene_layout],
                    Some((entry, &[target])),
                    depth,
                    self.samples,
                    &[
                        &sample_constants(self.samples)[..],
                        &self.shadows.constants(),
                    ]
                    .concat(),
                )
            };
            Naive {
                opaque: raster(
                    "shade.naive",
                    "fs_naive",
                    pipeline::target(self.color()),
                    pipeline::DepthTest::Equal,
                ),
                transparent: raster(
                    "shade.naive_transparent",
                    "fs_naive_transparent",
                    pipeline::blended_target(self.color()),
                    pipeline::DepthTest::Less,
                ),
            }
        })
    }

    /// The deferred lighting module (with MSAA, `DEFERRED_MSAA`).
    fn deferred_module(&self) -> &wgpu::ShaderModule {
        self.deferred_module.get_or_init(|| {
            let def = if self.samples > 1 {
                &DEFERRED_MSAA
            } else {
                &DEFERRED
            };
            create_over_samples(
                &self.device,
                def,
                self.samples,
                &deferred_swaps(self.hdr, false),
            )
        })
    }

    /// The deferred lighting module over a depth in an `R32Float` texture (one sample).
    fn deferred_float_module(&self) -> &wgpu::ShaderModule {
        self.deferred_float_module
            .get_or_init(|| DEFERRED.create_swapped(&self.device, &deferred_swaps(self.hdr, true)))
    }

    /// A deferred backend's pipelines over `surfaces` (a stored position takes no MSAA:
    /// `Renderer::render` says so).
    pub fn deferred(&self, surfaces: Surfaces) -> &Deferred {
        self.deferred[surfaces as usize].get_or_init(|| self.build_deferred(surfaces))
    }

    /// The raster pass that writes `surfaces` (none: the compute rasteriser's).
    fn surfaces_pass(&self, surfaces: Surfaces) -> Option<wgpu::RenderPipeline> {
        let d = &self.device;
        let g0 = &self.scene_layout;
        let depth = pipeline::DepthTest::WriteLess;
        Some(match surfaces {
            Surfaces::VisibilityCompute => return None,
            Surfaces::Rebuilt => pipeline::raster_msaa(
                d,
                "shade.gbuffer",
                &if self.gbuffer_ids {
                    GBUFFER_IDS.create(d)
                } else {
                    GBUFFER.create(d)
                },
                &[g0],
                Some((
                    if self.gbuffer_ids {
                        "fs_gbuffer_ids"
                    } else {
                        "fs_gbuffer"
                    },
                    &[
                        pipeline::target(GB_NORMAL_DEPTH),
                        pipeline::target(GB_MATERIAL),
                    ],
                )),
                depth,
                self.samples,
            ),
            Surfaces::Stored => pipeline::raster(
                d,
                "shade.gbuffer",
                &GBUFFER.create(d),
                &[g0],
                Some((
                    "fs_gbuffer_stored",
                    &[
                        pipeline::target(GB_NORMAL_DEPTH),
                        pipeline::target(GB_MATERIAL),
                        pipeline::target(GB_POSITION),
                    ],
                )),
                depth,
            ),
            Surfaces::Visibility => pipeline::raster_msaa(
                d,
                "shade.visibility",
                &VISIBILITY.create(d),
                &[g0],
                Some(("fs_visibility", &[pipeline::target(VISIBILITY_ID)])),
                depth,
                self.samples,
            ),
        })
    }

    fn build_deferred(&self, surfaces: Surfaces) -> Deferred {
        let d = &self.device;
        let g0 = &self.scene_layout;
        let gbuffer = self.surfaces_pass(surfaces);
        let float = surfaces == Surfaces::VisibilityCompute;
        let lists = if float {
            &self.deferred_float_lists
        } else {
            &self.deferred_lists
        };
        let layout = pipeline::layout(d, "shade.deferred", &[g0, lists, &self.deferred_gbuffer]);
        // One lighting pass over every model of the opaque triangles, branching on each
        // pixel's. With MSAA, GLASS: the lighting composites the glass layer over each sample.
        let mut constants = vec![("MATERIAL_MODELS", f64::from(self.opaque_model_mask))];
        constants.extend(self.shading_constants());
        constants.push((
            "VISIBILITY",
            f64::from(u8::from(matches!(
                surfaces,
                Surfaces::Visibility | Surfaces::VisibilityCompute
            ))),
        ));
        if self.samples > 1 {
            constants.push(("GLASS", f64::from(u8::from(self.glass_layer))));
            constants.push((
                "GBUFFER_IDS",
                f64::from(u8::from(self.gbuffer_ids && surfaces == Surfaces::Rebuilt)),
            ));
        }
        if !float {
            constants.extend(sample_constants(self.samples));
        }
        let options = wgpu::PipelineCompilationOptions {
            constants: &constants,
            ..Default::default()
        };
        let module = if float {
            self.deferred_float_module()
        } else {
            self.deferred_module()
        };
        let compute = |entry: &str| pipeline::compute_with(d, module, &layout, entry, &options);
        if self.samples > 1 {
            // One pass for the lists a bin (a tile's or a cluster's too) and one for z-binning's,
            // the position rebuilt.
            let bins = compute("deferred_shade_msaa");
            let zbin = compute("deferred_shade_msaa_zbin");
            return Deferred {
                gbuffer,
                tiles: bins.clone(),
                clusters: bins.clone(),
                bins,
                zbin: [zbin.clone(), zbin],
            };
        }
        let s = if surfaces == Surfaces::Stored {
            "_stored"
        } else {
            ""
        };
        Deferred {
            gbuffer,
            bins: compute(&format!("deferred_shade{s}")),
            zbin: [
                compute(&format!("deferred_shade{s}_zbin")),
                compute(&format!("deferred_shade{s}_zbin_rounds")),
            ],
            tiles: compute(&format!("deferred_shade{s}_tiles")),
            clusters: compute(&format!("deferred_shade{s}_clusters")),
        }
    }
}
