//! A frame's targets ([`Targets`]: colour, depth, and the G-buffer where the backend has one)
//! and the shading pass that reads a culling run's lists ([`ShadePass`]): `shade.forward` (the
//! geometry again, depth test `Equal`) or `shade.deferred` (a compute pass over the pixels).
//! The same pass serves a single frame ([`crate::Renderer::render`]) and back-to-back frames
//! timed with their culling ([`manylights_cull::Culler::run_repeated_with`], through
//! [`crate::Renderer::shade_pass`]), so that a frame's culling and shading are measured as one.

use manylights_cull::layout::ZBIN_ROUNDS_MIN_LIGHTS;
use manylights_cull::{ListForm, ListPass};
use manylights_gpu::lookup_bounds::BoundsTargets;
use manylights_gpu::prepass::depth_target_msaa;
use manylights_gpu::timing::{Category, GpuTimer};
use manylights_gpu::{GpuContext, GpuScene, pipeline};

use crate::vis_compute::ComputeTargets;

use crate::frame_plan::{self, FramePass, Recording, Resource, Work};
use crate::pipelines::Surfaces;
use crate::raster::Draw;

use crate::backends::{
    Backend, GB_MATERIAL, GB_NORMAL_DEPTH, GB_POSITION, HdrFormat, Loads, Renderer, VISIBILITY_ID,
};

/// The textures of one frame of a backend.
pub struct Targets {
    /// Width and height.
    pub(crate) size: (u32, u32),
    /// The colour targets' format.
    pub(crate) hdr: HdrFormat,
    /// HDR radiance (MSAA: resolved).
    pub(crate) color: wgpu::Texture,
    pub(crate) color_view: wgpu::TextureView,
    /// MSAA: the multisampled HDR target the forward passes draw into and resolve from.
    pub(crate) color_msaa: Option<wgpu::TextureView>,
    /// The depth buffer (prepass or G-buffer pass).
    pub(crate) depth: wgpu::Texture,
    pub(crate) depth_view: wgpu::TextureView,
    /// Deferred backends: normal and view depth, material, and (stored position) the world
    /// position; a 1 x 1 placeholder for the position where it is rebuilt.
    pub(crate) gbuffer: Option<[wgpu::TextureView; 3]>,
    /// G-buffer bytes (0 without one).
    pub(crate) gbuffer_bytes: u64,
    /// Bytes of the multisampled depth and colour targets (0 without MSAA).
    pub(crate) msaa_bytes: u64,
    /// MSAA forward: the depth ranges and the depth culling reads.
    pub(crate) bounds: Option<BoundsTargets>,
    /// The visibility buffer rasterised in compute: its keys, ids (the surface buffers' ids)
    /// and `R32Float` depths (what culling and lighting read).
    pub(crate) compute: Option<ComputeTargets>,
}

impl Targets {
    /// The targets of a `width` x `height` frame of `backend`.
    pub(crate) fn new(
        ctx: &GpuContext,
        renderer: &Renderer,
        scene: &GpuScene,
        backend: Backend,
        (width, height): (u32, u32),
    ) -> Self {
        let samples = renderer.samples;
        let hdr = renderer.hdr;
        let d = &ctx.device;
        let tex =
            |label, format, usage| pipeline::texture_2d(d, label, (width, height), format, usage);
        let color = tex(
            "shade.color",
            hdr.texture_format(),
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        let deferred = backend.lights_in_compute();
        let compute = renderer.computes_visibility(backend).then(|| {
            let vis = renderer
                .compute_visibility
                .get()
                .expect("built before the frame's targets");
            vis.targets(ctx, scene, (width, height))
        });
        // Deferred lighting writes the image itself: with MSAA a multisampled colour target
        // only for the glass, drawn into it first and composited sample by sample by the
        // lighting pass (which reads it).
        let color_msaa = (samples > 1 && (!deferred || renderer.transparent)).then(|| {
            pipeline::texture_2d_msaa(
                d,
                "shade.color_msaa",
                (width, height),
                hdr.texture_format(),
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
                samples,
            )
            .create_view(&Default::default())
        });
        let depth = depth_target_msaa(ctx, width, height, samples);
        // Where the renderer has lookup bounds (MSAA, transparent surfaces), every backend culls
        // over them: forward's over the depth ranges its prepass keeps (a fragment is looked up
        // at its centroid), the others' over the depth samples (deferred lighting looks up at
        // samples and pixel centres, between the samples' depths) and the glass.
        let bounds = renderer
            .lookup_bounds
            .as_ref()
            .map(|b| b.targets(ctx, (width, height), &depth, backend == Backend::Forward));
        let gbuffer = deferred.then(|| {
            surface_views(
                d,
                renderer,
                backend,
                (width, height),
                color_msaa.as_ref(),
                compute.as_ref(),
            )
        });
        let gbuffer_bytes = match &compute {
            Some(t) => t.bytes(),
            None => {
                u64::from(width)
                    * u64::from(height)
                    * backend.surface_bytes_per_sample()
                    * u64::from(samples)
            }
        };
        Self {
            size: (width, height),
            hdr,
            color_view: color.create_view(&Default::default()),
            color,
            color_msaa,
            depth_view: depth.create_view(&Default::default()),
            depth,
            gbuffer_bytes,
            gbuffer,
            msaa_bytes: msaa_bytes(
                renderer,
                backend,
                (width, height),
                bounds.as_ref(),
                gbuffer_bytes,
            ),
            bounds,
            compute,
        }
    }

    /// The depth culling reads: the depth buffer, the lookup bounds where the renderer has
    /// them, or the compute rasteriser's `R32Float` depths.
    pub(crate) fn cull_depth(&self) -> &wgpu::Texture {
        if let Some(t) = &self.compute {
            return &t.depth;
        }
        self.bounds.as_ref().map_or(&self.depth, |b| &b.bounds)
    }

    /// What [`Targets::cull_depth`] is, as a frame plan's resource.
    pub(crate) fn cull_depth_resource(&self) -> Resource {
        if self.compute.is_some() {
            Resource::ComputeDepth
        } else if self.bounds.is_some() {
            Resource::LookupBounds
        } else {
            Resource::Depth
        }
    }

    /// The forward passes' colour target: the HDR target, or with MSAA the multisampled one,
    /// resolved into it by the frame's `last` pass.
    pub(crate) fn color_attachment(
        &self,
        last: bool,
    ) -> (&wgpu::TextureView, Option<&wgpu::TextureView>) {
        match &self.color_msaa {
            Some(msaa) => (msaa, last.then_some(&self.color_view)),
            None => (&self.color_view, None),
        }
    }

    /// The colour targets of the raster pass of `backend` (deferred: the G-buffer, the stored
    /// position only where it is stored; visibility: the triangle ids).
    pub(crate) fn gbuffer_targets(&self, backend: Backend) -> Vec<&wgpu::TextureView> {
        let views = self.gbuffer.as_ref().expect("a deferred backend's targets");
        match backend {
            Backend::Visibility => vec![&views[1]],
            Backend::DeferredStoredPosition => views.iter().collect(),
            _ => views.iter().take(2).collect(),
        }
    }
}

/// The surface buffers' views of a deferred backend's frame: the G-buffer's normal and view
/// depth, material and stored position; the visibility buffer's stand-in, triangle ids (the
/// compute rasteriser's where it draws them) and, with MSAA, the glass layer.
fn surface_views(
    d: &wgpu::Device,
    renderer: &Renderer,
    backend: Backend,
    (width, height): (u32, u32),
    color_msaa: Option<&wgpu::TextureView>,
    compute: Option<&ComputeTargets>,
) -> [wgpu::TextureView; 3] {
    let samples = renderer.samples;
    let hdr = renderer.hdr;
    let stored = backend == Backend::DeferredStoredPosition;
    // Read back by the visibility buffer's oracle (`crate::visibility`) at one sample.
    let copy = if samples == 1 {
        wgpu::TextureUsages::COPY_SRC
    } else {
        wgpu::TextureUsages::empty()
    };
    let usage =
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING | copy;
    let (pw, ph) = if stored { (width, height) } else { (1, 1) };
    let ms = |label, format| {
        pipeline::texture_2d_msaa(d, label, (width, height), format, usage, samples)
            .create_view(&Default::default())
    };
    // The third: the stored position (a 1 x 1 stand-in where it is not stored); with
    // MSAA, the glass the lighting composites (a stand-in without glass).
    let third = match (samples > 1, color_msaa) {
        (false, _) => pipeline::texture_2d(d, "gbuffer.position", (pw, ph), GB_POSITION, usage)
            .create_view(&Default::default()),
        (true, Some(glass)) => glass.clone(),
        (true, None) => pipeline::texture_2d_msaa(
            d,
            "shade.glass",
            (1, 1),
            hdr.texture_format(),
            usage,
            samples,
        )
        .create_view(&Default::default()),
    };
    if backend == Backend::Visibility {
        // The triangle ids in the material's place (the compute rasteriser's where it
        // draws them), and a 1 x 1 stand-in for the normal and view depth.
        let stand_in = pipeline::texture_2d_msaa(
            d,
            "visibility.no_normal_depth",
            (1, 1),
            GB_NORMAL_DEPTH,
            usage,
            samples,
        );
        let ids = match compute {
            Some(t) => t.ids.create_view(&Default::default()),
            None => ms("visibility.ids", VISIBILITY_ID),
        };
        return [stand_in.create_view(&Default::default()), ids, third];
    }
    [
        ms("gbuffer.normal_depth", GB_NORMAL_DEPTH),
        ms("gbuffer.material", GB_MATERIAL),
        third,
    ]
}

/// Bytes of a frame's multisampled targets, and of the lookup bounds where its backend culls
/// over them (naive forward's frame reads none: they are made for measuring it).
fn msaa_bytes(
    renderer: &Renderer,
    backend: Backend,
    (width, height): (u32, u32),
    bounds: Option<&BoundsTargets>,
    gbuffer_bytes: u64,
) -> u64 {
    let samples = u64::from(renderer.samples);
    let pixels = u64::from(width) * u64::from(height);
    let hdr_bytes = renderer.hdr.texel_bytes();
    let bounds = bounds
        .filter(|_| backend != Backend::NaiveForward)
        .map_or(0, |b| b.bytes);
    bounds
        + match (samples > 1, backend.lights_in_compute()) {
            (false, _) => 0,
            // The G-buffer, depth included, and for glass the colour it is blended in.
            (true, true) => {
                gbuffer_bytes
                    + if renderer.transparent {
                        pixels * samples * hdr_bytes
                    } else {
                        0
                    }
            }
            // Depth32Float and the colour, `samples` each a pixel.
            (true, false) => pixels * samples * (4 + hdr_bytes),
        }
}

/// The shading pass of a forward or deferred frame over the lists it is bound to.
pub struct ShadePass<'a> {
    renderer: &'a Renderer,
    scene: &'a GpuScene,
    backend: Backend,
    targets: &'a Targets,
    /// The lists (and for deferred the depth), once bound.
    lists: Option<wgpu::BindGroup>,
    /// Their form, once bound: the entry point that reads them.
    form: ListForm,
    /// Deferred: the G-buffer and the colour target.
    gbuffer: Option<wgpu::BindGroup>,
    /// Deferred over transparent surfaces: the lists for their forward pass.
    forward_lists: Option<wgpu::BindGroup>,
}

impl<'a> ShadePass<'a> {
    /// The pass of `backend` (forward or deferred) over `targets`.
    pub(crate) fn new(
        ctx: &GpuContext,
        renderer: &'a Renderer,
        scene: &'a GpuScene,
        backend: Backend,
        targets: &'a Targets,
    ) -> Self {
        let gbuffer = targets.gbuffer.as_ref().map(|views| {
            pipeline::group(
                &ctx.device,
                "shade.deferred.gbuffer",
                &renderer.pipelines.deferred_gbuffer,
                &[
                    wgpu::BindingResource::TextureView(&views[0]),
                    wgpu::BindingResource::TextureView(&views[1]),
                    wgpu::BindingResource::TextureView(&targets.color_view),
                    wgpu::BindingResource::TextureView(&views[2]),
                    scene.vertices.as_entire_binding(),
                    scene.indices.as_entire_binding(),
                ],
            )
        });
        Self {
            renderer,
            scene,
            backend,
            targets,
            lists: None,
            form: ListForm::Bins,
            gbuffer,
            forward_lists: None,
        }
    }
}

impl<'a> ShadePass<'a> {
    /// `shade.forward_transparent`: the glass over `lists`, blended into the colour target
    /// (resolved from its samples with MSAA); with `layer` (deferred with MSAA) into the
    /// multisampled target alone, as its own contribution and transmittance, which the
    /// lighting pass then composites over each sample.
    fn glass_pass(&self, lists: &'a wgpu::BindGroup, layer: bool) -> FramePass<'a> {
        use Resource::{Color, Depth, GlassLayer, Lights, Lists, Scene};
        let r = self.renderer;
        let zbin = usize::from(self.form == ListForm::ZBin);
        let glass = r.pipelines.glass();
        let (pipeline, target, loads) = match (layer, &self.targets.color_msaa, &glass.layer) {
            (true, Some(msaa), Some(layer)) => (&layer[zbin], (msaa, None), Loads::GlassLayer),
            _ => (
                &glass.blended[zbin],
                self.targets.color_attachment(true),
                Loads::Transparent,
            ),
        };
        let (reads, writes): (&[Resource], &[Resource]) = if loads == Loads::GlassLayer {
            (&[Scene, Lights, Depth, Lists], &[GlassLayer])
        } else {
            (&[Scene, Lights, Depth, Lists, Color], &[Color])
        };
        FramePass::new(
            "shade.forward_transparent",
            Category::Shade,
            Work::Draw(Draw {
                pipelines: std::slice::from_ref(pipeline),
                targets: vec![target],
                depth: &self.targets.depth_view,
                loads,
                lists: Some(lists),
            }),
            reads,
            writes,
        )
    }

    /// The frame's passes after its culling, over the lists it is bound to: forward's
    /// `shade.forward` (and the glass over it), or deferred's lighting `shade.deferred` (and
    /// the glass, before it with MSAA, into the layer it composites, or after it over the lit
    /// image). A pass that reads the lists and writes what the shading reads goes first.
    pub fn plan(&self) -> Vec<FramePass<'_>> {
        use Resource::{
            Color, ComputeDepth, Depth, GlassLayer, Lights, Lists, Scene,
            Surfaces as SurfaceBuffers,
        };
        let lists = self.lists.as_ref().expect("bound before it is planned");
        let r = self.renderer;
        let transparent = r.transparent;
        let mut plan = Vec::new();
        match &self.gbuffer {
            None => {
                plan.push(FramePass::new(
                    "shade.forward",
                    Category::Shade,
                    Work::Draw(Draw {
                        pipelines: match self.form {
                            ListForm::Bins | ListForm::Tiles | ListForm::Clusters => {
                                &r.pipelines.forward().bins
                            }
                            ListForm::ZBin => &r.pipelines.forward().zbin,
                        },
                        targets: vec![self.targets.color_attachment(!transparent)],
                        depth: &self.targets.depth_view,
                        loads: Loads::Depth,
                        lists: Some(lists),
                    }),
                    &[Scene, Lights, Depth, Lists],
                    &[Color],
                ));
                if transparent {
                    plan.push(self.glass_pass(lists, false));
                }
            }
            Some(gbuffer) => {
                let (w, h) = self.targets.size;
                // With MSAA the glass first, into its own multisampled layer, which the
                // lighting composites over each sample it lights (the reference blends each
                // sample its own).
                let layer = self.renderer.samples > 1;
                let glass = self.forward_lists.as_ref();
                if let (true, Some(forward_lists)) = (layer, glass) {
                    plan.push(self.glass_pass(forward_lists, true));
                }
                let compute = self.targets.compute.is_some();
                let lighting = r.pipelines.deferred(Surfaces::of(self.backend, compute));
                let pipeline = match self.form {
                    ListForm::Bins => &lighting.bins,
                    ListForm::ZBin => {
                        // In rounds with many point lights (`ZBIN_ROUNDS_MIN_LIGHTS`).
                        let rounds = r.light_path.point_lights()
                            && self.scene.light_count >= ZBIN_ROUNDS_MIN_LIGHTS;
                        &lighting.zbin[usize::from(rounds)]
                    }
                    ListForm::Tiles => &lighting.tiles,
                    ListForm::Clusters => &lighting.clusters,
                };
                let mut reads = vec![
                    Scene,
                    Lights,
                    SurfaceBuffers,
                    if compute { ComputeDepth } else { Depth },
                    Lists,
                ];
                if layer && glass.is_some() {
                    reads.push(GlassLayer);
                }
                let mut lit = FramePass::new(
                    "shade.deferred",
                    Category::Shade,
                    Work::Dispatch {
                        pipeline,
                        groups: vec![&self.scene.bind_group, lists, gbuffer],
                        grid: [w.div_ceil(8), h.div_ceil(8), 1],
                    },
                    &[],
                    &[Color],
                );
                lit.reads = reads;
                plan.push(lit);
                // Deferred cannot shade transparent surfaces: at one sample a pixel a forward
                // pass over the same lists does, over the lit image (as engines do).
                if let (false, Some(forward_lists)) = (layer, glass) {
                    plan.push(self.glass_pass(forward_lists, false));
                }
            }
        }
        plan
    }
}

impl ListPass for ShadePass<'_> {
    fn passes(&self) -> u32 {
        // The transparent surfaces' forward pass (after the opaque shading; for deferred with
        // MSAA, before the lighting that composites it).
        1 + u32::from(self.renderer.transparent)
    }

    fn bind(&mut self, ctx: &GpuContext, lists: [wgpu::BindingResource<'_>; 3], form: ListForm) {
        self.form = form;
        let mut resources = lists.to_vec();
        if self.gbuffer.is_some() && self.renderer.transparent {
            self.forward_lists = Some(pipeline::group(
                &ctx.device,
                "shade.forward_transparent.lists",
                &self.renderer.pipelines.forward_lists,
                &resources,
            ));
        }
        let depth_only;
        let layout = if let Some(t) = &self.targets.compute {
            depth_only = t.depth.create_view(&Default::default());
            resources.push(wgpu::BindingResource::TextureView(&depth_only));
            &self.renderer.pipelines.deferred_float_lists
        } else if self.gbuffer.is_some() {
            depth_only = self
                .targets
                .depth
                .create_view(&wgpu::TextureViewDescriptor {
                    aspect: wgpu::TextureAspect::DepthOnly,
                    ..Default::default()
                });
            resources.push(wgpu::BindingResource::TextureView(&depth_only));
            &self.renderer.pipelines.deferred_lists
        } else {
            &self.renderer.pipelines.forward_lists
        };
        self.lists = Some(pipeline::group(
            &ctx.device,
            "shade.lists",
            layout,
            &resources,
        ));
    }

    fn record(&self, enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer) {
        frame_plan::record(enc, timer, self.scene, &self.plan(), Recording::Frame);
    }
}
