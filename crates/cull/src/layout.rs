//! Host mirrors of the culling WGSL structs and the constants both sides share.

use bytemuck::{Pod, Zeroable};
use manylights_gpu::shaders::WgslConst;

/// `CullParams.flags`: apply the 2.5D depth masks (`cull.depth_mask`).
pub const CULL_FLAG_DEPTH_MASK: u32 = 1;
/// `CullParams.flags`: emit lights only into clusters that hold geometry.
pub const CULL_FLAG_SKIP_EMPTY: u32 = 2;
/// `CullParams.flags`: z-binning's lists (`cull.zbin`): `bin_ranges` holds each depth bin's
/// range of depth-sorted lights, `light_indices` the sorted lights and after them each tile's
/// bitmask (see `shaders/cull/common/lookup.wgsl`).
pub const CULL_FLAG_ZBIN: u32 = 4;
/// `CullParams.flags`: tile tests also test each light's sphere against the view-space box of
/// the tile's frustum between its depth bounds (`CullSettings::tile_boxes`).
pub const CULL_FLAG_TILE_BOX: u32 = 8;
/// `CullParams.flags`: the clusters' per-light passes read each cluster's box from
/// `cull.clustered.boxes` (8 words a cluster) rather than computing it for every light.
pub const CULL_FLAG_CLUSTER_BOXES: u32 = 16;
/// `CullParams.flags` (with `CULL_FLAG_CLUSTER_BOXES`, at most [`CLUSTER_MASK_SLICES`]
/// slices): the clusters' per-light passes test only the slices of a tile that hold pixels,
/// from the tile's mask of occupied slices (`cull.clustered.boxes` sets it).
pub const CULL_FLAG_SLICE_MASKS: u32 = 32;
/// `CullParams.flags`: a light's tile rectangle from the exact bounds of its sphere's
/// projection (Mara and McGuire 2013, `light_tiles`) where the projection is a perspective
/// without skew, rather than from its view-space box's corners.
pub const CULL_FLAG_SPHERE_BOUNDS: u32 = 64;
/// `CullParams.flags` (at most [`CLUSTER_ORDER_BITS_LIGHTS`] lights): the clusters' order
/// passes sort a list by a bitmap of the light indices (`bits_sort`) rather than by the bitonic
/// network ([`crate::Culler::cluster_order_bits`]).
pub const CULL_FLAG_ORDER_BITS: u32 = 128;
/// `CullParams.slicing`: slices of equal depth.
pub const SLICING_LINEAR: u32 = 0;
/// `CullParams.slicing`: slices of equal depth ratio (Olsson et al. 2012).
pub const SLICING_EXPONENTIAL: u32 = 1;
/// Spots whose outer cosine is at most this (half-angle of about 89.9 degrees or more) are
/// culled as spheres; narrower ones also by their cone.
pub const CONE_MIN_COS: f32 = 1e-3;
/// Default conservative slack, relative to each light's `|centre| + radius` in view space.
///
/// Budget: the f32 planes and the linearised depth bounds carry relative errors of a few 1e-7
/// (the depth linearisation's subtraction is exact by Sterbenz' lemma, leaving one rounding per
/// operation); the pixel positions the exact oracle reconstructs from the same depth values
/// agree with them to that order. 1e-4 covers this by a factor of about 100 and costs a
/// negligible widening (1 mm for a light 10 m away).
pub const DEFAULT_SLACK: f32 = 1e-4;

/// Threads of the portable scan's workgroups.
pub const SCAN_THREADS: u32 = 256;
/// Elements each scan thread handles.
pub const SCAN_PER_THREAD: u32 = 4;
/// Elements one scan workgroup handles.
pub const SCAN_BLOCK: u32 = SCAN_THREADS * SCAN_PER_THREAD;
/// Workgroups along x in a 2D scan dispatch (rows of this many blocks).
pub const SCAN_MAX_GROUPS_X: u32 = 32768;

/// Workgroups along x in the 2D dispatches of one-thread-per-item passes (per light, per bin).
pub const GROUPS_X: u32 = 32768;
/// Threads sharing one light's tiles in `cull.clustered` (one NVIDIA warp): balances lights that
/// cover the whole screen against the many small ones.
pub const CLUSTER_LANES: u32 = 32;
/// The most depth slices of the clusters' tile path (`cull.clustered.tiles_count`: each of the
/// first 64 threads of a tile's workgroup owns a slice).
pub const CLUSTER_TILE_SLICES: u32 = 64;
/// The most depth slices of clusters whose lists deferred lighting takes a workgroup at a time
/// ([`crate::ListForm::Clusters`]: a bit a slice in the workgroup's memory, 32 bytes).
pub const CLUSTER_GROUP_SLICES: u32 = 256;
/// The most lights for which the clusters' order passes sort by a bitmap of the light indices
/// (`CULL_FLAG_ORDER_BITS`): a bit a light in workgroup memory, 8 KB.
pub const CLUSTER_ORDER_BITS_LIGHTS: u32 = 65536;
/// The most slices of a tile's mask of occupied slices (`CULL_FLAG_SLICE_MASKS`): two words a
/// tile after the occupancy words.
pub const CLUSTER_MASK_SLICES: u32 = 64;
/// Deferred lighting takes clusters' lists a workgroup at a time above this many lights, and a
/// pixel at a time up to it ([`crate::ListForm::Clusters`]; on an H100 the loop a pixel was
/// faster at 500 and 3,072 lights, the workgroup's at 50,000 and 1M: shaders/render/deferred.wgsl,
/// `shade_cluster_group`).
pub const CLUSTER_GROUP_MIN_LIGHTS: u32 = 4096;
/// Deferred lighting over z-binning's lists in a point-light pipeline takes a workgroup's lights
/// in rounds (`shade_zbin_rounds`, shaders/render/deferred.wgsl: each thread walks its run of
/// the mask's words and loads a light a round) from this many lights, and the workgroup's one
/// walk below: with many lights the rounds overlap a workgroup's loads (half the time at 1M
/// lights), with few a round's barriers cost more than the loads they overlap (docs/bench/
/// HISTORY.md, "Z-binning's lighting in rounds"). The rounds have entry points and pipelines of
/// their own (`shade_zbin_rounds_group`): in the one walk's pipeline they cost it 1-3% below
/// this count.
pub const ZBIN_ROUNDS_MIN_LIGHTS: u32 = 16384;
/// Threads sharing one light's tiles in `cull.tiled_scatter`; each (light, lane) has a count, so
/// the scan runs over lights x SCATTER_LANES entries.
pub const SCATTER_LANES: u32 = 16;

/// Tiles a `cull.depth_bounds` workgroup takes, 64 threads each: launching workgroups costs
/// more than a small tile's work (see docs/bench/HISTORY.md).
pub const DEPTH_TILES: u32 = 4;

/// Threads of a `cull.tiled_scatter.count` workgroup with tile masks, and the tiles of a block
/// of a light's rectangle that the workgroup takes at a time (a tile a thread).
pub const SCATTER_MASK_THREADS: u32 = 256;
/// Workgroups of that pass, each taking every `SCATTER_MASK_GROUPS`-th queued block (fewer
/// where fewer blocks can be queued).
pub const SCATTER_MASK_GROUPS: u32 = 2048;

/// Lines (columns of tiles, rows of tiles, depth bins) that a `cull.tile_lines` workgroup takes
/// for gather's lines path, with 64 [`DEPTH_TILES`] lights: one (line, word) pair a thread.
pub const LINES_PER_GROUP: u32 = 32;

/// Depth bins of gather's lines path (z-bins after the columns and rows of tiles): bin
/// `(bits(max(d, near)) - bits(near)) >> ZBIN_SHIFT` of linear depth `d`, clamped to the last,
/// with `near` the camera's near plane (> 0; otherwise every light is in bin 0). Float bits
/// order like positive floats, so the bin is monotone in `d` without rounding: four bins an
/// octave from the near plane, 16 octaves.
pub const ZBINS: u32 = 64;
/// See [`ZBINS`].
pub const ZBIN_SHIFT: u32 = 21;
/// Tiles spanning more depth bins than this skip the bins' prefilter (it would load many words
/// to reject few lights).
pub const ZBIN_MAX_SPAN: u32 = 8;

/// Tiles a workgroup of the tile masks' fill takes, 64 threads each (as [`DEPTH_TILES`]).
pub const MASK_FILL_TILES: u32 = 4;

/// Threads of a workgroup of the list passes of gather's lines path. A tile takes
/// [`line_threads`] of them, so a workgroup takes `LINE_GROUP_THREADS / line_threads` tiles.
pub const LINE_GROUP_THREADS: u32 = 128;
/// The fewest threads a tile in those passes. Gather's subgroup scans need subgroups of at most
/// this many invocations (`gather_subgroups_fit`).
pub const LINE_THREADS_MIN: u32 = 32;
/// Mask words a thread of those passes aims at: a tile takes the fewest threads (a power of
/// two from [`LINE_THREADS_MIN`] to [`LINE_GROUP_THREADS`]) that leave each at most this many.
pub const LINE_WORDS: u32 = 8;

/// The threads a tile that [`line_threads`] takes: each list pass of the lines path is built
/// once for each (the shaders' `LINE_THREADS` override).
pub const LINE_THREAD_COUNTS: [u32; 3] = [32, 64, 128];
const _: () = assert!(
    LINE_THREAD_COUNTS[0] == LINE_THREADS_MIN
        && LINE_THREAD_COUNTS[1] == 2 * LINE_THREADS_MIN
        && LINE_THREAD_COUNTS[2] == LINE_GROUP_THREADS
);

/// Threads a tile in the list passes of gather's lines path, for `light_count` lights (one of
/// [`LINE_THREAD_COUNTS`]): 32 up to 8,192 lights (three mask words a thread at the Forward+
/// paper's 3,072: half the threads of 64 a tile measured 8% faster on an H100), 64 up to
/// 16,384 (where 32 measured 20% slower), 128 beyond. Aiming at 4 or 2 words a thread instead
/// measured no faster anywhere and slower at 4K (docs/bench/HISTORY.md).
pub fn line_threads(light_count: u32) -> u32 {
    let words = light_count.div_ceil(64) * 2;
    words
        .div_ceil(LINE_WORDS)
        .next_power_of_two()
        .clamp(LINE_THREADS_MIN, LINE_GROUP_THREADS)
}

/// Tiles whose depth data one workgroup computes (`tile_bounds`): the most of
/// `cull.depth_bounds`'s and the lines path's.
pub const TILE_SLOTS: u32 = if DEPTH_TILES > LINE_GROUP_THREADS / LINE_THREADS_MIN {
    DEPTH_TILES
} else {
    LINE_GROUP_THREADS / LINE_THREADS_MIN
};

// The workgroup scans' memory holds 64 MASK_FILL_TILES slots; the lines path's workgroups use
// no more, and their tiles' threads are powers of two (the scans' segments).
const _: () = assert!(LINE_GROUP_THREADS <= 64 * MASK_FILL_TILES);
const _: () = assert!(LINE_THREADS_MIN.is_power_of_two() && LINE_GROUP_THREADS.is_power_of_two());
const _: () = assert!(LINE_THREADS_MIN <= LINE_GROUP_THREADS);
const _: () = assert!(MASK_FILL_TILES <= TILE_SLOTS);

/// Constants of the culling shaders, generated into their prelude.
pub const CULL_CONSTS: &[WgslConst] = &[
    WgslConst::U32("GROUPS_X", GROUPS_X),
    WgslConst::U32("DEPTH_TILES", DEPTH_TILES),
    WgslConst::U32("MASK_FILL_TILES", MASK_FILL_TILES),
    WgslConst::U32("LINE_GROUP_THREADS", LINE_GROUP_THREADS),
    WgslConst::U32("TILE_SLOTS", TILE_SLOTS),
    WgslConst::U32("LINES_PER_GROUP", LINES_PER_GROUP),
    WgslConst::U32("ZBINS", ZBINS),
    WgslConst::U32("ZBIN_SHIFT", ZBIN_SHIFT),
    WgslConst::U32("ZBIN_MAX_SPAN", ZBIN_MAX_SPAN),
    WgslConst::U32("CLUSTER_LANES", CLUSTER_LANES),
    WgslConst::U32("CLUSTER_TILE_SLICES", CLUSTER_TILE_SLICES),
    WgslConst::U32("CLUSTER_GROUP_SLICES", CLUSTER_GROUP_SLICES),
    WgslConst::U32("SCATTER_LANES", SCATTER_LANES),
    WgslConst::U32("SCATTER_MASK_THREADS", SCATTER_MASK_THREADS),
    WgslConst::U32("CULL_FLAG_DEPTH_MASK", CULL_FLAG_DEPTH_MASK),
    WgslConst::U32("CULL_FLAG_SKIP_EMPTY", CULL_FLAG_SKIP_EMPTY),
    WgslConst::U32("CULL_FLAG_ZBIN", CULL_FLAG_ZBIN),
    WgslConst::U32("CULL_FLAG_TILE_BOX", CULL_FLAG_TILE_BOX),
    WgslConst::U32("CULL_FLAG_CLUSTER_BOXES", CULL_FLAG_CLUSTER_BOXES),
    WgslConst::U32("CULL_FLAG_SLICE_MASKS", CULL_FLAG_SLICE_MASKS),
    WgslConst::U32("CULL_FLAG_SPHERE_BOUNDS", CULL_FLAG_SPHERE_BOUNDS),
    WgslConst::U32("CULL_FLAG_ORDER_BITS", CULL_FLAG_ORDER_BITS),
    WgslConst::U32("CLUSTER_ORDER_BITS_LIGHTS", CLUSTER_ORDER_BITS_LIGHTS),
    WgslConst::U32("CLUSTER_MASK_SLICES", CLUSTER_MASK_SLICES),
    WgslConst::U32("ZBIN_ROUNDS_MIN_LIGHTS", ZBIN_ROUNDS_MIN_LIGHTS),
    WgslConst::U32("SLICING_LINEAR", SLICING_LINEAR),
    WgslConst::U32("SLICING_EXPONENTIAL", SLICING_EXPONENTIAL),
    WgslConst::F32("CONE_MIN_COS", CONE_MIN_COS),
];

/// Constants of the scan shader.
pub const SCAN_CONSTS: &[WgslConst] = &[
    WgslConst::U32("SCAN_THREADS", SCAN_THREADS),
    WgslConst::U32("SCAN_PER_THREAD", SCAN_PER_THREAD),
    WgslConst::U32("SCAN_BLOCK", SCAN_BLOCK),
    WgslConst::U32("SCAN_MAX_GROUPS_X", SCAN_MAX_GROUPS_X),
];

/// Mirror of WGSL `CullParams` (`shaders/cull/common/geometry.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuCullParams {
    /// Tiles across.
    pub tiles_x: u32,
    /// Tiles down.
    pub tiles_y: u32,
    /// Tile side in pixels.
    pub tile_size: u32,
    /// Lights.
    pub light_count: u32,
    /// Depth slices (1 for tiled strategies).
    pub slices: u32,
    /// `SLICING_*`.
    pub slicing: u32,
    /// `CULL_FLAG_*`.
    pub flags: u32,
    /// Bins: tiles x slices.
    pub bins: u32,
    /// Near plane distance.
    pub near: f32,
    /// Far plane distance.
    pub far: f32,
    /// Relative conservative slack.
    pub slack: f32,
    /// Slice scale: slices / (far - near) or slices / ln(far / near).
    pub slice_scale: f32,
    /// Deliberate cap on each list's length (0: none).
    pub capacity: u32,
    /// Gather's coarse level: the side of a coarse tile in tiles (8; 0: no coarse level).
    pub coarse: u32,
    /// Coarse tiles across (0 without a coarse level).
    pub coarse_x: u32,
    /// Lights of a chunk in gather's coarse-to-fine passes (a multiple of 64); for clusters,
    /// the tiles a lane of a wide light takes before the light is split into bands
    /// ([`crate::Culler::cluster_lane_tiles`]).
    pub chunk: u32,
}
const _: () = assert!(size_of::<GpuCullParams>() == 64);

/// Mirror of WGSL `ExactParams` (`shaders/cull/per_pixel/exact.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuExactParams {
    /// Inverse of the frame's `clip_from_world`.
    pub world_from_clip: glam::Mat4,
    /// Pixel sampling stride (1: every pixel).
    pub stride: u32,
    /// 1: the exact set is shadowed (a light needed only where its shadow ray is clear).
    pub shadows: u32,
    /// Padding to 16 bytes.
    pub _pad: [u32; 2],
}
const _: () = assert!(size_of::<GpuExactParams>() == 80);

/// Mirror of WGSL `TileDepth` (`shaders/cull/common/geometry.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTileDepth {
    /// Nearest covered linear depth.
    pub dmin: f32,
    /// Farthest covered linear depth.
    pub dmax: f32,
    /// 2.5D geometry mask.
    pub mask: u32,
    /// Covered pixels.
    pub covered: u32,
}
const _: () = assert!(size_of::<GpuTileDepth>() == 16);
