//! The orchestration: [`Culler`] builds every strategy's and building block's pipelines once
//! over its depth input, and over a float depth at the first run over one
//! ([`crate::input_pipelines`]; tiled scatter's, the clusters' and z-binning's at their first
//! run), and a run checks its inputs, computes the parameters and hands them to the strategy's
//! module ([`crate::strategies`]), which records its plan through [`crate::frame::execute`].

use manylights_gpu::pipeline::{self, UNIFORM, depth_texture, storage};
use manylights_gpu::timing::GpuTimer;
use std::sync::OnceLock;

use manylights_gpu::{GpuContext, GpuError, GpuScene};

use crate::blocks::occlusion::{OCCLUDERS_MAX, Occlusion};
use crate::frame::{self, Done, Frame, Repeat};
use crate::input_pipelines::InputPipelines;
use crate::layout::{GpuCullParams, LINE_THREADS_MIN};
use crate::per_pixel::PerPixel;
use crate::program::DepthInput;
use crate::radix_sort::RadixSort;
use crate::record::{ListPass, Recorder};
use crate::scan::Scan;
use crate::strategies::{Plan, clustered, depth_mask, tiled_gather, tiled_scatter, zbin};
use crate::{CullError, CullOutput, CullSettings, Strategy};

/// Pipelines of every culling pass, and the knobs of the runs.
pub struct Culler {
    /// Every culling pipeline over its own depth input.
    pipelines: InputPipelines,
    /// Over an `R32Float` depth a compute pass wrote (the visibility buffer's compute
    /// rasteriser), built at the first run over one: the same culler, knobs and lists.
    float_pipelines: OnceLock<InputPipelines>,
    /// Whether gather's scans may use subgroups (`Culler::with_subgroups`).
    subgroups: bool,
    /// Samples a pixel of the depth buffers its oracle checks (MSAA where more than one): the
    /// exact oracle checks every sample.
    pub samples: u32,
    /// Whether it culls over lookup bounds (`Culler::with_bounds`: a pixel's nearest and
    /// farthest lookup depth) in place of depth buffers of `samples`. Tile and cluster depth
    /// bounds are taken over every sample, or over both bounds.
    pub lookup_bounds: bool,
    /// Layout of group 1 for list consumers (shading, `cull.lights_per_pixel`): 0 params,
    /// 1 ranges, 2 indices, 3 depth, 4 a per-pixel output, 5 a pass-specific uniform.
    pub lists_layout: wgpu::BindGroupLayout,
    /// Whether gather's scans use subgroup operations.
    pub gather_subgroups: bool,
    /// The fewest lights a workgroup of gather's coarse-to-fine passes takes
    /// ([`crate::MIN_CHUNK`] by default; larger trades parallelism for less repeated set-up).
    pub gather_min_chunk: u32,
    /// The same with tile masks ([`crate::MIN_CHUNK_MASKED`] by default: without a scan over
    /// (tile, chunk) counts, smaller chunks cost less).
    pub gather_min_chunk_masked: u32,
    /// The most bytes of tile masks gather's coarse-to-fine passes and tiled scatter may use
    /// ([`crate::MASK_BUDGET`] by default): where a bit per (tile, light) fits, the count pass
    /// stores the kept lights as bits and the fill pass expands them without testing again
    /// (scatter: without pairs and their sort); past it (or at 0) gather's fill tests every
    /// light again and scatter sorts its pairs.
    /// A run's [`CullSettings::mask_budget`] overrides it.
    pub mask_budget: u64,
    /// Whether gather and 2.5D take their lines path where tile masks fit (true by default):
    /// `cull.tile_lines`, then one pass that computes each tile's depth data and decides and
    /// writes its list ([`crate::blocks::tile_lines`]); false: the count pass stores tile masks
    /// and the fill expands them.
    pub gather_lines: bool,
    /// The most lights for which the clusters take their tile path (a workgroup a tile, at
    /// most [`crate::layout::CLUSTER_TILE_SLICES`] slices and [`crate::CLUSTER_TILES_MAX_PAIRS`]
    /// (tile, light) pairs; [`crate::CLUSTER_TILES_MAX_LIGHTS`] by default; 0: never): the same
    /// lists as the per-light passes.
    pub cluster_tiles_max_lights: u32,
    /// The fewest (tile, light) pairs at which that path computes the lights' rectangles in a
    /// pass of their own ([`crate::CLUSTER_TILE_RECT_PAIRS`] by default; 0: always).
    pub cluster_tile_rect_pairs: u64,
    /// Whether the clusters' per-light passes with the box test read each cluster's box from
    /// `cull.clustered.boxes`, which stores it once a run where the boxes fit a binding (true
    /// by default); false: each (light, cluster) test computes it. The same lists either way.
    pub cluster_boxes: bool,
    /// With the clusters' boxes, whether their per-light passes test only the slices of a tile
    /// that hold pixels, from a mask a tile (`CULL_FLAG_SLICE_MASKS`; at most
    /// [`crate::layout::CLUSTER_MASK_SLICES`] slices). True by default: culling at 1M lights
    /// (clusters 32 px x 32) took 1.60 ms against 1.86 looping over the light's slices, and at
    /// 50,000 lights in the hall 0.378 against 0.447 (H100). The same lists either way.
    pub cluster_slice_masks: bool,
    /// With the clusters' boxes, whether a run whose lists are sized up front (back-to-back
    /// runs) has its count passes hold each (cluster, light) pair they count, so that
    /// `cull.clustered.scatter` puts them in their lists in place of the fill passes, which
    /// would test them all again (`CLUSTER_PAIRS`; 8 bytes a list entry). True by default: at 1M
    /// lights in 32-px clusters the steady culling 0.94 against 0.66 ms without, the frame 2.15
    /// against 1.87 (H100; `experiments/cluster-pairs-1m.ron`). The same lists either way.
    pub cluster_pairs: bool,
    /// The tiles a lane of the clusters' wide-light passes should take
    /// ([`crate::CLUSTER_LANE_TILES`] by default): a light whose rectangle holds more than
    /// [`crate::layout::CLUSTER_LANES`] times as many tiles is split into bands of its rows, each
    /// with lanes of its own (0: never split). The same lists either way.
    pub cluster_lane_tiles: u32,
    /// The queue entries for the bands past each light's first (the band pool; `None`: one a
    /// light). A light whose bands do not fit keeps its whole rectangle in one entry.
    pub cluster_band_pool: Option<u32>,
    /// Whether the clusters take each light's tile rectangle from the exact bounds of its
    /// sphere's projection (Mara and McGuire 2013; `CULL_FLAG_SPHERE_BOUNDS`, for a perspective
    /// without skew) rather than from its box's corners: fewer candidate tiles, lists a subset
    /// of those without (with the box test, the same lists). True by default: on the H100,
    /// culling at 1M lights 1.183 against 1.109 ms in 32-pixel tiles, 2.01 against 1.64 in
    /// 16-pixel tiles; in the hall at 50,000 lights 0.379 against 0.353 ms.
    pub cluster_sphere_bounds: bool,
    /// Whether the clusters' order passes sort a list of more than 512 lights by a bitmap of
    /// the light indices (a bit a light in workgroup memory, set by each entry, then each light
    /// written at its rank: four barriers whatever the length) where the lights are at most
    /// [`crate::layout::CLUSTER_ORDER_BITS_LIGHTS`] (`CULL_FLAG_ORDER_BITS`), rather than by
    /// buckets of the light indices (or, for a list of lights with neighbouring indices or
    /// longer than 4,096, the bitonic network). The same lists. True by default: on the H100,
    /// the hall at 50,000 lights, that pass 28 against 23 µs (67 µs by the network alone).
    pub cluster_order_bits: bool,
    /// The fewest lights at which z-binning sets its masks a light at a time
    /// (`cull.zbin.covers`, `cull.zbin.scatter`: work as the (light, tile) pairs) rather than a
    /// tile at a time (`cull.zbin.masks`: tiles x the lights of a tile's depth bins)
    /// ([`crate::ZBIN_SCATTER_MIN_LIGHTS`] by default; 0: always, `u32::MAX`: never). The same
    /// masks either way.
    pub zbin_scatter_min_lights: u32,
    /// What the float depth's pipelines are built over.
    scene_layout: wgpu::BindGroupLayout,
    pub(crate) per_pixel: PerPixel,
    scan: Scan,
    pub(crate) sort: RadixSort,
    /// Culling by visibility's pass over the scene's occluders ([`Culler::set_occluders`]).
    pub(crate) occlusion: Option<Occlusion>,
    /// Bound where a strategy has no buffer for a binding (made once, not per run).
    pub(crate) placeholder: wgpu::Buffer,
}

/// A binding of the culling groups (visible to compute and, for list consumers, fragments).
pub(crate) fn entry(binding: u32, ty: wgpu::BindingType) -> wgpu::BindGroupLayoutEntry {
    pipeline::entry(
        binding,
        wgpu::ShaderStages::COMPUTE | wgpu::ShaderStages::FRAGMENT,
        ty,
    )
}

impl Culler {
    /// Builds the pipelines for scenes laid out as [`GpuScene`] (tiled scatter's, the
    /// clusters' and z-binning's at their strategy's first run).
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Self {
        Self::with_subgroups(ctx, scene, true)
    }

    /// As [`Culler::new`]; with `subgroups` false, gather keeps its portable scans even where
    /// the device has subgroup operations (both paths give the same lists; the tests run both).
    pub fn with_subgroups(ctx: &GpuContext, scene: &GpuScene, subgroups: bool) -> Self {
        Self::build(ctx, scene, subgroups, 1, DepthInput::Samples(1))
    }

    /// As [`Culler::new`], for depth buffers of `samples` samples a pixel (MSAA; see
    /// `GpuContext::check_msaa`): every sample's depth counts in the tiles' and clusters'
    /// bounds, so lists stay conservative for every sample. Its lists are for culling and the
    /// exact oracle; the shading backends read lists of single-sample depth buffers.
    pub fn with_samples(ctx: &GpuContext, scene: &GpuScene, samples: u32) -> Self {
        Self::build(ctx, scene, true, samples, DepthInput::Samples(samples))
    }

    /// As [`Culler::with_samples`], culling over lookup bounds
    /// (`manylights_gpu::lookup_bounds`: a texture of
    /// [`BOUNDS_FORMAT`](manylights_gpu::lookup_bounds::BOUNDS_FORMAT), a pixel's nearest and
    /// farthest lookup depth) while its oracle and per-pixel consumers read depth buffers of
    /// `samples`.
    pub fn with_bounds(ctx: &GpuContext, scene: &GpuScene, samples: u32) -> Self {
        Self::build(ctx, scene, true, samples, DepthInput::Bounds)
    }

    fn build(
        ctx: &GpuContext,
        scene: &GpuScene,
        subgroups: bool,
        samples: u32,
        input: DepthInput,
    ) -> Self {
        let d = &ctx.device;
        let lookup_bounds = input == DepthInput::Bounds;
        let lists_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lists.group1"),
            entries: &[
                entry(0, UNIFORM),
                entry(1, storage(true)),
                entry(2, storage(true)),
                entry(3, depth_texture(samples)),
                entry(4, storage(false)),
                entry(5, UNIFORM),
            ],
        });
        let pipelines = InputPipelines::new(ctx, &scene.layout, input, subgroups);
        Self {
            gather_subgroups: pipelines.gather_subgroups,
            pipelines,
            float_pipelines: OnceLock::new(),
            subgroups,
            scene_layout: scene.layout.clone(),
            per_pixel: PerPixel::new(d, samples, &scene.layout, &lists_layout),
            samples,
            lookup_bounds,
            lists_layout,
            gather_min_chunk: crate::MIN_CHUNK,
            gather_min_chunk_masked: crate::MIN_CHUNK_MASKED,
            mask_budget: crate::MASK_BUDGET,
            gather_lines: true,
            cluster_tiles_max_lights: crate::CLUSTER_TILES_MAX_LIGHTS,
            cluster_tile_rect_pairs: crate::CLUSTER_TILE_RECT_PAIRS,
            cluster_boxes: true,
            cluster_slice_masks: true,
            cluster_pairs: true,
            cluster_lane_tiles: crate::CLUSTER_LANE_TILES,
            cluster_band_pool: None,
            cluster_sphere_bounds: true,
            cluster_order_bits: true,
            zbin_scatter_min_lights: crate::ZBIN_SCATTER_MIN_LIGHTS,
            scan: Scan::new(ctx),
            sort: RadixSort::new(ctx),
            placeholder: frame::storage_buf(ctx, "cull.placeholder", 16),
            occlusion: None,
        }
    }

    /// The scene's occluders for culling by visibility (`CullSettings::occlusion`), as
    /// [`manylights_scene::occluders::occluders`] chooses them, at most [`OCCLUDERS_MAX`];
    /// none drops nothing.
    pub fn set_occluders(
        &mut self,
        ctx: &GpuContext,
        occluders: &[manylights_scene::occluders::Occluder],
    ) -> Result<(), CullError> {
        if occluders.len() > OCCLUDERS_MAX {
            return Err(CullError::InvalidParameter {
                field: "occluders",
                value: occluders.len().to_string(),
                accepted: "at most 64 (cull.occlusion keeps a bin's candidate occluders in \
                           workgroup memory, one a thread; occluders::of_scene takes the 64 \
                           largest)",
            });
        }
        match &mut self.occlusion {
            Some(o) => o.set(ctx, occluders),
            None => self.occlusion = Some(Occlusion::new(ctx, &self.scene_layout, occluders)),
        }
        Ok(())
    }

    /// The pipelines over `depth`: its own input's, or where it is an `R32Float` depth a
    /// compute pass wrote (and the culler's own input is a single-sample depth buffer) those
    /// over a float depth, built at their first use.
    fn pipelines_for(
        &self,
        ctx: &GpuContext,
        depth: &wgpu::Texture,
    ) -> Result<&InputPipelines, CullError> {
        if depth.format() != wgpu::TextureFormat::R32Float
            || self.pipelines.input == DepthInput::Float
        {
            return Ok(&self.pipelines);
        }
        if self.pipelines.input != DepthInput::Samples(1) {
            return Err(GpuError::Unsupported(format!(
                "culling over an R32Float depth with a culler of {:?}: a float depth is one \
                 sample a pixel",
                self.pipelines.input
            ))
            .into());
        }
        Ok(self.float_pipelines.get_or_init(|| {
            InputPipelines::new(ctx, &self.scene_layout, DepthInput::Float, self.subgroups)
        }))
    }

    /// Runs `strategy` over the depth buffer `depth` of `scene` (whose frame uniform is set for
    /// the depth buffer's size) with `settings`. Two submissions: counts and scan, then (with
    /// the lists sized exactly from the total the scan read back) fill and finalize.
    pub fn run(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::Texture,
        strategy: &Strategy,
        settings: &CullSettings,
        timer: &mut GpuTimer,
    ) -> Result<CullOutput, CullError> {
        self.run_with(ctx, scene, depth, strategy, settings, timer, None, None)
    }

    /// Runs `strategy` `runs` times back to back in one submission, with no host round trip
    /// between or inside the runs, as a renderer does frame after frame: what steady-state
    /// timing measures. The lists are sized from `earlier`, a [`Culler::run`] of the same
    /// scene, depth, strategy and settings; the last run's total is read back and checked
    /// against it ([`CullError::SizeChanged`] where it differs). `timer` records `runs` times
    /// the passes of one run; a timer of spans ([`GpuTimer::spans`]) times each
    /// run as one span, `cull.<strategy>`, with no timestamps between its passes.
    #[allow(
        clippy::too_many_arguments,
        reason = "the inputs of a run, as `run` takes them, and the repeat"
    )]
    pub fn run_repeated(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::Texture,
        strategy: &Strategy,
        settings: &CullSettings,
        earlier: &CullOutput,
        runs: u32,
        timer: &mut GpuTimer,
    ) -> Result<CullOutput, CullError> {
        let repeat = Some(Repeat::after(earlier, runs));
        self.run_with(ctx, scene, depth, strategy, settings, timer, repeat, None)
    }

    /// As [`Culler::run_repeated`], each run followed by `then` (a pass reading its lists, such
    /// as shading) inside its span: a frame's culling and the pass that pays for its lists,
    /// timed together. `timer` records `then`'s passes too.
    #[allow(
        clippy::too_many_arguments,
        reason = "the inputs of a run, as `run` takes them, the repeat and the pass after it"
    )]
    pub fn run_repeated_with(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::Texture,
        strategy: &Strategy,
        settings: &CullSettings,
        earlier: &CullOutput,
        runs: u32,
        timer: &mut GpuTimer,
        then: &mut dyn ListPass,
    ) -> Result<CullOutput, CullError> {
        let repeat = Some(Repeat::after(earlier, runs));
        let then = Some(then);
        self.run_with(ctx, scene, depth, strategy, settings, timer, repeat, then)
    }

    #[allow(
        clippy::too_many_arguments,
        reason = "the inputs of a run, as `run` takes them, and the repeat"
    )]
    fn run_with(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::Texture,
        strategy: &Strategy,
        settings: &CullSettings,
        timer: &mut GpuTimer,
        repeat: Option<Repeat>,
        then: Option<&mut dyn ListPass>,
    ) -> Result<CullOutput, CullError> {
        strategy.validate()?;
        settings.validate()?;
        if settings.occlusion {
            if matches!(strategy, Strategy::ZBin { .. }) {
                return Err(CullError::InvalidParameter {
                    field: "occlusion",
                    value: "true with z-binning".into(),
                    accepted: "culling by visibility over lists of a list a bin: tiled gather, \
                               2.5D, tiled scatter or clusters",
                });
            }
            if self.occlusion.is_none() {
                return Err(CullError::InvalidParameter {
                    field: "occlusion",
                    value: "true before Culler::set_occluders".into(),
                    accepted: "culling by visibility once the scene's occluders are set",
                });
            }
        }
        let params = strategy.params(depth.width(), depth.height(), scene.light_count, settings);
        let inputs = RunInputs {
            culler: self,
            pipelines: self.pipelines_for(ctx, depth)?,
            ctx,
            rec: Recorder {
                ctx,
                scene: &scene.bind_group,
                scan: &self.scan,
                sort: &self.sort,
            },
            depth,
            strategy,
            settings,
            repeat,
        };
        let t = Timing {
            timer,
            then: then.map(|p| p as &mut dyn ListPass),
        };
        match strategy {
            Strategy::TiledGather { .. } => tiled_gather::run(&inputs, params, t),
            Strategy::DepthMask { .. } => depth_mask::run(&inputs, params, t),
            Strategy::TiledScatter { .. } => tiled_scatter::run(&inputs, params, t),
            Strategy::Clustered { .. } => clustered::run(&inputs, params, t),
            Strategy::ZBin { .. } => zbin::run(&inputs, params, t),
        }
    }
}

/// What a strategy's `run` takes besides its parameters.
pub(crate) struct RunInputs<'a> {
    pub culler: &'a Culler,
    /// The culler's pipelines over the run's depth input.
    pub pipelines: &'a InputPipelines,
    pub ctx: &'a GpuContext,
    pub rec: Recorder<'a>,
    pub depth: &'a wgpu::Texture,
    pub strategy: &'a Strategy,
    pub settings: &'a CullSettings,
    pub repeat: Option<Repeat>,
}

/// Where a run's passes are timed, and the pass after each back-to-back run
/// ([`Culler::run_repeated_with`]).
pub(crate) struct Timing<'t> {
    pub timer: &'t mut GpuTimer,
    pub then: Option<&'t mut dyn ListPass>,
}

impl RunInputs<'_> {
    /// The frame's buffers for `params`, with `items` count entries.
    pub fn frame(&self, params: GpuCullParams, items: u64) -> Frame<'_> {
        Frame::new(
            self.ctx,
            &self.pipelines.layout,
            self.depth,
            self.strategy,
            params,
            items,
        )
    }

    /// Records and submits `plan` over `f`, once or back to back.
    pub fn execute<P: Plan>(
        &self,
        f: &Frame<'_>,
        plan: P,
        t: Timing<'_>,
    ) -> Result<Done, CullError> {
        let occlusion = self
            .culler
            .occlusion
            .as_ref()
            .filter(|_| self.settings.occlusion);
        frame::execute(f, &self.rec, plan, t.timer, self.repeat, t.then, occlusion)
    }

    /// Checks that the bins' ranges fit a storage binding.
    pub fn check_bins(&self, p: &GpuCullParams) -> Result<(), CullError> {
        Ok(self.ctx.check_storage("cull bins", u64::from(p.bins) * 8)?)
    }
}

/// Whether gather's subgroup scans apply: subgroup operations, with subgroups that tile each
/// scan's segment (sizes are powers of two; the smallest segment is a lines-path tile's
/// [`LINE_THREADS_MIN`]). Elsewhere (64-wide subgroups) gather takes the portable scans.
pub(crate) fn gather_subgroups_fit(ctx: &GpuContext) -> bool {
    ctx.features.subgroups && ctx.features.subgroup_size.1 <= LINE_THREADS_MIN
}
