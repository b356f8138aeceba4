//! Light-culling strategies of manylights.
//!
//! A strategy takes the depth buffer (where it uses one), the camera and the lights, and writes
//! light lists in the same bindings for every strategy: `bin_ranges[bin] = (offset, count)` into
//! `light_indices`, where a bin is a screen tile or a cluster (tile x depth slice); z-binning
//! writes its own form there (depth bins' ranges of depth-sorted lights, tile bitmasks). Every
//! shading backend reads them through `shaders/cull/common/lookup.wgsl`.
//!
//! The crate, by concept:
//! - [`strategies`]: a module a strategy (`tiled_gather`, Harada, McKee, Yang 2012, section
//!   4.1; `tiled_scatter`, section 4.2; `depth_mask`, 2.5D culling, Harada 2012; `clustered`,
//!   Olsson, Billeter, Assarsson 2012; `zbin`, z-binning, Drobot 2017), each owning its
//!   pipelines and declaring the passes of a run as data;
//! - [`blocks`], [`scan`], [`radix_sort`]: the building blocks strategies compose (tile depth,
//!   tile masks, tile lines, list finalisation; the exclusive scan; the radix sort);
//! - [`record`]: passes as data and the one recorder that encodes, labels and times them;
//!   `frame` runs a plan once (sized exactly between two submissions) or back to back;
//! - [`Culler`]: builds every pipeline once (a strategy's own at its first run) and runs a
//!   strategy; [`CullOutput`] is what a run leaves on the GPU;
//! - [`cpu`]: the CPU oracle of every pass; [`metrics`]: the exact per-pixel oracle and list
//!   metrics; [`per_pixel`]: the per-pixel list consumers on the GPU; [`geometry`]: the
//!   culling geometry both sides share; [`layout`]: host mirrors of the WGSL structs and shared
//!   constants.
//!
//! Lists are sized exactly: a count pass counts each bin's lights, a scan gives the total, and
//! the host sizes `light_indices` from it before the fill (no capacity, nothing dropped unless
//! a run asks for a capacity, and then the dropped lights are counted). docs/STRATEGIES.md
//! describes the methods, their tests, parameters, memory and false positives; docs/
//! ARCHITECTURE.md says how to add a strategy.

pub mod blocks;
pub mod cpu;
mod culler;
mod frame;
pub mod geometry;
pub mod heatmap;
mod input_pipelines;
pub mod layout;
pub mod metrics;
pub mod occlusion;
mod output;
pub mod per_pixel;
mod program;
pub mod radix_sort;
pub mod record;
pub mod scan;
mod settings;
pub mod shaders;
pub mod strategies;

pub use culler::Culler;
pub use output::{BinLists, CullOutput, ListForm, zbin_cells, zbin_lengths, zbin_range};
pub use program::Kernel;
pub use record::ListPass;
pub use settings::CullSettings;

use serde::{Deserialize, Serialize};

use layout::{
    CULL_FLAG_DEPTH_MASK, CULL_FLAG_SKIP_EMPTY, CULL_FLAG_TILE_BOX, CULL_FLAG_ZBIN, GpuCullParams,
    SLICING_EXPONENTIAL, SLICING_LINEAR,
};

/// How the depth range of the cluster grid is sliced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Slicing {
    /// Equal depth per slice.
    Linear,
    /// Equal depth ratio per slice: `d_k = near * (far / near)^(k / S)`.
    Exponential,
}

impl Slicing {
    /// `CullParams.slicing`.
    fn code(self) -> u32 {
        match self {
            Self::Linear => SLICING_LINEAR,
            Self::Exponential => SLICING_EXPONENTIAL,
        }
    }
}

/// A culling strategy and its parameters. In RON, omitted parameters take their defaults:
/// tiles of 16 pixels (64 for clusters), 24 exponential slices, `skip_empty: false`,
/// `ordered: true`; for z-binning 256 exponential depth bins.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Strategy {
    /// Forward+ tiled gather: one workgroup per tile tests every light against the tile frustum
    /// between the tile's depth bounds.
    TiledGather {
        /// Tile side in pixels (the paper's 8; 16 and 32 are common).
        #[serde(default = "default_tile")]
        tile_size: u32,
        /// Coarse-to-fine: 8 (the default) tests each light against coarse tiles of 8 x 8 tiles
        /// first, once per coarse tile, and each tile only the survivors; 0 tests every light
        /// at every tile (the paper's single level). See docs/STRATEGIES.md.
        #[serde(default = "default_coarse")]
        coarse: u32,
    },
    /// Forward+ tiled scatter: one thread per light writes (tile, light) pairs for the tiles it
    /// overlaps; a GPU radix sort orders them by tile.
    TiledScatter {
        /// Tile side in pixels.
        #[serde(default = "default_tile")]
        tile_size: u32,
    },
    /// 2.5D culling: tiled gather plus 32-cell depth masks of geometry and lights.
    DepthMask {
        /// Tile side in pixels.
        #[serde(default = "default_tile")]
        tile_size: u32,
        /// Coarse-to-fine, as for `TiledGather`.
        #[serde(default = "default_coarse")]
        coarse: u32,
    },
    /// 3D clusters: tiles x depth slices, lights assigned per light.
    Clustered {
        /// Tile side in pixels.
        #[serde(default = "default_cluster_tile")]
        tile_size: u32,
        /// Depth slices.
        #[serde(default = "default_slices")]
        slices: u32,
        /// Slicing of [near, far].
        #[serde(default = "default_slicing")]
        slicing: Slicing,
        /// Emit lights only into clusters that hold geometry.
        #[serde(default)]
        skip_empty: bool,
        /// Sort each cluster's list into light order after the fill (`cull.clustered.order`),
        /// so that shading sums a pixel's lights in the same order on every run and images are
        /// bit-identical. `false` keeps the atomic fill's arbitrary order (the same lights as
        /// sets, one pass less).
        #[serde(default = "default_ordered")]
        ordered: bool,
        /// 2.5D cells inside each cluster (Harada 2012's depth masks, a cluster at a time;
        /// `cull.clustered.cells`): each cluster's pixels' depth range in 32 cells, a bit a
        /// cell its pixels fall in, and a light kept only where its depth extent's cells meet
        /// them. Lists a subset of those without; needs the box test (`tile_boxes`, on by
        /// default), whose depth bounds of a cluster's pixels the cells divide, and takes the
        /// per-light passes (not the tile path). `false` by default.
        #[serde(default)]
        cells: bool,
    },
    /// Z-binning with tile bitmasks (Drobot, SIGGRAPH 2017; Unity URP's Forward+): the lights
    /// sorted by view depth, each depth bin holding the index range of the sorted lights that
    /// reach it, each tile a bit per sorted light; a pixel's lights are its tile's bits within
    /// its depth bin's range.
    ZBin {
        /// Tile side in pixels.
        #[serde(default = "default_tile")]
        tile_size: u32,
        /// Depth bins over [near, far].
        #[serde(default = "default_zbins")]
        bins: u32,
        /// Slicing of [near, far] into the bins.
        #[serde(default = "default_slicing")]
        slicing: Slicing,
    },
}

/// The default depth bins of z-binning.
pub const DEFAULT_ZBINS: u32 = 256;

/// The most depth bins of z-binning: its sort keys are a bin's 64 sub-bins in 16 bits.
pub const MAX_ZBINS: u32 = 1024;

fn default_zbins() -> u32 {
    DEFAULT_ZBINS
}

fn default_ordered() -> bool {
    true
}

/// The default side of gather's coarse tiles, in tiles.
pub const DEFAULT_COARSE: u32 = 8;

fn default_coarse() -> u32 {
    DEFAULT_COARSE
}

/// The most (bin, chunk) count entries of gather's coarse-to-fine passes; past it, chunks of
/// lights grow.
pub const MAX_CHUNK_ENTRIES: u64 = 1 << 23;

/// The default smallest chunk of lights of gather's coarse-to-fine passes (a workgroup's
/// share; [`crate::Culler::gather_min_chunk`]).
pub const MIN_CHUNK: u32 = 256;

/// The same with tile masks ([`crate::Culler::gather_min_chunk_masked`]): 89 against 94 µs at
/// the Forward+ paper's configuration on the H200, where without masks 128 made the scan over
/// (tile, chunk) counts dearer than the parallelism gained (4K, 16,384 lights: 403 against
/// 336 µs).
pub const MIN_CHUNK_MASKED: u32 = 128;

/// The default most bytes of gather's tile masks (a bit per tile and light;
/// [`crate::Culler::mask_budget`]): 5.5 MB at the Forward+ paper's configuration (3,072
/// lights, 1280x720 in 8-pixel tiles), 16.7 MB at 16,384 lights and 1080p in 16-pixel tiles;
/// past it the fill tests every light again. On the H200, masks of 66 MB were slower than
/// testing again (16,384 lights at 4K: 412 against 336 µs), those of 16.6 MB faster.
pub const MASK_BUDGET: u64 = 16 << 20;

/// The default most lights of the clusters' tile path ([`crate::Culler::cluster_tiles_max_lights`]).
/// Its count pass walks every light at every tile, 256 at a time, so its cost grows with the
/// lights; the per-light passes' with the (light, cluster) pairs. On the H100, culling spans at
/// 1080p in the CIS 5650 hall (docs/BENCHMARKS.md): the tile path 101 against 269 µs at 500
/// lights (64 px x 24 slices), 280 against 291 µs at 5,000, 731 against 400 µs at 16,384; at the
/// Forward+ configuration (3,072 dense lights, 720p) 165 against 250 µs.
pub const CLUSTER_TILES_MAX_LIGHTS: u32 = 4096;

/// The most (tile, light) pairs of the clusters' tile path: 2,000 lights in 16-pixel tiles at
/// 1080p (16 million pairs) still gain (0.87 against 1.39 ms); at 5,000 lights there (41
/// million) the per-light passes are faster.
pub const CLUSTER_TILES_MAX_PAIRS: u64 = 1 << 24;

/// The default fewest (tile, light) pairs at which the clusters' tile path computes the lights'
/// rectangles once (`cull.clustered.rects`) rather than at every tile
/// ([`crate::Culler::cluster_tile_rect_pairs`]): on the H100, 500 lights in 64-pixel tiles at
/// 1080p (255,000 pairs) took 107 against 102 µs with the extra pass, 2,000 lights in 16-pixel
/// tiles (16 million) 571 against 859 µs, and the Forward+ configuration (737,000) 160 against
/// 164 µs.
pub const CLUSTER_TILE_RECT_PAIRS: u64 = 1 << 19;

/// The default tiles a lane of the clusters' wide-light passes takes before the light is split
/// into bands of its rows, each with lanes of its own ([`crate::Culler::cluster_lane_tiles`]).
pub const CLUSTER_LANE_TILES: u32 = 4;

/// The default fewest lights at which z-binning sets its masks a light at a time
/// ([`crate::Culler::zbin_scatter_min_lights`]): a tile at a time wins where lights are few
/// and large (each covers thousands of tiles), a light at a time from between 50,000 and 262,144
/// lights, as timed with culling and deferred lighting (docs/bench/HISTORY.md, "Z-binning's
/// masks: a tile or a light at a time").
pub const ZBIN_SCATTER_MIN_LIGHTS: u32 = 131_072;

/// The step of chunk sizes: a batch of the shader, 64 lights, one a thread.
pub const CHUNK_STEP: u32 = 64;

/// Fits gather's coarse-to-fine passes in `p` to a device: the chunk of lights a workgroup
/// takes (a multiple of [`CHUNK_STEP`], at least `min_chunk`) grows until the (tile, chunk) count entries
/// fit `max_entries` and the chunks fit `max_groups` workgroups in one dispatch dimension.
/// Without a coarse level, without lights, or with a capacity (which caps whole lists, not
/// chunks), the single level runs (`p.coarse = 0`).
pub fn fit_chunks(p: &mut GpuCullParams, max_entries: u64, max_groups: u32, min_chunk: u32) {
    p.chunk = 0;
    if p.coarse == 0 || p.light_count == 0 || p.capacity != 0 {
        p.coarse = 0;
        p.coarse_x = 0;
        return;
    }
    let lights = u64::from(p.light_count);
    let tiles = u64::from(p.bins);
    let by_entries = (lights * tiles).div_ceil(max_entries.max(1));
    let by_groups = lights.div_ceil(u64::from(max_groups.max(1)));
    let chunk = by_entries
        .max(by_groups)
        .max(u64::from(min_chunk.max(CHUNK_STEP)))
        .next_multiple_of(u64::from(CHUNK_STEP));
    match u32::try_from(chunk) {
        Ok(c) if lights.div_ceil(chunk) * tiles <= max_entries.max(tiles) => p.chunk = c,
        _ => {
            p.coarse = 0;
            p.coarse_x = 0;
        }
    }
}

fn default_tile() -> u32 {
    16
}
fn default_cluster_tile() -> u32 {
    64
}
fn default_slices() -> u32 {
    24
}
fn default_slicing() -> Slicing {
    Slicing::Exponential
}

/// Errors of culling.
#[derive(Debug, thiserror::Error)]
pub enum CullError {
    /// A parameter outside its range.
    #[error("invalid {field} = {value}: {accepted}")]
    InvalidParameter {
        /// Parameter.
        field: &'static str,
        /// Value.
        value: String,
        /// What is accepted.
        accepted: &'static str,
    },
    /// A GPU failure.
    #[error(transparent)]
    Gpu(#[from] manylights_gpu::GpuError),
    /// Repeated runs of one input needed other list sizes than the run that sized them.
    #[error(
        "repeated culling runs needed {now} list entries where the run that sized them needed \
         {earlier}: the input changed between them"
    )]
    SizeChanged {
        /// Entries of the sizing run.
        earlier: u32,
        /// Entries of the repeated runs.
        now: u64,
    },
}

impl Strategy {
    /// The strategy's name: its file names, profiler scopes and result column value.
    pub fn name(&self) -> &'static str {
        match self {
            Self::TiledGather { .. } => "tiled_gather",
            Self::TiledScatter { .. } => "tiled_scatter",
            Self::DepthMask { .. } => "depth_mask",
            Self::Clustered { .. } => "clustered",
            Self::ZBin { .. } => "zbin",
        }
    }

    /// The default parameters of each strategy, in a fixed order.
    pub fn defaults() -> [Strategy; 5] {
        [
            Self::tiled_gather(16),
            Self::TiledScatter { tile_size: 16 },
            Self::depth_mask(16),
            Self::Clustered {
                tile_size: 64,
                slices: 24,
                slicing: Slicing::Exponential,
                skip_empty: false,
                ordered: true,
                cells: false,
            },
            Self::ZBin {
                tile_size: 16,
                bins: DEFAULT_ZBINS,
                slicing: Slicing::Exponential,
            },
        ]
    }

    /// Tiled gather with `tile_size`-pixel tiles and the default coarse level.
    pub fn tiled_gather(tile_size: u32) -> Self {
        Self::TiledGather {
            tile_size,
            coarse: DEFAULT_COARSE,
        }
    }

    /// 2.5D culling with `tile_size`-pixel tiles and the default coarse level.
    pub fn depth_mask(tile_size: u32) -> Self {
        Self::DepthMask {
            tile_size,
            coarse: DEFAULT_COARSE,
        }
    }

    /// Tile side in pixels.
    pub fn tile_size(&self) -> u32 {
        match *self {
            Self::TiledGather { tile_size, .. }
            | Self::TiledScatter { tile_size }
            | Self::DepthMask { tile_size, .. }
            | Self::Clustered { tile_size, .. }
            | Self::ZBin { tile_size, .. } => tile_size,
        }
    }

    /// Gather's coarse level: a coarse tile's side in tiles, 0 (none) for other strategies.
    pub fn coarse(&self) -> u32 {
        match *self {
            Self::TiledGather { coarse, .. } | Self::DepthMask { coarse, .. } => coarse,
            _ => 0,
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), CullError> {
        let ts = self.tile_size();
        if !(4..=256).contains(&ts) {
            return Err(CullError::InvalidParameter {
                field: "tile_size",
                value: ts.to_string(),
                accepted: "an integer in 4..=256 pixels",
            });
        }
        if !matches!(self.coarse(), 0 | DEFAULT_COARSE) {
            return Err(CullError::InvalidParameter {
                field: "coarse",
                value: self.coarse().to_string(),
                accepted: "8 (coarse tiles of 8 x 8 tiles, a thread a tile) or 0 (no coarse level)",
            });
        }
        if let Self::Clustered { slices, .. } = *self {
            if !(1..=1024).contains(&slices) {
                return Err(CullError::InvalidParameter {
                    field: "slices",
                    value: slices.to_string(),
                    accepted: "an integer in 1..=1024",
                });
            }
        }
        if let Self::ZBin { bins, .. } = *self {
            if !(1..=MAX_ZBINS).contains(&bins) {
                return Err(CullError::InvalidParameter {
                    field: "bins",
                    value: bins.to_string(),
                    accepted: "an integer in 1..=1024 (depth bins of z-binning)",
                });
            }
        }
        Ok(())
    }

    /// The culling parameters for a `width` x `height` target and `lights` lights.
    pub fn params(
        &self,
        width: u32,
        height: u32,
        lights: u32,
        settings: &CullSettings,
    ) -> GpuCullParams {
        let CullSettings {
            near,
            far,
            slack,
            capacity,
            tile_boxes,
            ..
        } = *settings;
        let ts = self.tile_size();
        let (tiles_x, tiles_y) = (width.div_ceil(ts), height.div_ceil(ts));
        let (slices, slicing, strategy_flags) = match *self {
            Self::TiledGather { .. } | Self::TiledScatter { .. } => (1, SLICING_LINEAR, 0),
            Self::ZBin { bins, slicing, .. } => (bins, slicing.code(), CULL_FLAG_ZBIN),
            Self::DepthMask { .. } => (1, SLICING_LINEAR, CULL_FLAG_DEPTH_MASK),
            Self::Clustered {
                slices,
                slicing,
                skip_empty,
                cells,
                ..
            } => (
                slices,
                slicing.code(),
                (if skip_empty { CULL_FLAG_SKIP_EMPTY } else { 0 })
                    | if cells && tile_boxes {
                        CULL_FLAG_DEPTH_MASK
                    } else {
                        0
                    },
            ),
        };
        let flags = strategy_flags | if tile_boxes { CULL_FLAG_TILE_BOX } else { 0 };
        // An orthographic camera's near plane may be <= 0; exponential slicing then starts at a
        // small positive depth (depths below it fall in slice 0).
        let near_s = if slicing == SLICING_EXPONENTIAL {
            near.max(far * 1e-6).max(1e-6)
        } else {
            near
        };
        let slice_scale = if slicing == SLICING_EXPONENTIAL {
            slices as f32 / (far / near_s).ln()
        } else {
            slices as f32 / (far - near_s)
        };
        GpuCullParams {
            tiles_x,
            tiles_y,
            tile_size: ts,
            light_count: lights,
            slices,
            slicing,
            flags,
            // Z-binning's bin_ranges hold a range a depth bin; every other strategy's a list a
            // tile or cluster.
            bins: if flags & CULL_FLAG_ZBIN != 0 {
                slices
            } else {
                tiles_x * tiles_y * slices
            },
            near: near_s,
            far,
            slack,
            slice_scale,
            capacity: capacity.unwrap_or(0),
            coarse: self.coarse(),
            coarse_x: if self.coarse() > 0 {
                tiles_x.div_ceil(self.coarse())
            } else {
                0
            },
            // Set for the device by `fit_chunks` (Culler::run).
            chunk: 0,
        }
    }
}

/// The largest light count the device `ctx` holds: every per-light buffer fits one storage
/// binding (the lights, 64 bytes each, and tiled scatter's per-lane counts and offsets,
/// `SCATTER_LANES` x 4 bytes a light plus one entry), and, on a driver that stops loops short
/// (`GpuContext::loop_limit`), per-pixel loops over every light stay within its limit.
pub fn max_lights(ctx: &manylights_gpu::GpuContext) -> u32 {
    let limits = &ctx.limits;
    let binding = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    let per_light = 64.max(4 * u64::from(layout::SCATTER_LANES));
    let storage = binding.saturating_sub(4) / per_light;
    let loops = ctx.loop_light_limit().unwrap_or(u64::MAX);
    u32::try_from(storage.min(loops)).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gather_params(w: u32, h: u32, lights: u32) -> GpuCullParams {
        Strategy::tiled_gather(16).params(
            w,
            h,
            lights,
            &CullSettings {
                near: 0.1,
                far: 100.0,
                slack: layout::DEFAULT_SLACK,
                capacity: None,
                mask_budget: None,
                tile_boxes: true,
                occlusion: false,
            },
        )
    }

    #[test]
    fn chunks_grow_until_the_entries_fit() {
        // 1080p: 120 x 68 = 8,160 tiles; 15 coarse tiles across.
        let mut p = gather_params(1920, 1080, 3072);
        fit_chunks(&mut p, MAX_CHUNK_ENTRIES, 65_535, MIN_CHUNK);
        assert_eq!((p.coarse, p.coarse_x, p.chunk), (8, 15, MIN_CHUNK));
        // 1M lights: 8,160 tiles x chunks <= 2^23 entries needs chunks of 1,024 lights.
        let mut p = gather_params(1920, 1080, 1 << 20);
        fit_chunks(&mut p, MAX_CHUNK_ENTRIES, 65_535, MIN_CHUNK);
        assert_eq!(p.chunk, 1024);
        // Another minimum (the ablation knob), rounded to whole batches.
        let mut q = gather_params(1920, 1080, 3072);
        fit_chunks(&mut q, MAX_CHUNK_ENTRIES, 65_535, 1000);
        assert_eq!(q.chunk, 1024);
        fit_chunks(&mut q, MAX_CHUNK_ENTRIES, 65_535, 1);
        assert_eq!(q.chunk, 64);
        assert!(u64::from(p.bins) * u64::from((1u32 << 20).div_ceil(p.chunk)) <= MAX_CHUNK_ENTRIES);
        // One tile and 33.5M lights: the chunks must fit one dispatch dimension.
        let mut p = gather_params(8, 4, 33_554_431);
        fit_chunks(&mut p, MAX_CHUNK_ENTRIES, 65_535, MIN_CHUNK);
        assert!(p.chunk.is_multiple_of(CHUNK_STEP) && 33_554_431u32.div_ceil(p.chunk) <= 65_535);
        // No lights, a capacity, or asked for none: the single level.
        let mut p = gather_params(64, 64, 0);
        fit_chunks(&mut p, MAX_CHUNK_ENTRIES, 65_535, MIN_CHUNK);
        assert_eq!((p.coarse, p.chunk), (0, 0));
        let mut p = gather_params(64, 64, 100);
        p.capacity = 8;
        fit_chunks(&mut p, MAX_CHUNK_ENTRIES, 65_535, MIN_CHUNK);
        assert_eq!(p.coarse, 0);
        let mut p = gather_params(64, 64, 100);
        p.coarse = 0;
        fit_chunks(&mut p, MAX_CHUNK_ENTRIES, 65_535, MIN_CHUNK);
        assert_eq!(p.coarse, 0);
    }
}
