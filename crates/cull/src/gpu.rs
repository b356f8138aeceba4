//! The GPU side: pipelines of every culling pass, and their orchestration for one frame.

use manylights_gpu::shaders::{FRAME, LIGHT, SCENE, ShaderDef, ShaderFile};
use manylights_gpu::timing::GpuTimer;
use manylights_gpu::{GpuContext, GpuError, GpuScene, pipeline, readback, shader_file};

use crate::layout::{CULL_CONSTS, GROUPS_X, GpuCullParams, GpuTileDepth};
use crate::radix_sort::{RadixSort, SortedIn, key_bits_for};
use crate::scan::{Scan, groups_2d};
use crate::{CullError, CullSettings, Strategy};

/// Shared culling geometry and parameters.
pub const COMMON: ShaderFile = shader_file!("cull/common.wgsl");
/// List buffers of the culling passes.
pub const LISTS: ShaderFile = shader_file!("cull/lists.wgsl");
/// The pixel-to-list lookup of every list consumer.
pub const LOOKUP: ShaderFile = shader_file!("cull/lookup.wgsl");
/// Tile masks and their fill (in the gather modules, which hold the workgroup scan the fill
/// uses; tiled scatter's count pass that sets them is in its own module).
pub const TILE_MASKS: ShaderFile = shader_file!("cull/tile_masks.wgsl");

/// The tiles' depth data (`cull.depth_bounds`, and gather's lines path's list passes).
pub const TILE_DEPTH: ShaderFile = shader_file!("cull/tile_depth.wgsl");
/// `cull.depth_bounds`, and `cull.tile_lines` (gather's lines path).
pub const DEPTH_BOUNDS: ShaderDef = ShaderDef {
    name: "cull.depth_bounds",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        COMMON,
        shader_file!("cull/depth_bounds.wgsl"),
        TILE_DEPTH,
    ],
};
/// `cull.tiled_gather` (also `cull.depth_mask`, with its flag), `cull.finalize`, and the tile
/// masks' fill (also tiled scatter's), with the portable workgroup scan.
pub const TILED_GATHER: ShaderDef = ShaderDef {
    name: "cull.tiled_gather",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        COMMON,
        LISTS,
        shader_file!("cull/tiled_gather.wgsl"),
        TILE_MASKS,
        shader_file!("cull/tile_lines.wgsl"),
        TILE_DEPTH,
        shader_file!("cull/gather_scan.wgsl"),
    ],
};
/// [`TILED_GATHER`] with its scans in subgroup operations (built only where the device has
/// them).
pub const TILED_GATHER_SUBGROUP: ShaderDef = ShaderDef {
    name: "cull.tiled_gather.subgroup",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        COMMON,
        LISTS,
        shader_file!("cull/tiled_gather.wgsl"),
        TILE_MASKS,
        shader_file!("cull/tile_lines.wgsl"),
        TILE_DEPTH,
        shader_file!("cull/gather_scan_subgroup.wgsl"),
    ],
};
/// `cull.tiled_scatter`: its pairs, and with tile masks its count pass.
pub const TILED_SCATTER: ShaderDef = ShaderDef {
    name: "cull.tiled_scatter",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        COMMON,
        LISTS,
        shader_file!("cull/tiled_scatter.wgsl"),
    ],
};
/// `cull.clustered`, `cull.clustered.order` and `cull.occupancy`.
pub const CLUSTERED: ShaderDef = ShaderDef {
    name: "cull.clustered",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        COMMON,
        LISTS,
        shader_file!("cull/clustered.wgsl"),
    ],
};
/// `cull.lights_per_pixel`: the shared lookup, per pixel.
pub const LIGHTS_PER_PIXEL: ShaderDef = ShaderDef {
    name: "cull.lights_per_pixel",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        COMMON,
        LOOKUP,
        shader_file!("cull/lights_per_pixel.wgsl"),
    ],
};

/// `cull.exact`: the exact per-pixel oracle on the GPU.
pub const EXACT: ShaderDef = ShaderDef {
    name: "cull.exact",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        COMMON,
        LOOKUP,
        shader_file!("cull/exact.wgsl"),
    ],
};

/// Every shader of this crate.
pub const SHADERS: &[ShaderDef] = &[
    DEPTH_BOUNDS,
    TILED_GATHER,
    TILED_GATHER_SUBGROUP,
    TILED_SCATTER,
    CLUSTERED,
    LIGHTS_PER_PIXEL,
    EXACT,
    crate::scan::SHADER,
    crate::scan::SUBGROUP_SHADER,
    crate::radix_sort::SHADER,
    crate::radix_sort::ONESWEEP_SHADER,
];

/// Light lists read back to the host.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BinLists {
    /// (offset, count) per bin.
    pub ranges: Vec<[u32; 2]>,
    /// Light indices.
    pub indices: Vec<u32>,
}

impl BinLists {
    /// The lights of bin `b`.
    pub fn list(&self, b: usize) -> &[u32] {
        let [o, c] = self.ranges[b];
        &self.indices[o as usize..(o + c) as usize]
    }

    /// The lights of bin `b`, sorted.
    pub fn sorted(&self, b: usize) -> Vec<u32> {
        let mut v = self.list(b).to_vec();
        v.sort_unstable();
        v
    }
}

/// The lists of one frame on the GPU, ready for shading.
pub struct CullOutput {
    /// The parameters they were built with.
    pub params: GpuCullParams,
    /// The `CullParams` uniform.
    pub params_buf: wgpu::Buffer,
    /// `bin_ranges`.
    pub ranges: wgpu::Buffer,
    /// `light_indices` (at least one element).
    pub indices: wgpu::Buffer,
    /// Total list entries.
    pub total: u32,
    /// Lights dropped by a deliberate capacity (0 without one).
    pub dropped: u32,
    /// Per-tile depth data (tiled strategies).
    pub tile_depth: wgpu::Buffer,
    /// Cluster occupancy (clusters with `skip_empty`).
    pub occupancy: wgpu::Buffer,
    /// The tile masks, where the run used them (gather's and 2.5D's coarse-to-fine passes, and
    /// tiled scatter, within [`Culler::mask_budget`]). Every fill leaves them all zero, as the
    /// next count pass needs (see `shaders/cull/tile_masks.wgsl`).
    pub tile_masks: Option<wgpu::Buffer>,
    /// The tile lines, where the run took gather's and 2.5D's lines path (within
    /// [`Culler::mask_budget`], with [`Culler::gather_lines`]): for each column of tiles, then
    /// each row, then each depth bin, two words for each 64 lights, and after them each light's
    /// depth extent (see `shaders/cull/tile_lines.wgsl`).
    pub tile_lines: Option<wgpu::Buffer>,
}

impl CullOutput {
    /// Whether the run decided its lists as a bit per (tile, light): with tile masks, or with
    /// tile lines (whose per-tile words are never stored). The `tile_masks` result column.
    pub fn used_tile_masks(&self) -> bool {
        self.tile_masks.is_some() || self.tile_lines.is_some()
    }

    /// Reads the tile lines back (their words, not the lights' depth extents after them),
    /// where the run used them.
    pub fn read_tile_lines(&self, ctx: &GpuContext) -> Result<Option<Vec<u32>>, GpuError> {
        read_words(ctx, self.tile_lines.as_ref(), lines_bytes(&self.params))
    }

    /// The lists' bindings 0, 1, 2 (`CullParams`, `bin_ranges`, `light_indices`), as every
    /// consumer's bind group starts.
    pub fn list_bindings(&self) -> [wgpu::BindingResource<'_>; 3] {
        [
            self.params_buf.as_entire_binding(),
            self.ranges.as_entire_binding(),
            self.indices.as_entire_binding(),
        ]
    }

    /// Bytes of the lists: ranges plus indices.
    pub fn list_bytes(&self) -> u64 {
        u64::from(self.params.bins) * 8 + u64::from(self.total) * 4
    }

    /// Reads the lists back.
    pub fn read(&self, ctx: &GpuContext) -> Result<BinLists, GpuError> {
        let ranges = readback::read_buffer(ctx, &self.ranges, 0, u64::from(self.params.bins) * 8)?;
        let indices = if self.total > 0 {
            readback::read_buffer(ctx, &self.indices, 0, u64::from(self.total) * 4)?
        } else {
            Vec::new()
        };
        Ok(BinLists {
            ranges: bytemuck::pod_collect_to_vec(&ranges),
            indices: bytemuck::pod_collect_to_vec(&indices),
        })
    }

    /// Reads the per-tile depth data back (meaningful for tiled strategies).
    pub fn read_tile_depth(&self, ctx: &GpuContext) -> Result<Vec<GpuTileDepth>, GpuError> {
        let n = u64::from(self.params.tiles_x * self.params.tiles_y);
        Ok(bytemuck::pod_collect_to_vec(&readback::read_buffer(
            ctx,
            &self.tile_depth,
            0,
            n * 16,
        )?))
    }

    /// Reads the tile masks back, where the run used them.
    pub fn read_tile_masks(&self, ctx: &GpuContext) -> Result<Option<Vec<u32>>, GpuError> {
        read_words(ctx, self.tile_masks.as_ref(), mask_bytes(&self.params))
    }

    /// Reads the cluster occupancy back (meaningful with `skip_empty`).
    pub fn read_occupancy(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        Ok(bytemuck::pod_collect_to_vec(&readback::read_buffer(
            ctx,
            &self.occupancy,
            0,
            u64::from(self.params.bins) * 4,
        )?))
    }
}

/// Workgroups of `cull.depth_bounds`: [`crate::layout::DEPTH_TILES`] tiles of a row each, and
/// with `rects` rows before the tiles' that store the lights' tile rectangles, a light a thread.
fn depth_groups(p: &GpuCullParams, rects: bool) -> (u32, u32) {
    let x = p.tiles_x.div_ceil(crate::layout::DEPTH_TILES);
    let rows = if rects {
        p.light_count.div_ceil(x * 64 * crate::layout::DEPTH_TILES)
    } else {
        0
    };
    (x, p.tiles_y + rows)
}

/// Workgroups of `cull.tile_lines` (gather's lines path): one for each 64 `DEPTH_TILES` lights
/// and [`crate::layout::LINES_PER_GROUP`] lines of tiles.
fn tile_lines_groups(p: &GpuCullParams) -> (u32, u32) {
    let chunks =
        (p.tiles_x + p.tiles_y + crate::layout::ZBINS).div_ceil(crate::layout::LINES_PER_GROUP);
    let groups = p.light_count.div_ceil(64 * crate::layout::DEPTH_TILES) * chunks;
    groups_2d(groups, GROUPS_X)
}

/// Workgroups of the tile masks' fill: [`crate::layout::MASK_FILL_TILES`] tiles of a row each.
fn mask_fill_groups(p: &GpuCullParams) -> (u32, u32) {
    (
        p.tiles_x.div_ceil(crate::layout::MASK_FILL_TILES),
        p.tiles_y,
    )
}

/// Workgroups of the list passes of gather's lines path:
/// [`crate::layout::LINE_GROUP_THREADS`] / [`crate::layout::line_threads`] tiles of a row each.
fn lines_fill_groups(p: &GpuCullParams) -> (u32, u32) {
    let tiles = crate::layout::LINE_GROUP_THREADS / crate::layout::line_threads(p.light_count);
    (p.tiles_x.div_ceil(tiles), p.tiles_y)
}

/// The first `bytes` of `buf` as words, where there is a buffer.
fn read_words(
    ctx: &GpuContext,
    buf: Option<&wgpu::Buffer>,
    bytes: u64,
) -> Result<Option<Vec<u32>>, GpuError> {
    buf.map(|b| {
        Ok(bytemuck::pod_collect_to_vec(&readback::read_buffer(
            ctx, b, 0, bytes,
        )?))
    })
    .transpose()
}

/// Bytes of the tile lines (`shaders/cull/tile_lines.wgsl`): two words a column or row of
/// tiles or depth bin for each 64 lights.
fn lines_bytes(p: &GpuCullParams) -> u64 {
    u64::from(p.tiles_x + p.tiles_y + crate::layout::ZBINS)
        * u64::from(p.light_count.div_ceil(64))
        * 8
}

/// Bytes of the tile lines and, after them, each light's depth extent (four f32).
fn lines_buffer_bytes(p: &GpuCullParams) -> u64 {
    lines_bytes(p) + u64::from(p.light_count) * 16
}

/// Bytes of the tile masks: two words a tile for each 64 lights.
fn mask_bytes(p: &GpuCullParams) -> u64 {
    u64::from(p.bins) * u64::from(p.light_count.div_ceil(64)) * 8
}

/// Pipelines of every culling pass.
pub struct Culler {
    layout: wgpu::BindGroupLayout,
    /// Layout of group 1 for list consumers (shading, `cull.lights_per_pixel`): 0 params,
    /// 1 ranges, 2 indices, 3 depth, 4 a per-pixel output.
    pub lists_layout: wgpu::BindGroupLayout,
    depth_bounds: wgpu::ComputePipeline,
    depth_bounds_blocks: wgpu::ComputePipeline,
    tile_lines: wgpu::ComputePipeline,
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
    /// writes its list (`shaders/cull/tile_lines.wgsl`); false: the count pass stores tile masks
    /// and the fill expands them.
    pub gather_lines: bool,
    gather_count: wgpu::ComputePipeline,
    /// For each of `layout::LINE_THREAD_COUNTS`.
    gather_lines_count: [wgpu::ComputePipeline; 3],
    gather_lines_fill: [wgpu::ComputePipeline; 3],
    gather_count_masks: wgpu::ComputePipeline,
    gather_fill_masks: wgpu::ComputePipeline,
    scatter_masks: wgpu::ComputePipeline,
    gather_count_flat: wgpu::ComputePipeline,
    gather_fill_flat: wgpu::ComputePipeline,
    gather_fill: wgpu::ComputePipeline,
    clustered_count: wgpu::ComputePipeline,
    clustered_fill: wgpu::ComputePipeline,
    clustered_count_wide: wgpu::ComputePipeline,
    clustered_fill_wide: wgpu::ComputePipeline,
    clustered_wide_args: wgpu::ComputePipeline,
    cluster_order: wgpu::ComputePipeline,
    cluster_order_short: wgpu::ComputePipeline,
    occupancy: wgpu::ComputePipeline,
    finalize: wgpu::ComputePipeline,
    cap: wgpu::ComputePipeline,
    lights_per_pixel: wgpu::ComputePipeline,
    exact: wgpu::ComputePipeline,
    scatter: [wgpu::ComputePipeline; 4],
    scan: Scan,
    sort: RadixSort,
    /// Bound where a strategy has no buffer for a binding (made once, not per run).
    placeholder: wgpu::Buffer,
}

/// A binding of the culling groups (visible to compute and, for list consumers, fragments).
fn entry(binding: u32, ty: wgpu::BindingType) -> wgpu::BindGroupLayoutEntry {
    pipeline::entry(
        binding,
        wgpu::ShaderStages::COMPUTE | wgpu::ShaderStages::FRAGMENT,
        ty,
    )
}

use pipeline::{DEPTH_TEXTURE as DEPTH, UNIFORM, storage};

/// The module of one shader and its pipeline layout, over group 0 (the scene) and `group1`.
fn program(
    d: &wgpu::Device,
    def: &ShaderDef,
    scene_layout: &wgpu::BindGroupLayout,
    group1: &wgpu::BindGroupLayout,
) -> (wgpu::ShaderModule, wgpu::PipelineLayout) {
    (
        def.create(d),
        pipeline::layout(d, def.name, &[scene_layout, group1]),
    )
}

/// Compute pipelines for the entry points of one shader, over group 0 (the scene) and `group1`.
fn pipelines<const N: usize>(
    d: &wgpu::Device,
    def: &ShaderDef,
    scene_layout: &wgpu::BindGroupLayout,
    group1: &wgpu::BindGroupLayout,
    entries: [&str; N],
) -> [wgpu::ComputePipeline; N] {
    let (module, pl) = program(d, def, scene_layout, group1);
    entries.map(|e| pipeline::compute(d, &module, &pl, e))
}

/// Entry point `entry` of `module` built once for each of
/// [`crate::layout::LINE_THREAD_COUNTS`] (the shader's `LINE_THREADS` override): the lines
/// path's list passes.
fn line_pipelines(
    d: &wgpu::Device,
    module: &wgpu::ShaderModule,
    pl: &wgpu::PipelineLayout,
    entry: &str,
) -> [wgpu::ComputePipeline; 3] {
    crate::layout::LINE_THREAD_COUNTS.map(|t| {
        let constants = [("LINE_THREADS", f64::from(t))];
        // (Without zeroing workgroup memory, which these passes do not need, measured the same
        // on an H100.)
        let options = wgpu::PipelineCompilationOptions {
            constants: &constants,
            ..Default::default()
        };
        pipeline::compute_with(d, module, pl, entry, &options)
    })
}

/// The lines path's pipeline of `set` for `light_count` lights ([`crate::layout::line_threads`]).
fn line_pipeline(set: &[wgpu::ComputePipeline; 3], light_count: u32) -> &wgpu::ComputePipeline {
    let t = crate::layout::line_threads(light_count);
    let i = crate::layout::LINE_THREAD_COUNTS
        .iter()
        .position(|&c| c == t)
        .expect("line_threads returns one of LINE_THREAD_COUNTS");
    &set[i]
}

impl Culler {
    /// Builds every pipeline for scenes laid out as [`GpuScene`].
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Self {
        Self::with_subgroups(ctx, scene, true)
    }

    /// As [`Culler::new`]; with `subgroups` false, gather keeps its portable scans even where
    /// the device has subgroup operations (both paths give the same lists; the tests run both).
    pub fn with_subgroups(ctx: &GpuContext, scene: &GpuScene, subgroups: bool) -> Self {
        let d = &ctx.device;
        let mut entries = vec![entry(0, UNIFORM), entry(1, DEPTH)];
        entries.extend((2..=11).map(|b| entry(b, storage(false))));
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cull.group1"),
            entries: &entries,
        });
        let lists_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lists.group1"),
            entries: &[
                entry(0, UNIFORM),
                entry(1, storage(true)),
                entry(2, storage(true)),
                entry(3, DEPTH),
                entry(4, storage(false)),
                entry(5, UNIFORM),
            ],
        });
        let scene_layout = &scene.layout;
        let [depth_bounds, depth_bounds_blocks, tile_lines] = pipelines(
            d,
            &DEPTH_BOUNDS,
            scene_layout,
            &layout,
            ["depth_bounds", "depth_bounds_blocks", "tile_lines_pass"],
        );
        let gather_subgroups = subgroups && gather_subgroups_fit(ctx);
        let gather_def = if gather_subgroups {
            &TILED_GATHER_SUBGROUP
        } else {
            &TILED_GATHER
        };
        // One module for all of gather's pipelines.
        let (gather_module, gather_pl) = program(d, gather_def, scene_layout, &layout);
        let gather_lines_count =
            line_pipelines(d, &gather_module, &gather_pl, "gather_lines_count");
        let gather_lines_fill = line_pipelines(d, &gather_module, &gather_pl, "gather_lines_fill");
        let [
            gather_count,
            gather_fill,
            gather_count_masks,
            gather_fill_masks,
            gather_count_flat,
            gather_fill_flat,
            finalize,
            cap,
        ] = [
            "gather_count",
            "gather_fill",
            "gather_count_masks",
            "gather_fill_masks",
            "gather_count_flat",
            "gather_fill_flat",
            "finalize",
            "cap_counts",
        ]
        .map(|e| pipeline::compute(d, &gather_module, &gather_pl, e));
        let [
            clustered_count,
            clustered_fill,
            clustered_count_wide,
            clustered_fill_wide,
            clustered_wide_args,
            cluster_order,
            cluster_order_short,
            occupancy,
        ] = pipelines(
            d,
            &CLUSTERED,
            scene_layout,
            &layout,
            [
                "clustered_count",
                "clustered_fill",
                "clustered_count_wide",
                "clustered_fill_wide",
                "clustered_wide_args",
                "cluster_order",
                "cluster_order_short",
                "cluster_occupancy",
            ],
        );
        let [
            scatter_count,
            scatter_pairs,
            scatter_ranges,
            scatter_finalize,
            scatter_masks,
        ] = pipelines(
            d,
            &TILED_SCATTER,
            scene_layout,
            &layout,
            [
                "scatter_count",
                "scatter_pairs",
                "scatter_ranges",
                "scatter_finalize",
                "scatter_masks",
            ],
        );
        let scatter = [
            scatter_count,
            scatter_pairs,
            scatter_ranges,
            scatter_finalize,
        ];
        let [lights_per_pixel] = pipelines(
            d,
            &LIGHTS_PER_PIXEL,
            scene_layout,
            &lists_layout,
            ["lights_per_pixel"],
        );
        let [exact] = pipelines(d, &EXACT, scene_layout, &lists_layout, ["exact_counts"]);
        Self {
            layout,
            lists_layout,
            depth_bounds,
            depth_bounds_blocks,
            tile_lines,
            gather_subgroups,
            gather_min_chunk: crate::MIN_CHUNK,
            gather_min_chunk_masked: crate::MIN_CHUNK_MASKED,
            mask_budget: crate::MASK_BUDGET,
            gather_lines: true,
            gather_count,
            gather_lines_count,
            gather_lines_fill,
            gather_fill,
            gather_count_masks,
            gather_fill_masks,
            scatter_masks,
            gather_count_flat,
            gather_fill_flat,
            clustered_count,
            clustered_fill,
            clustered_count_wide,
            clustered_fill_wide,
            clustered_wide_args,
            cluster_order,
            cluster_order_short,
            occupancy,
            finalize,
            cap,
            lights_per_pixel,
            exact,
            scatter,
            scan: Scan::new(ctx),
            sort: RadixSort::new(ctx),
            placeholder: storage_buf(ctx, "cull.placeholder", 16),
        }
    }

    /// Whether tile masks may serve `p` (gather also needs its coarse level): no capacity,
    /// masks within [`Culler::mask_budget`] and the device's buffers, and bins x lights within
    /// u32 (the masked count passes sum the total in a u32).
    fn masks_fit(&self, ctx: &GpuContext, p: &GpuCullParams, settings: &CullSettings) -> bool {
        p.capacity == 0
            && p.light_count > 0
            && u64::from(p.bins) * u64::from(p.light_count) < 1 << 32
            && mask_bytes(p)
                <= settings.mask_budget.unwrap_or(self.mask_budget).min(
                    ctx.limits
                        .max_storage_buffer_binding_size
                        .min(ctx.limits.max_buffer_size),
                )
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
        self.run_with(ctx, scene, depth, strategy, settings, timer, None)
    }

    /// Runs `strategy` `runs` times back to back in one submission, with no host round trip
    /// between or inside the runs, as a renderer does frame after frame: what steady-state
    /// timing measures. The lists are sized from `earlier`, a [`Culler::run`] of the same
    /// scene, depth, strategy and settings; the last run's total is read back and checked
    /// against it ([`CullError::SizeChanged`] where it differs). `timer` needs room for
    /// `runs` times the passes of one run; a timer of spans ([`GpuTimer::spans`]) times each
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
        let repeat = Repeat {
            total: earlier.total,
            runs: runs.max(1),
        };
        self.run_with(ctx, scene, depth, strategy, settings, timer, Some(repeat))
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
    ) -> Result<CullOutput, CullError> {
        strategy.validate()?;
        settings.validate()?;
        let (w, h) = (depth.width(), depth.height());
        let mut params = strategy.params(w, h, scene.light_count, settings);
        let clustered = matches!(strategy, Strategy::Clustered { .. });
        let per_light = matches!(strategy, Strategy::TiledScatter { .. });
        // Tile masks serve scatter and gather's coarse-to-fine passes.
        let maskable = |p: &GpuCullParams| per_light || (!clustered && p.coarse > 0);
        // Decided before the chunks are fitted (their chunks are smaller); fitting may still
        // drop gather's coarse level, and the masks with it.
        let masked = maskable(&params) && self.masks_fit(ctx, &params, settings);
        let min_chunk = if masked {
            self.gather_min_chunk_masked
        } else {
            self.gather_min_chunk
        };
        crate::fit_chunks(
            &mut params,
            (ctx.limits
                .max_storage_buffer_binding_size
                .min(ctx.limits.max_buffer_size)
                / 4)
            .min(crate::MAX_CHUNK_ENTRIES),
            ctx.limits.max_compute_workgroups_per_dimension,
            min_chunk,
        );
        let masked = masked && maskable(&params);
        ctx.check_storage("cull bins", u64::from(params.bins) * 8)?;
        if clustered {
            ctx.check_storage(
                "clusters' wide-light queue",
                (u64::from(params.light_count) + 1) * 16,
            )?;
        }
        // Rows of light rectangles: gather's coarse-to-fine passes, and scatter's masks.
        let (_, depth_rows) = depth_groups(
            &params,
            (!clustered && params.coarse > 0) || (per_light && masked),
        );
        if depth_rows > ctx.limits.max_compute_workgroups_per_dimension {
            return Err(GpuError::OverLimit {
                what: "cull.depth_bounds workgroup rows (tiles and light rectangles)".into(),
                value: depth_rows.into(),
                limit: ctx.limits.max_compute_workgroups_per_dimension.into(),
                limit_name: "max_compute_workgroups_per_dimension",
            }
            .into());
        }
        if per_light && !masked {
            ctx.check_storage(
                "tiled scatter per-lane counts",
                (u64::from(params.light_count) * u64::from(crate::layout::SCATTER_LANES) + 1) * 4,
            )?;
        }
        let f = Frame::new(
            self,
            ctx,
            scene,
            depth,
            strategy,
            params,
            per_light && !masked,
        );
        match strategy {
            Strategy::TiledScatter { .. } if masked => {
                self.run_scatter_masks(ctx, f, timer, repeat)
            }
            Strategy::TiledScatter { .. } => self.run_scatter(ctx, f, timer, repeat),
            _ if masked && self.gather_lines => self.run_lines(f, strategy, timer, repeat),
            _ => self.run_binned(ctx, f, strategy, masked, timer, repeat),
        }
    }

    /// Gather, 2.5D and clusters: a count pass and a fill pass over bins; `masked`: gather with
    /// tile masks.
    fn run_binned(
        &self,
        ctx: &GpuContext,
        f: Frame<'_>,
        strategy: &Strategy,
        masked: bool,
        timer: &mut GpuTimer,
        repeat: Option<Repeat>,
    ) -> Result<CullOutput, CullError> {
        let p = f.params;
        let name = strategy.name();
        let clustered = matches!(strategy, Strategy::Clustered { .. });
        // Gather's coarse-to-fine passes: a workgroup per (coarse tile, chunk of lights), and a
        // count per (tile, chunk), or per tile with tile masks; each light's tile rectangle
        // first.
        let chunked = !clustered && p.coarse > 0;
        let (count, fill_pipe) = if clustered {
            (&self.clustered_count, &self.clustered_fill)
        } else if masked {
            (&self.gather_count_masks, &self.gather_fill_masks)
        } else if chunked {
            (&self.gather_count, &self.gather_fill)
        } else {
            (&self.gather_count_flat, &self.gather_fill_flat)
        };
        // Clusters: a thread a light, then CLUSTER_LANES threads for each wide light (the queue
        // and the indirect dispatch of clustered.wgsl).
        let main = if clustered {
            groups_2d(p.light_count.div_ceil(64), GROUPS_X)
        } else {
            (p.tiles_x, p.tiles_y)
        };
        let placeholder = &self.placeholder;
        let wide_bufs = clustered.then(|| {
            (
                f.buf(
                    "cull.clustered.wide_lights",
                    (u64::from(p.light_count) + 1) * 16,
                ),
                f.ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("cull.clustered.wide_args"),
                    size: 16,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
                    mapped_at_creation: false,
                }),
            )
        });
        let rects = chunked.then(|| f.buf("cull.light_rects", u64::from(p.light_count) * 8));
        let masks = masked.then(|| f.buf("cull.tile_masks", mask_bytes(&p)));
        // Binding 9: the clusters' wide-light queue, or gather's light rectangles; 11: the
        // clusters' indirect arguments, or gather's tile masks.
        let (wide, wide_args) = match (&wide_bufs, &rects) {
            (Some((w, a)), _) => (w, a),
            (None, Some(r)) => (r, masks.as_ref().unwrap_or(placeholder)),
            (None, None) => (placeholder, placeholder),
        };
        // The indirect arguments are written in one pass and read by the next: a buffer bound
        // for storage in a dispatch cannot also be its indirect buffer. So binding 11 of the
        // count and fill passes is the tile masks or nothing.
        let binding_11 = if masked { wide_args } else { placeholder };
        let group_a = f.group(placeholder, wide, binding_11);
        let group_args = f.group(placeholder, wide, wide_args);
        let chunk_groups = [
            p.coarse_x,
            p.tiles_y.div_ceil(p.coarse.max(1)),
            p.light_count.div_ceil(p.chunk.max(1)),
        ];
        let entries = f.entries_counted();
        let groups = if chunked {
            chunk_groups
        } else {
            [main.0, main.1, 1]
        };
        // The tile masks' fill: MASK_FILL_TILES tiles a workgroup.
        let fill_groups = if masked {
            let (x, y) = mask_fill_groups(&p);
            [x, y, 1]
        } else {
            groups
        };
        // The count or fill pass, and for clusters its wide lights' pass (after the count
        // pass, the queue's dispatch arguments).
        let phase = |enc: &mut wgpu::CommandEncoder,
                     timer: &mut GpuTimer,
                     fill: bool,
                     group: &wgpu::BindGroup| {
            let (what, pipe, wide_pipe) = if fill {
                ("fill", fill_pipe, &self.clustered_fill_wide)
            } else {
                ("count", count, &self.clustered_count_wide)
            };
            f.pass_3d(
                enc,
                timer,
                &format!("cull.{name}.{what}"),
                pipe,
                group,
                if fill { fill_groups } else { groups },
            );
            if clustered {
                if !fill {
                    f.pass(
                        enc,
                        timer,
                        "cull.clustered.wide_args",
                        &self.clustered_wide_args,
                        &group_args,
                        (1, 1),
                    );
                }
                f.pass_indirect(
                    enc,
                    timer,
                    &format!("cull.clustered.{what}_wide"),
                    wide_pipe,
                    group,
                    wide_args,
                );
            }
        };
        // Everything up to the scanned counts.
        let counting = |enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer, _sized: bool| {
            f.clear(enc, masked);
            if clustered {
                enc.clear_buffer(wide, 0, Some(4));
                if p.flags & crate::layout::CULL_FLAG_SKIP_EMPTY != 0 {
                    f.pass(
                        enc,
                        timer,
                        "cull.occupancy",
                        &self.occupancy,
                        &group_a,
                        (f.w.div_ceil(8), f.h.div_ceil(8)),
                    );
                }
            } else {
                // With the lights' rectangles for the coarse-to-fine passes (binding 9).
                f.pass(
                    enc,
                    timer,
                    "cull.depth_bounds",
                    &self.depth_bounds,
                    &group_a,
                    depth_groups(&p, chunked),
                );
            }
            phase(enc, timer, false, &group_a);
            if p.capacity != 0 {
                f.pass(
                    enc,
                    timer,
                    "cull.cap",
                    &self.cap,
                    &group_a,
                    groups_2d(p.bins.div_ceil(64), GROUPS_X),
                );
            }
            // (With tile masks the count pass sums the total itself and the fill places each
            // tile's list with an atomic add: no scan.)
            if !masked {
                f.encode_scan(ctx, &self.scan, enc, entries, timer);
            }
        };
        // The exact list total after the count pass.
        let total_of = |ctx: &GpuContext| {
            if masked {
                f.masked_total(ctx)
            } else {
                f.bins_total(ctx, entries)
            }
        };
        // The lists, once the index buffer is sized.
        let filling = |enc: &mut wgpu::CommandEncoder,
                       timer: &mut GpuTimer,
                       group_b: &wgpu::BindGroup,
                       _sized: bool| {
            phase(enc, timer, true, group_b);
            if matches!(strategy, Strategy::Clustered { ordered: true, .. }) {
                for (label, pipe) in [
                    ("cull.clustered.order_short", &self.cluster_order_short),
                    ("cull.clustered.order", &self.cluster_order),
                ] {
                    f.pass(
                        enc,
                        timer,
                        label,
                        pipe,
                        group_b,
                        groups_2d(p.bins, GROUPS_X),
                    );
                }
            }
            // (Coarse-to-fine gather's fill writes the ranges itself.)
            if !chunked {
                f.pass(
                    enc,
                    timer,
                    "cull.finalize",
                    &self.finalize,
                    group_b,
                    groups_2d(p.bins.div_ceil(64), GROUPS_X),
                );
            }
        };
        let (indices, total) = f.count_then_fill(
            timer,
            repeat,
            &counting,
            &total_of,
            &|indices| f.group(indices, wide, binding_11),
            &filling,
        )?;
        Ok(f.finish(indices, total, masks.clone(), None)?)
    }

    /// Gather's and 2.5D's lines path: `cull.tile_lines`, then each tile's depth data and list
    /// in one pass (`shaders/cull/tile_lines.wgsl`). Alone, a count pass of the same kind first
    /// sizes the lists; back to back, a run is the two passes.
    fn run_lines(
        &self,
        f: Frame<'_>,
        strategy: &Strategy,
        timer: &mut GpuTimer,
        repeat: Option<Repeat>,
    ) -> Result<CullOutput, CullError> {
        let p = f.params;
        let name = strategy.name();
        let lines = f.buf("cull.tile_lines", lines_buffer_bytes(&p));
        let placeholder = &self.placeholder;
        let group_a = f.group(placeholder, placeholder, &lines);
        let groups = lines_fill_groups(&p);
        // No clear: `cull.tile_lines` zeroes the list passes' cursor, the only counter these
        // runs use (a clear is a transfer of its own between passes).
        let counting = |enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer, sized: bool| {
            f.pass(
                enc,
                timer,
                "cull.tile_lines",
                &self.tile_lines,
                &group_a,
                tile_lines_groups(&p),
            );
            if !sized {
                f.pass(
                    enc,
                    timer,
                    &format!("cull.{name}.count"),
                    line_pipeline(&self.gather_lines_count, p.light_count),
                    &group_a,
                    groups,
                );
            }
        };
        let filling = |enc: &mut wgpu::CommandEncoder,
                       timer: &mut GpuTimer,
                       group_b: &wgpu::BindGroup,
                       sized: bool| {
            if !sized {
                // The count pass left its total in the fill's cursor.
                enc.clear_buffer(&f.stats, 20, Some(4));
            }
            f.pass(
                enc,
                timer,
                &format!("cull.{name}.fill"),
                line_pipeline(&self.gather_lines_fill, p.light_count),
                group_b,
                groups,
            );
        };
        let (indices, total) = f.count_then_fill(
            timer,
            repeat,
            &counting,
            &|ctx| f.lines_total(ctx),
            &|indices| f.group(indices, placeholder, &lines),
            &filling,
        )?;
        Ok(f.finish(indices, total, None, Some(lines.clone()))?)
    }

    /// Tiled scatter with tile masks: the depth-bounds pass also stores each light's rectangle
    /// and queues its blocks of tiles; the count pass sets each light's bit in every tile of
    /// its rectangle that keeps it, a block a workgroup at a time; and the fill expands each
    /// tile's bits into its list (`shaders/cull/tile_masks.wgsl`): no pairs, no sort.
    fn run_scatter_masks(
        &self,
        ctx: &GpuContext,
        f: Frame<'_>,
        timer: &mut GpuTimer,
        repeat: Option<Repeat>,
    ) -> Result<CullOutput, CullError> {
        let p = f.params;
        let masks = f.buf("cull.tile_masks", mask_bytes(&p));
        let rects = f.buf("cull.light_rects", u64::from(p.light_count) * 8);
        // At most every tile of the screen for each light, in blocks.
        let blocks = u64::from(p.light_count)
            * u64::from(p.bins.div_ceil(crate::layout::SCATTER_MASK_THREADS));
        ctx.check_storage("tiled scatter's block queue", blocks * 8)?;
        let queue = f.buf("cull.tiled_scatter.blocks", blocks * 8);
        // Binding 7: the block queue, until the fill binds the lists there.
        let group_a = f.group(&queue, &rects, &masks);
        let groups = u32::try_from(blocks.min(u64::from(crate::layout::SCATTER_MASK_GROUPS)))
            .expect("at most SCATTER_MASK_GROUPS");
        let counting = |enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer, _sized: bool| {
            f.clear(enc, true);
            f.pass(
                enc,
                timer,
                "cull.depth_bounds",
                &self.depth_bounds_blocks,
                &group_a,
                depth_groups(&p, true),
            );
            f.pass(
                enc,
                timer,
                "cull.tiled_scatter.count",
                &self.scatter_masks,
                &group_a,
                (groups, 1),
            );
        };
        let filling = |enc: &mut wgpu::CommandEncoder,
                       timer: &mut GpuTimer,
                       group_b: &wgpu::BindGroup,
                       _sized: bool| {
            f.pass(
                enc,
                timer,
                "cull.tiled_scatter.fill",
                &self.gather_fill_masks,
                group_b,
                mask_fill_groups(&p),
            );
        };
        let (indices, total) = f.count_then_fill(
            timer,
            repeat,
            &counting,
            &|ctx| f.masked_total(ctx),
            &|indices| f.group(indices, &rects, &masks),
            &filling,
        )?;
        Ok(f.finish(indices, total, Some(masks.clone()), None)?)
    }

    /// Tiled scatter: per-light pair counts, their scan, the pairs, the radix sort by tile, and
    /// each tile's start and end.
    fn run_scatter(
        &self,
        ctx: &GpuContext,
        f: Frame<'_>,
        timer: &mut GpuTimer,
        repeat: Option<Repeat>,
    ) -> Result<CullOutput, CullError> {
        let p = f.params;
        let [count, pairs_pipe, ranges, finalize] = &self.scatter;
        let work = p.light_count * crate::layout::SCATTER_LANES;
        let light_groups = groups_2d(work.div_ceil(64), GROUPS_X);
        let placeholder = &self.placeholder;
        let group_a = f.group(placeholder, placeholder, placeholder);
        let counting = |enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer| {
            f.clear(enc, false);
            f.pass(
                enc,
                timer,
                "cull.depth_bounds",
                &self.depth_bounds,
                &group_a,
                depth_groups(&p, false),
            );
            f.pass(
                enc,
                timer,
                "cull.tiled_scatter.count",
                count,
                &group_a,
                light_groups,
            );
            f.encode_scan(ctx, &self.scan, enc, work, timer);
        };
        let pairs = match repeat {
            Some(r) => r.total,
            None => {
                let mut enc = ctx.encoder("cull.tiled_scatter.count");
                counting(&mut enc, timer);
                ctx.submit_and_wait(enc, "culling: count and scan")?;
                Frame::entries(
                    ctx,
                    "tiled scatter pairs",
                    "tiled scatter pairs",
                    f.pairs_total(ctx)?,
                )?
            }
        };
        let (keys, vals) = (
            f.buf("cull.pair_keys", u64::from(pairs) * 4),
            f.buf("cull.light_indices", u64::from(pairs) * 4),
        );
        let (keys_tmp, vals_tmp) = (
            f.buf("cull.pair_keys.tmp", u64::from(pairs) * 4),
            f.buf("cull.light_indices.tmp", u64::from(pairs) * 4),
        );
        let group_pairs = f.group(&vals, &keys, placeholder);
        let bits = key_bits_for(p.bins.saturating_sub(1));
        // The pairs, their sort by tile, and each tile's range; the sorted pairs' buffers.
        let sorting = |enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer| {
            f.pass(
                enc,
                timer,
                "cull.tiled_scatter.pairs",
                pairs_pipe,
                &group_pairs,
                light_groups,
            );
            let sorted = self.sort.encode(
                ctx, enc, &keys, &vals, &keys_tmp, &vals_tmp, pairs, bits, timer,
            )?;
            let group_c = match sorted {
                SortedIn::Input => f.group(&vals, &keys, placeholder),
                SortedIn::Scratch => f.group(&vals_tmp, &keys_tmp, placeholder),
            };
            f.pass(
                enc,
                timer,
                "cull.tiled_scatter.ranges",
                ranges,
                &group_c,
                groups_2d(pairs.div_ceil(64), GROUPS_X),
            );
            f.pass(
                enc,
                timer,
                "cull.finalize",
                finalize,
                &group_c,
                groups_2d(p.bins.div_ceil(64), GROUPS_X),
            );
            Ok::<_, GpuError>(sorted)
        };
        let mut enc = ctx.encoder("cull.tiled_scatter.sort");
        let mut sorted = SortedIn::Input;
        for _ in 0..repeat.map_or(1, |r| r.runs) {
            if repeat.is_some() {
                timer.span_begin(&mut enc, &f.span);
                counting(&mut enc, timer);
            }
            sorted = sorting(&mut enc, timer)?;
            timer.span_end(&mut enc);
        }
        timer.resolve(&mut enc);
        ctx.submit_and_wait(enc, "culling: tiled scatter")?;
        if let Some(r) = repeat {
            r.check(f.pairs_total(ctx)?)?;
        }
        let vals = match sorted {
            SortedIn::Input => vals,
            SortedIn::Scratch => vals_tmp,
        };
        Ok(f.finish(vals, pairs, None, None)?)
    }

    /// The length of the list each pixel reads through the shared lookup (0 for background).
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
            &self.lights_per_pixel,
            1,
            bytemuck::bytes_of(&[0u32; 4]),
        )
    }

    /// The exact per-pixel oracle on the GPU: per pixel `[evaluated, needed, found, covered]`
    /// (see `shaders/cull/exact.wgsl`); `world_from_clip` is the inverse of the frame's
    /// `clip_from_world`; only pixels on a grid of `stride` are evaluated (1: all).
    pub fn exact_counts(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::Texture,
        lists: &CullOutput,
        world_from_clip: glam::Mat4,
        stride: u32,
    ) -> Result<Vec<[u32; 4]>, GpuError> {
        let params = crate::layout::GpuExactParams {
            world_from_clip,
            stride: stride.max(1),
            _pad: [0; 3],
        };
        let flat = self.per_pixel(
            ctx,
            scene,
            depth,
            lists,
            &self.exact,
            4,
            bytemuck::bytes_of(&params),
        )?;
        Ok(flat
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect())
    }

    /// Runs a one-thread-per-pixel consumer of the lists with `uniform` at binding 5 and reads
    /// back its `stride` u32 per pixel.
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
        pipeline: &wgpu::ComputePipeline,
        stride: u64,
        uniform: &[u8],
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
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &scene.bind_group, &[]);
            pass.set_bind_group(1, &group, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        ctx.submit_and_wait(enc, "per-pixel list consumer")?;
        Ok(bytemuck::pod_collect_to_vec(&readback::read_buffer(
            ctx, &out, 0, bytes,
        )?))
    }
}

/// The per-frame buffers and bind groups of one culling run.
struct Frame<'a> {
    ctx: &'a GpuContext,
    scene: &'a GpuScene,
    layout: &'a wgpu::BindGroupLayout,
    params: GpuCullParams,
    w: u32,
    h: u32,
    params_buf: wgpu::Buffer,
    depth_view: wgpu::TextureView,
    tile_depth: wgpu::Buffer,
    counts: wgpu::Buffer,
    offsets: wgpu::Buffer,
    cursors: wgpu::Buffer,
    ranges: wgpu::Buffer,
    occupancy: wgpu::Buffer,
    stats: wgpu::Buffer,
    /// What a timer of spans calls one run: `cull.<strategy>`.
    span: String,
}

impl<'a> Frame<'a> {
    fn new(
        culler: &'a Culler,
        ctx: &'a GpuContext,
        scene: &'a GpuScene,
        depth: &wgpu::Texture,
        strategy: &Strategy,
        params: GpuCullParams,
        per_light: bool,
    ) -> Self {
        let bins = u64::from(params.bins);
        let tiles = u64::from(params.tiles_x * params.tiles_y);
        // Counts and offsets hold one entry per bin, or per (light, lane) for tiled scatter.
        let items = if per_light {
            bins.max(u64::from(params.light_count) * u64::from(crate::layout::SCATTER_LANES))
        } else {
            bins * chunks(&params)
        };
        let params_buf =
            pipeline::uniform_buffer(&ctx.device, "cull.params", bytemuck::bytes_of(&params));
        Self {
            ctx,
            scene,
            layout: &culler.layout,
            params,
            w: depth.width(),
            h: depth.height(),
            params_buf,
            depth_view: depth.create_view(&wgpu::TextureViewDescriptor {
                aspect: wgpu::TextureAspect::DepthOnly,
                ..Default::default()
            }),
            tile_depth: storage_buf(ctx, "cull.tile_depth", tiles * 16),
            counts: storage_buf(ctx, "cull.bin_counts", (items + 1) * 4),
            offsets: storage_buf(ctx, "cull.bin_offsets", (items + 1) * 4),
            cursors: storage_buf(ctx, "cull.bin_cursors", bins * 4),
            ranges: storage_buf(ctx, "cull.bin_ranges", bins * 8),
            occupancy: storage_buf(ctx, "cull.occupancy", bins * 4),
            stats: storage_buf(ctx, "cull.stats", 32),
            span: format!("cull.{}", strategy.name()),
        }
    }

    fn buf(&self, label: &str, size: u64) -> wgpu::Buffer {
        storage_buf(self.ctx, label, size)
    }

    /// The culling group: `indices` at binding 7 (the lists, or before them tiled scatter's
    /// block queue with tile masks), `pair_keys` at 9 (tiled scatter's pair keys, the clusters'
    /// wide-light queue, the light rectangles), `args` at 11 (the clusters' indirect dispatch,
    /// the tile masks).
    fn group(
        &self,
        indices: &wgpu::Buffer,
        pair_keys: &wgpu::Buffer,
        args: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        pipeline::group(
            &self.ctx.device,
            "cull.group1",
            self.layout,
            &[
                self.params_buf.as_entire_binding(),
                wgpu::BindingResource::TextureView(&self.depth_view),
                self.tile_depth.as_entire_binding(),
                self.counts.as_entire_binding(),
                self.offsets.as_entire_binding(),
                self.cursors.as_entire_binding(),
                self.ranges.as_entire_binding(),
                indices.as_entire_binding(),
                self.occupancy.as_entire_binding(),
                pair_keys.as_entire_binding(),
                self.stats.as_entire_binding(),
                args.as_entire_binding(),
            ],
        )
    }

    /// Clears the counters at the start of a run. With tile masks (`masked`) only the stats:
    /// those passes use no counts, cursors or occupancy, and the masks' fill writes every
    /// tile's range. (Each clear is a transfer between passes, which costs time of its own.)
    fn clear(&self, enc: &mut wgpu::CommandEncoder, masked: bool) {
        if masked {
            enc.clear_buffer(&self.stats, 0, None);
            return;
        }
        for b in [
            &self.counts,
            &self.cursors,
            &self.occupancy,
            &self.ranges,
            &self.stats,
        ] {
            enc.clear_buffer(b, 0, None);
        }
    }

    /// The count entries of a binned strategy: a count per bin, or for gather's coarse-to-fine
    /// passes per (bin, chunk of lights).
    fn entries_counted(&self) -> u32 {
        u32::try_from(u64::from(self.params.bins) * chunks(&self.params))
            .expect("fit_chunks bounds the entries")
    }

    fn pass_indirect(
        &self,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        label: &str,
        pipe: &wgpu::ComputePipeline,
        group: &wgpu::BindGroup,
        args: &wgpu::Buffer,
    ) {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: timer.compute_pass(label),
        });
        pass.set_pipeline(pipe);
        pass.set_bind_group(0, &self.scene.bind_group, &[]);
        pass.set_bind_group(1, group, &[]);
        pass.dispatch_workgroups_indirect(args, 0);
    }

    fn pass_3d(
        &self,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        label: &str,
        pipe: &wgpu::ComputePipeline,
        group: &wgpu::BindGroup,
        groups: [u32; 3],
    ) {
        pipeline::dispatch_3d(
            enc,
            timer,
            label,
            pipe,
            &[&self.scene.bind_group, group],
            groups,
        );
    }

    fn pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        label: &str,
        pipe: &wgpu::ComputePipeline,
        group: &wgpu::BindGroup,
        groups: (u32, u32),
    ) {
        pipeline::dispatch(
            enc,
            timer,
            label,
            pipe,
            &[&self.scene.bind_group, group],
            groups,
        );
    }

    /// Copies the first `n` counts (plus a zero) to the offsets and scans them.
    fn encode_scan(
        &self,
        ctx: &GpuContext,
        scan: &Scan,
        enc: &mut wgpu::CommandEncoder,
        n: u32,
        timer: &mut GpuTimer,
    ) {
        enc.copy_buffer_to_buffer(&self.counts, 0, &self.offsets, 0, (u64::from(n) + 1) * 4);
        scan.encode(ctx, enc, &self.offsets, n + 1, timer);
    }

    /// The exact total of the `n` counts after [`Frame::encode_scan`]: the scan's u32 total
    /// (`offsets[n]`), or, where the counts could sum past u32 (bins x lights > 2^32), the
    /// counts read back and summed in u64, so that a wrapped total never sizes the lists short.
    fn bins_total(&self, ctx: &GpuContext, n: u32) -> Result<u64, GpuError> {
        if u64::from(self.params.bins) * u64::from(self.params.light_count) > u64::from(u32::MAX) {
            Ok(read_u32s(ctx, &self.counts, 0, u64::from(n))?
                .iter()
                .map(|&c| u64::from(c))
                .sum())
        } else {
            Ok(u64::from(
                read_u32s(ctx, &self.offsets, u64::from(n), 1)?[0],
            ))
        }
    }

    /// Gather's list total with tile masks, which its count pass sums (`cull_stats[4]`; it
    /// cannot wrap: the masks' budget bounds bins x lights below 2^32).
    fn masked_total(&self, ctx: &GpuContext) -> Result<u64, GpuError> {
        Ok(u64::from(read_u32s(ctx, &self.stats, 4, 1)?[0]))
    }

    /// The list total of the lines path, which its count and fill passes sum into
    /// `cull_stats[5]`.
    fn lines_total(&self, ctx: &GpuContext) -> Result<u64, GpuError> {
        Ok(u64::from(read_u32s(ctx, &self.stats, 5, 1)?[0]))
    }

    /// Tiled scatter's pair total, which its count pass sums in 64 bits (`cull_stats[1]`, with
    /// the carries in `cull_stats[2]`).
    fn pairs_total(&self, ctx: &GpuContext) -> Result<u64, GpuError> {
        let sum = read_u32s(ctx, &self.stats, 1, 2)?;
        Ok(u64::from(sum[0]) | (u64::from(sum[1]) << 32))
    }

    /// `entries` list entries, checked: they must fit one storage binding (`what_bytes`) and
    /// u32 offsets (`what`), or it is an error, never a wrapped, short buffer.
    fn entries(
        ctx: &GpuContext,
        what_bytes: &str,
        what: &str,
        entries: u64,
    ) -> Result<u32, GpuError> {
        ctx.check_storage(what_bytes, entries * 4)?;
        u32::try_from(entries).map_err(|_| GpuError::OverLimit {
            what: what.into(),
            value: entries,
            limit: u32::MAX.into(),
            limit_name: "u32 list offsets",
        })
    }

    /// The two phases of a binned run: `counting` (up to the list total, which `total_of`
    /// reads back), then `filling` into lists of that size (bound by `group_for`). Without
    /// `repeat`, once, the lists sized exactly between two submissions; with it, `repeat.runs`
    /// times back to back in one submission, sized from the earlier run and checked against
    /// it. Returns the lists' index buffer and entries.
    #[allow(
        clippy::type_complexity,
        reason = "the phases as the callers' closures"
    )]
    fn count_then_fill(
        &self,
        timer: &mut GpuTimer,
        repeat: Option<Repeat>,
        counting: &dyn Fn(&mut wgpu::CommandEncoder, &mut GpuTimer, bool),
        total_of: &dyn Fn(&GpuContext) -> Result<u64, GpuError>,
        group_for: &dyn Fn(&wgpu::Buffer) -> wgpu::BindGroup,
        filling: &dyn Fn(&mut wgpu::CommandEncoder, &mut GpuTimer, &wgpu::BindGroup, bool),
    ) -> Result<(wgpu::Buffer, u32), CullError> {
        let ctx = self.ctx;
        let Some(repeat) = repeat else {
            let mut enc = ctx.encoder("cull.count");
            counting(&mut enc, timer, false);
            ctx.submit_and_wait(enc, "culling: count")?;
            let total = Frame::entries(
                ctx,
                "light list bytes",
                "light list entries",
                total_of(ctx)?,
            )?;
            let indices = self.buf("cull.light_indices", u64::from(total) * 4);
            let group = group_for(&indices);
            let mut enc = ctx.encoder("cull.fill");
            filling(&mut enc, timer, &group, false);
            timer.resolve(&mut enc);
            ctx.submit_and_wait(enc, "culling: fill")?;
            return Ok((indices, total));
        };
        let indices = self.buf("cull.light_indices", u64::from(repeat.total) * 4);
        let group = group_for(&indices);
        let mut enc = ctx.encoder("cull.repeated");
        for _ in 0..repeat.runs {
            timer.span_begin(&mut enc, &self.span);
            counting(&mut enc, timer, true);
            filling(&mut enc, timer, &group, true);
            timer.span_end(&mut enc);
        }
        timer.resolve(&mut enc);
        ctx.submit_and_wait(enc, "culling: repeated runs")?;
        repeat.check(total_of(ctx)?)?;
        Ok((indices, repeat.total))
    }

    /// The output; reads back the dropped count where a capacity was set.
    fn finish(
        self,
        indices: wgpu::Buffer,
        total: u32,
        tile_masks: Option<wgpu::Buffer>,
        tile_lines: Option<wgpu::Buffer>,
    ) -> Result<CullOutput, GpuError> {
        let dropped = if self.params.capacity != 0 {
            read_u32s(self.ctx, &self.stats, 0, 1)?[0]
        } else {
            0
        };
        Ok(CullOutput {
            dropped,
            params: self.params,
            params_buf: self.params_buf,
            ranges: self.ranges,
            indices,
            total,
            tile_depth: self.tile_depth,
            occupancy: self.occupancy,
            tile_masks,
            tile_lines,
        })
    }
}

/// Back-to-back runs of [`Culler::run_repeated`]: how many, and the list entries (or scatter's
/// pairs) an earlier run of the same input needed.
#[derive(Clone, Copy)]
struct Repeat {
    total: u32,
    runs: u32,
}

impl Repeat {
    /// The total the repeated runs needed, which must be the earlier run's.
    fn check(self, total: u64) -> Result<(), CullError> {
        if total == u64::from(self.total) {
            Ok(())
        } else {
            Err(CullError::SizeChanged {
                earlier: self.total,
                now: total,
            })
        }
    }
}

/// Chunks of lights per bin in the count entries: `ceil(lights / chunk)` for gather's
/// coarse-to-fine passes, 1 otherwise.
fn chunks(p: &GpuCullParams) -> u64 {
    if p.coarse > 0 && p.chunk > 0 {
        u64::from(p.light_count.div_ceil(p.chunk)).max(1)
    } else {
        1
    }
}

/// Whether gather's subgroup scans apply: subgroup operations, with subgroups that tile each
/// scan's segment (sizes are powers of two; the smallest segment is a lines-path tile's
/// [`crate::layout::LINE_THREADS_MIN`]). Elsewhere (64-wide subgroups) gather takes the portable
/// scans.
fn gather_subgroups_fit(ctx: &GpuContext) -> bool {
    ctx.features.subgroups && ctx.features.subgroup_size.1 <= crate::layout::LINE_THREADS_MIN
}

/// `count` u32 words of `buf` from word `first`, read back.
fn read_u32s(
    ctx: &GpuContext,
    buf: &wgpu::Buffer,
    first: u64,
    count: u64,
) -> Result<Vec<u32>, GpuError> {
    Ok(bytemuck::pod_collect_to_vec(&readback::read_buffer(
        ctx,
        buf,
        first * 4,
        count * 4,
    )?))
}

/// A storage buffer (at least 4 bytes) that can be cleared and read back.
fn storage_buf(ctx: &GpuContext, label: &str, size: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(4),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}
