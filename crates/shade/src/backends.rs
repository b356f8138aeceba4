//! The shading backends: forward (Forward+), deferred (and its stored-position variant), the
//! visibility buffer, and naive forward, each over any culling strategy (naive forward culls
//! nothing), with per-pass GPU timing.
//!
//! - `forward`: `prepass.depth`, culling, `shade.forward` (the geometry again with depth test
//!   `Equal`, a loop over each pixel's list).
//! - `deferred`: `shade.gbuffer` (depth, shading normal with linear view depth, material index),
//!   culling on its depth, `shade.deferred` (a compute pass over pixels reading the lists).
//! - `deferred_stored_position`: as `deferred`, with the interpolated world position stored in
//!   the G-buffer instead of rebuilt (agrees with forward to rounding on any GPU).
//! - `visibility`: a triangle id and depth a pixel (`shade.visibility`, or rasterised in compute,
//!   `shade.visibility_compute.*`), culling on its depth, `shade.deferred` with each pixel's
//!   surface rebuilt from its triangle.
//! - `naive_forward`: `prepass.depth`, `shade.naive` (every light at every fragment).
//!
//! All five use the one shading model of `shaders/common/shading.wgsl`.

use manylights_cull::ListPass;
use manylights_cull::{CullOutput, CullSettings, Culler, Strategy};
use manylights_gpu::lookup_bounds::LookupBounds;
use manylights_gpu::prepass::DepthPrepass;
use manylights_gpu::timing::{Category, GpuTimer, PassTiming};
use manylights_gpu::{GpuContext, GpuScene, LightPath, readback};

use crate::frame_plan::{self, FramePass, PassInfo, Recording, Resource, Work};
use crate::kinds::Shadows;
use crate::pipelines::Surfaces;
use crate::raster::Draw;
pub(crate) use crate::raster::Loads;
use crate::shade_pass::{ShadePass, Targets};
pub use crate::shaders::{DEFERRED, DEFERRED_MSAA, FORWARD, GBUFFER, LIST_SHADING};
use crate::{HdrImage, ShadeError};

pub use crate::kinds::{
    Backend, GBUFFER_BYTES_PER_PIXEL, HdrFormat, VISIBILITY_BYTES_PER_PIXEL, VisibilityPass,
};
pub(crate) use crate::kinds::{GB_MATERIAL, GB_NORMAL_DEPTH, GB_POSITION, VISIBILITY_ID};
use crate::vis_compute::ComputeVisibility;
use std::sync::OnceLock;

/// What one frame of a backend produced.
pub struct ShadeOutput {
    /// HDR radiance (alpha 1 where covered).
    pub color: HdrImage,
    /// GPU time of every pass, in order; `None` without timestamp queries.
    pub timings: Option<Vec<PassTiming>>,
    /// The light lists (not for naive forward).
    pub lists: Option<CullOutput>,
    /// The depth buffer (its samples are what the exact oracle checks).
    pub depth: wgpu::Texture,
    /// The depth the lists were built from: the depth buffer, or with MSAA or glass the lookup
    /// bounds, each pixel's nearest and farthest depth a list is looked up at
    /// (`manylights_gpu::lookup_bounds`). Culling timed again for this frame runs on it.
    pub cull_depth: wgpu::Texture,
    /// G-buffer bytes (deferred only; 0 otherwise).
    pub gbuffer_bytes: u64,
    /// Bytes of the multisampled targets (depth and HDR colour, or the G-buffer), and of the
    /// lookup bounds where forward or deferred culls over them; 0 without MSAA or glass.
    pub msaa_target_bytes: u64,
    /// The backend that rendered it.
    pub backend: Backend,
    /// Its passes in order, the culling run among them (`cull`), with what each reads and
    /// writes ([`crate::frame_plan`]).
    pub passes: Vec<PassInfo>,
    /// Its textures, for [`Renderer::shade_pass`].
    pub(crate) targets: Targets,
}

impl ShadeOutput {
    /// Whether its triangles were found by the compute rasteriser
    /// ([`Renderer::computes_visibility`]; its passes `shade.visibility_compute.*`), not a
    /// raster pass.
    pub fn computed_visibility(&self) -> bool {
        self.targets.compute.is_some()
    }

    /// Reads the colour target again (after [`Renderer::shade_pass`] shaded into it anew).
    pub fn read_color(&self, ctx: &GpuContext) -> Result<HdrImage, manylights_gpu::GpuError> {
        let (w, h) = self.targets.size;
        let bytes = readback::read_texture(ctx, &self.targets.color, wgpu::TextureAspect::All)?;
        Ok(self.targets.hdr.image(w, h, &bytes))
    }
}

/// Pipelines of every backend for one scene layout, and the culler.
pub struct Renderer {
    /// The culling strategies, over whatever depth a frame's geometry wrote (the depth buffer,
    /// lookup bounds, or the compute rasteriser's `R32Float` depth).
    pub culler: Culler,
    /// Samples a pixel of the depth buffer and the forward passes' colour target (MSAA where
    /// more than one).
    pub(crate) samples: u32,
    /// The lit image's format.
    pub(crate) hdr: HdrFormat,
    /// The path its shading pipelines are built for (`POINT_LIGHTS`, `STOCHASTIC_POINTS`,
    /// `BAND_POINTS`, shaders/common/shading.wgsl): the scene's when the renderer was built
    /// ([`GpuScene::light_path`]).
    pub(crate) light_path: LightPath,
    pub(crate) prepass: DepthPrepass,
    /// Whether the scene has transparent surfaces.
    pub(crate) transparent: bool,
    /// MSAA or transparent surfaces: the depth culling reads, where lists are looked up off
    /// the depth buffer's samples.
    pub(crate) lookup_bounds: Option<LookupBounds>,
    /// Every backend's pipelines, built at their first use.
    pub(crate) pipelines: crate::pipelines::Pipelines,
    /// How the visibility backend finds each pixel's triangle (default: the compute rasteriser
    /// where it can, [`VisibilityPass::Compute`]).
    pub visibility_pass: VisibilityPass,
    /// Whether the device has 64-bit atomic max (the compute rasteriser needs it).
    pub(crate) int64_atomics: bool,
    /// The compute rasteriser, built at its first frame.
    pub(crate) compute_visibility: OnceLock<ComputeVisibility>,
    /// Whether its shading casts shadow rays ([`Renderer::with_shadows`]).
    pub(crate) shadows: Shadows,
}

impl Renderer {
    /// A renderer for scenes laid out as [`GpuScene`] (each backend's pipelines built at its
    /// first frame).
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Self {
        Self::build(ctx, scene, 1, HdrFormat::F32)
    }

    /// Every pipeline for frames of `samples` samples a pixel: MSAA where more than one
    /// (forward and naive forward: a multisampled depth prepass and shading pass, resolved
    /// into the colour target; culling bounds over every sample). An error names the counts
    /// the device supports for the depth buffer and the HDR target.
    pub fn with_samples(
        ctx: &GpuContext,
        scene: &GpuScene,
        samples: u32,
    ) -> Result<Self, manylights_gpu::GpuError> {
        Self::with_format(ctx, scene, samples, HdrFormat::F32)
    }

    /// [`Renderer::with_samples`] shading into a lit image of format `hdr`.
    pub fn with_format(
        ctx: &GpuContext,
        scene: &GpuScene,
        samples: u32,
        hdr: HdrFormat,
    ) -> Result<Self, manylights_gpu::GpuError> {
        ctx.check_msaa_of(
            samples,
            &[
                manylights_gpu::prepass::DEPTH_FORMAT,
                hdr.texture_format(),
                manylights_gpu::lookup_bounds::RANGE_FORMAT,
                GB_NORMAL_DEPTH,
                GB_MATERIAL,
            ],
        )?;
        Ok(Self::build(ctx, scene, samples, hdr))
    }

    /// The renderer with its shading pipelines built to cast `shadows` (none built yet: its
    /// earlier frames' pipelines are dropped). Frames with shadows need the scene's BVH
    /// ([`GpuScene::build_bvh`]); [`Renderer::render`] refuses a scene without one.
    pub fn with_shadows(mut self, shadows: Shadows) -> Self {
        self.shadows = shadows;
        self.pipelines.with_shadows(shadows);
        self
    }

    /// Whether its shading casts shadow rays.
    pub fn shadows(&self) -> Shadows {
        self.shadows
    }

    /// The path its shading pipelines are built for ([`GpuScene::light_path`]). A renderer of
    /// the general path shades any scene; one of a point-light path only scenes of that path.
    pub fn light_path(&self) -> LightPath {
        self.light_path
    }

    /// Whether the visibility backend can render `scene` at `size` here: its lighting binds the
    /// scene's indices (as it does the vertices, which `GpuScene::upload` checks) as one storage
    /// binding; the compute rasteriser binds its keys and queue so
    /// ([`ComputeVisibility::check`]); the raster pass needs `PRIMITIVE_INDEX`.
    fn check_visibility(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        size: (u32, u32),
    ) -> Result<(), manylights_gpu::GpuError> {
        ctx.check_storage("index buffer bytes", scene.indices.size())?;
        if self.computes_visibility(Backend::Visibility) {
            return ComputeVisibility::check(ctx, scene, size).map_err(|e| {
                manylights_gpu::GpuError::Unsupported(format!(
                    "the visibility buffer's compute rasteriser cannot draw this frame: {e}; \
                     visibility_pass: Raster (--visibility-pass raster) draws it with the raster \
                     pass"
                ))
            });
        }
        if !ctx.features.primitive_index {
            return Err(manylights_gpu::GpuError::Unsupported(format!(
                "backend visibility's raster pass needs `@builtin(primitive_index)` (wgpu feature \
                 PRIMITIVE_INDEX; on Vulkan the geometryShader feature), which adapter {} does \
                 not offer (the compute rasteriser, which needs 64-bit atomic max instead, draws \
                 only at one sample a pixel without glass): use backend deferred or forward there",
                ctx.info.name
            )));
        }
        Ok(())
    }

    /// Whether frames of `backend` find their triangles with the compute rasteriser: the
    /// visibility backend with [`VisibilityPass::Compute`], at one sample a pixel, over a scene
    /// without transparent surfaces (whose forward pass tests a depth buffer), on a device with
    /// 64-bit atomic max. Elsewhere it draws the raster pass.
    pub fn computes_visibility(&self, backend: Backend) -> bool {
        backend == Backend::Visibility
            && self.visibility_pass == VisibilityPass::Compute
            && self.samples == 1
            && !self.transparent
            && self.int64_atomics
    }

    /// The compute rasteriser (built by the first frame that draws it).
    fn compute_visibility(&self, ctx: &GpuContext, scene: &GpuScene) -> &ComputeVisibility {
        self.compute_visibility.get_or_init(|| {
            ComputeVisibility::new(ctx, scene)
                .expect("computes_visibility checked the device's 64-bit atomics")
        })
    }

    /// Samples a pixel of its frames.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The format of its lit image.
    pub fn hdr_format(&self) -> HdrFormat {
        self.hdr
    }

    /// Renders one frame of `scene` (its frame uniform set for `width` x `height`) with
    /// `backend`; `strategy` and `settings` are ignored by naive forward.
    pub fn render(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        backend: Backend,
        strategy: &Strategy,
        settings: &CullSettings,
        (width, height): (u32, u32),
    ) -> Result<ShadeOutput, ShadeError> {
        ctx.check_resolution(width, height)?;
        if self.shadows.casts() && !scene.has_bvh() {
            return Err(ShadeError::NoBvh {
                shadows: self.shadows,
            });
        }
        if self.light_path.point_lights() && self.light_path != scene.light_path() {
            return Err(ShadeError::LightPath {
                built: self.light_path,
                scene: scene.light_path(),
            });
        }
        if self.samples > 1 && backend == Backend::DeferredStoredPosition {
            return Err(ShadeError::Backend {
                backend: backend.name(),
                why: format!(
                    "with MSAA ({} samples): not built; MSAA renders with forward, deferred, \
                     visibility and naive_forward",
                    self.samples
                ),
            });
        }
        if backend == Backend::Visibility {
            self.check_visibility(ctx, scene, (width, height))?;
        }
        let compute = self.computes_visibility(backend);
        self.pipelines.prepare(backend, self.transparent, compute);
        if compute {
            self.compute_visibility(ctx, scene);
        }
        let targets = Targets::new(ctx, self, scene, backend, (width, height));
        let geometry = self.geometry_plan(scene, backend, &targets);
        let mut passes: Vec<PassInfo> = geometry.iter().map(FramePass::info).collect();
        // Room for the geometry's passes, culling's and the shading's (the timer grows past it).
        let mut timer = GpuTimer::new(ctx, frame_plan::timed_passes(&geometry) + 64);
        let mut enc = ctx.encoder("shade");
        frame_plan::record(&mut enc, &mut timer, scene, &geometry, Recording::Frame);
        let lists = if backend == Backend::NaiveForward {
            timer.resolve(&mut enc);
            ctx.submit_and_wait(enc, "naive forward")?;
            None
        } else {
            ctx.submit_and_wait(
                enc,
                match backend {
                    Backend::Forward => "depth prepass",
                    Backend::Visibility => "visibility buffer",
                    _ => "G-buffer",
                },
            )?;
            let lists = self.culler.run(
                ctx,
                scene,
                targets.cull_depth(),
                strategy,
                settings,
                &mut timer,
            )?;
            passes.push(frame_plan::cull_info(targets.cull_depth_resource()));
            let mut pass = ShadePass::new(ctx, self, scene, backend, &targets);
            pass.bind(ctx, lists.list_bindings(), lists.form());
            passes.extend(pass.plan().iter().map(FramePass::info));
            let mut enc = ctx.encoder("shade");
            pass.record(&mut enc, &mut timer);
            timer.resolve(&mut enc);
            let during = if backend.lights_in_compute() {
                "deferred lighting"
            } else {
                "forward shading"
            };
            ctx.submit_and_wait(enc, during)?;
            Some(lists)
        };
        let bytes = readback::read_texture(ctx, &targets.color, wgpu::TextureAspect::All)?;
        Ok(ShadeOutput {
            color: self.hdr.image(width, height, &bytes),
            timings: timer.read(ctx)?,
            lists,
            depth: targets.depth.clone(),
            cull_depth: targets.cull_depth().clone(),
            gbuffer_bytes: targets.gbuffer_bytes,
            msaa_target_bytes: targets.msaa_bytes,
            backend,
            passes,
            targets,
        })
    }

    /// The passes of a frame of `backend` before its culling, over `targets`: the depth
    /// prepass or the G-buffer (or visibility buffer) pass, then the lookup bounds culling
    /// reads (where the renderer keeps them). Naive forward culls nothing: its plan is its
    /// whole frame, and its lookup bounds, which a culler measuring its lights needed reads
    /// (`ShadeOutput::cull_depth`), are for the checks.
    pub(crate) fn geometry_plan<'a>(
        &'a self,
        scene: &'a GpuScene,
        backend: Backend,
        targets: &'a Targets,
    ) -> Vec<FramePass<'a>> {
        use Resource::{ComputeDepth, Depth, DepthRanges, Scene, Surfaces as SurfaceBuffers};
        let depth = &targets.depth_view;
        let mut plan = Vec::new();
        match backend {
            Backend::Forward | Backend::NaiveForward => {
                plan.push(match (&self.lookup_bounds, &targets.bounds) {
                    (Some(bounds), Some(t))
                        if bounds.has_prepass() && backend == Backend::Forward =>
                    {
                        FramePass::new(
                            "prepass.depth",
                            Category::Prepass,
                            Work::RangesPrepass {
                                bounds,
                                depth,
                                targets: t,
                            },
                            &[Scene],
                            &[Depth, DepthRanges],
                        )
                    }
                    _ => FramePass::new(
                        "prepass.depth",
                        Category::Prepass,
                        Work::DepthPrepass {
                            prepass: &self.prepass,
                            depth,
                        },
                        &[Scene],
                        &[Depth],
                    ),
                });
            }
            Backend::Visibility if targets.compute.is_some() => {
                let vis = self
                    .compute_visibility
                    .get()
                    .expect("built by the frame's render");
                let t = targets.compute.as_ref().expect("matched");
                plan.extend(vis.plan(scene, t));
                // The depth buffer the oracle reads (culling and lighting read the compute
                // pass's depths).
                plan.push(
                    FramePass::new(
                        "shade.visibility_depth",
                        Category::Prepass,
                        Work::ComputeDepth {
                            vis,
                            targets: t,
                            depth,
                        },
                        &[ComputeDepth],
                        &[Depth],
                    )
                    .for_checks(),
                );
            }
            Backend::Deferred | Backend::DeferredStoredPosition | Backend::Visibility => {
                let surfaces = Surfaces::of(backend, false);
                let pass = self.pipelines.deferred(surfaces).gbuffer.as_ref();
                let draw = Draw {
                    pipelines: std::slice::from_ref(pass.expect("a raster pass")),
                    targets: targets
                        .gbuffer_targets(backend)
                        .into_iter()
                        .map(|v| (v, None))
                        .collect(),
                    depth,
                    loads: Loads::Clear,
                    lists: None,
                };
                plan.push(FramePass::new(
                    surfaces.pass_name(),
                    Category::Prepass,
                    Work::Draw(draw),
                    &[Scene],
                    &[Depth, SurfaceBuffers],
                ));
            }
        }
        let bounds = self.lookup_bounds_pass(backend, targets);
        if backend == Backend::NaiveForward {
            plan.extend(self.naive_plan(scene, targets));
            plan.extend(bounds.map(FramePass::for_checks));
        } else {
            plan.extend(bounds);
        }
        plan
    }

    /// The lookup bounds culling reads, where the renderer keeps them.
    fn lookup_bounds_pass<'a>(
        &'a self,
        backend: Backend,
        targets: &'a Targets,
    ) -> Option<FramePass<'a>> {
        let (Some(bounds), Some(t)) = (&self.lookup_bounds, &targets.bounds) else {
            return None;
        };
        // Forward's prepass kept the depth ranges (with MSAA); deferred's G-buffer did not.
        let ranges = backend == Backend::Forward && bounds.has_prepass();
        let reads: &[Resource] = if ranges {
            &[Resource::Scene, Resource::Depth, Resource::DepthRanges]
        } else {
            &[Resource::Scene, Resource::Depth]
        };
        Some(FramePass::new(
            "prepass.depth_bounds",
            Category::Prepass,
            Work::LookupBounds {
                bounds,
                targets: t,
                ranges,
            },
            reads,
            &[Resource::LookupBounds],
        ))
    }

    /// Naive forward's shading: every light at every fragment, then any transparent surfaces
    /// over it.
    fn naive_plan<'a>(&'a self, scene: &GpuScene, targets: &'a Targets) -> Vec<FramePass<'a>> {
        use Resource::{Color, Depth, Lights, Scene};
        let transparent = scene.has_transparent();
        let naive = self.pipelines.naive();
        let draw = |pipeline, last, loads| {
            Work::Draw(Draw {
                pipelines: std::slice::from_ref(pipeline),
                targets: vec![targets.color_attachment(last)],
                depth: &targets.depth_view,
                loads,
                lists: None,
            })
        };
        let mut plan = vec![FramePass::new(
            "shade.naive",
            Category::Shade,
            draw(&naive.opaque, !transparent, Loads::Depth),
            &[Scene, Lights, Depth],
            &[Color],
        )];
        if transparent {
            plan.push(FramePass::new(
                "shade.naive_transparent",
                Category::Shade,
                draw(&naive.transparent, true, Loads::Transparent),
                &[Scene, Lights, Depth, Color],
                &[Color],
            ));
        }
        plan
    }

    /// `runs` repetitions of the geometry of the frame `out` rendered (the depth prepass or the
    /// G-buffer pass and the lookup bounds; naive forward: its whole frame) back to back in
    /// one submission, into its targets, timed by `timer` (a timer of spans times each
    /// repetition as one span, `geometry`): with [`Culler::run_repeated_with`] over the
    /// shading pass, a frame timed in steady state.
    pub fn geometry_repeated(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        out: &ShadeOutput,
        runs: u32,
        timer: &mut GpuTimer,
    ) -> Result<(), manylights_gpu::GpuError> {
        let mut enc = ctx.encoder("shade.geometry_repeated");
        let plan = self.geometry_plan(scene, out.backend, &out.targets);
        for _ in 0..runs {
            let outer = timer.set_category(Category::Prepass);
            timer.span_begin(&mut enc, "geometry");
            timer.set_category(outer);
            frame_plan::record(&mut enc, timer, scene, &plan, Recording::Repeat);
        }
        timer.span_end(&mut enc);
        timer.resolve(&mut enc);
        ctx.submit_and_wait(enc, "geometry repeated")
    }

    /// The shading pass of the frame `out` rendered (forward or deferred; `None` for naive
    /// forward), over its targets and the scene: bound to the lists of any culling run over
    /// `out.depth` (`Culler::run_repeated_with` binds it to each run's lists and records it
    /// after each run, timing a frame's culling and shading together).
    pub fn shade_pass<'a>(
        &'a self,
        ctx: &GpuContext,
        scene: &'a GpuScene,
        out: &'a ShadeOutput,
    ) -> Option<ShadePass<'a>> {
        (out.backend != Backend::NaiveForward)
            .then(|| ShadePass::new(ctx, self, scene, out.backend, &out.targets))
    }
}
