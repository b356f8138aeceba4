//! Light-culling strategies of manylights.
//!
//! A strategy takes the depth buffer (where it uses one), the camera and the lights, and writes
//! light lists in one format for every strategy: `bin_ranges[bin] = (offset, count)` into
//! `light_indices`, where a bin is a screen tile or a cluster (tile x depth slice). Every
//! shading backend reads them through `shaders/cull/lookup.wgsl` (`light_list(pixel, depth)`).
//!
//! Passes, in order (profiler scopes in brackets):
//! 1. `cull.depth_bounds` (tiled strategies): per tile, the nearest and farthest covered depth
//!    and the 2.5D geometry mask.
//! 2. `cull.occupancy` (clusters with `skip_empty`): clusters that hold covered pixels;
//!    `cull.<strategy>.coarse` (gather and 2.5D with a coarse level): a bit mask of the lights
//!    each coarse tile keeps.
//! 3. `cull.<strategy>.count`: each bin's light count. 4. `scan.*`: exclusive scan of the
//!    counts into offsets; the total sizes `light_indices` exactly (no capacity, nothing
//!    dropped). 5. `cull.<strategy>.fill`: the lists. 6. `cull.finalize`: the ranges.
//!
//! Strategies ([`Strategy`]): `tiled_gather` (Harada, McKee, Yang 2012, section 4.1),
//! `tiled_scatter` (same paper, section 4.2; pairs sorted by [`radix_sort`]),
//! `depth_mask` (2.5D culling, Harada 2012), `clustered` (Olsson, Billeter, Assarsson 2012).
//! Each has a CPU oracle in [`cpu`]; [`metrics`] holds the exact per-pixel oracle. See
//! docs/STRATEGIES.md for the methods, their tests, parameters, memory and false positives.

pub mod cpu;
pub mod geometry;
pub mod gpu;
pub mod heatmap;
pub mod layout;
pub mod metrics;
pub mod radix_sort;
pub mod scan;

pub use gpu::{BinLists, CullOutput, Culler};

use serde::{Deserialize, Serialize};

use layout::{
    CULL_FLAG_DEPTH_MASK, CULL_FLAG_SKIP_EMPTY, GpuCullParams, SLICING_EXPONENTIAL, SLICING_LINEAR,
};

/// How the depth range of the cluster grid is sliced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Slicing {
    /// Equal depth per slice.
    Linear,
    /// Equal depth ratio per slice: `d_k = near * (far / near)^(k / S)`.
    Exponential,
}

/// A culling strategy and its parameters. In RON, omitted parameters take their defaults:
/// tiles of 16 pixels (64 for clusters), 24 exponential slices, `skip_empty: false`,
/// `ordered: true`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Strategy {
    /// Forward+ tiled gather: one workgroup per tile tests every light against the tile frustum
    /// between the tile's depth bounds.
    TiledGather {
        /// Tile side in pixels (the paper's 8; 16 and 32 are common).
        #[serde(default = "default_tile")]
        tile_size: u32,
        /// Coarse-to-fine: lights are first culled against coarse tiles of `coarse` x `coarse`
        /// tiles (`cull.tiled_gather.coarse`, a bit mask of lights per coarse tile), and each
        /// tile tests only its coarse tile's lights. The lists are the same; 0 tests every
        /// light at every tile (the paper's single level).
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
    },
}

fn default_ordered() -> bool {
    true
}

/// The default side of gather's coarse tiles, in tiles.
pub const DEFAULT_COARSE: u32 = 8;

fn default_coarse() -> u32 {
    DEFAULT_COARSE
}

/// The most bytes gather's coarse masks may take; past it, coarse tiles grow.
pub const COARSE_MASK_BUDGET: u64 = 256 << 20;

/// Fits gather's coarse level in `p` (coarse tiles of `p.coarse` x `p.coarse` tiles; 0: none)
/// to a device: the side doubles until the masks (a bit per light per coarse tile) fit `budget`
/// bytes, up to one coarse tile for the whole image. Where even that has no room, or the mask
/// words need more than `max_groups` workgroups of 64 in one dispatch dimension, no coarse level:
/// the lists are then the single level's (a superset, equally conservative).
pub fn fit_coarse(p: &mut GpuCullParams, budget: u64, max_groups: u32) {
    let want = p.coarse;
    p.coarse = 0;
    p.coarse_x = 0;
    let words = u64::from(p.light_count.div_ceil(32));
    if want == 0 || words == 0 || words.div_ceil(64) > u64::from(max_groups) {
        return;
    }
    let mut side = want;
    loop {
        let (cx, cy) = (p.tiles_x.div_ceil(side), p.tiles_y.div_ceil(side));
        if u64::from(cx) * u64::from(cy) * words * 4 <= budget {
            p.coarse = side;
            p.coarse_x = cx;
            return;
        }
        if cx == 1 && cy == 1 {
            return;
        }
        side *= 2;
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
}

impl Strategy {
    /// The strategy's name: its file names, profiler scopes and result column value.
    pub fn name(&self) -> &'static str {
        match self {
            Self::TiledGather { .. } => "tiled_gather",
            Self::TiledScatter { .. } => "tiled_scatter",
            Self::DepthMask { .. } => "depth_mask",
            Self::Clustered { .. } => "clustered",
        }
    }

    /// The default parameters of each strategy, in a fixed order.
    pub fn defaults() -> [Strategy; 4] {
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
            | Self::Clustered { tile_size, .. } => tile_size,
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
        if self.coarse() > 64 {
            return Err(CullError::InvalidParameter {
                field: "coarse",
                value: self.coarse().to_string(),
                accepted: "an integer in 0..=64 tiles (0: no coarse level)",
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
        } = *settings;
        let ts = self.tile_size();
        let (tiles_x, tiles_y) = (width.div_ceil(ts), height.div_ceil(ts));
        let (slices, slicing, flags) = match *self {
            Self::TiledGather { .. } | Self::TiledScatter { .. } => (1, SLICING_LINEAR, 0),
            Self::DepthMask { .. } => (1, SLICING_LINEAR, CULL_FLAG_DEPTH_MASK),
            Self::Clustered {
                slices,
                slicing,
                skip_empty,
                ..
            } => (
                slices,
                match slicing {
                    Slicing::Linear => SLICING_LINEAR,
                    Slicing::Exponential => SLICING_EXPONENTIAL,
                },
                if skip_empty { CULL_FLAG_SKIP_EMPTY } else { 0 },
            ),
        };
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
            bins: tiles_x * tiles_y * slices,
            near: near_s,
            far,
            slack,
            slice_scale,
            capacity: capacity.unwrap_or(0),
            // The device may need larger coarse tiles for the masks to fit (Culler::run).
            coarse: self.coarse(),
            coarse_x: if self.coarse() > 0 {
                tiles_x.div_ceil(self.coarse())
            } else {
                0
            },
            _pad: 0,
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

/// Settings of a culling run that are not the strategy's own.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CullSettings {
    /// The camera's near plane distance.
    pub near: f32,
    /// The camera's far plane distance.
    pub far: f32,
    /// Conservative slack, relative to each light's distance (see `layout::DEFAULT_SLACK`).
    pub slack: f32,
    /// A deliberate cap on each list's length; lights beyond it are dropped and counted in
    /// [`CullOutput::dropped`]. `None` (the default): lists are sized exactly, nothing dropped.
    pub capacity: Option<u32>,
}

impl CullSettings {
    /// The settings for `camera`, with the default slack and no capacity.
    pub fn for_camera(camera: &manylights_scene::Camera) -> Self {
        let (near, far) = camera.near_far();
        Self {
            near,
            far,
            slack: layout::DEFAULT_SLACK,
            capacity: None,
        }
    }

    /// Checks the values.
    pub fn validate(&self) -> Result<(), CullError> {
        if !(self.slack.is_finite() && self.slack >= 0.0) {
            return Err(CullError::InvalidParameter {
                field: "slack",
                value: self.slack.to_string(),
                accepted: "a finite value >= 0",
            });
        }
        if self.capacity == Some(0) {
            return Err(CullError::InvalidParameter {
                field: "capacity",
                value: "0".into(),
                accepted: "an integer >= 1, or none",
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gather_params(w: u32, h: u32, lights: u32, coarse: u32) -> GpuCullParams {
        Strategy::TiledGather {
            tile_size: 16,
            coarse,
        }
        .params(
            w,
            h,
            lights,
            &CullSettings {
                near: 0.1,
                far: 100.0,
                slack: layout::DEFAULT_SLACK,
                capacity: None,
            },
        )
    }

    #[test]
    fn coarse_level_grows_until_the_masks_fit() {
        // 1080p: 120 x 68 tiles; 8-tile coarse tiles: 15 x 9; 1M lights: 32,768 words.
        let mut p = gather_params(1920, 1080, 1 << 20, 8);
        fit_coarse(&mut p, u64::MAX, 65_535);
        assert_eq!((p.coarse, p.coarse_x), (8, 15));
        // 135 coarse tiles x 128 KiB do not fit 4 MiB; 16-tile ones (8 x 5 = 40, 5 MiB) do not
        // either; 32-tile ones (4 x 3 = 12, 1.5 MiB) do.
        let mut p = gather_params(1920, 1080, 1 << 20, 8);
        fit_coarse(&mut p, 4 << 20, 65_535);
        assert_eq!((p.coarse, p.coarse_x), (32, 4));
        // Not even one coarse tile's mask fits: no coarse level.
        let mut p = gather_params(1920, 1080, 1 << 20, 8);
        fit_coarse(&mut p, 1 << 10, 65_535);
        assert_eq!((p.coarse, p.coarse_x), (0, 0));
        // More mask words than one dispatch dimension reaches: no coarse level.
        let mut p = gather_params(64, 64, 1 << 20, 8);
        fit_coarse(&mut p, u64::MAX, 8);
        assert_eq!(p.coarse, 0);
        // Asked for none, and no lights: none.
        for (lights, coarse) in [(1024, 0), (0, 8)] {
            let mut p = gather_params(64, 64, lights, coarse);
            fit_coarse(&mut p, u64::MAX, 65_535);
            assert_eq!(p.coarse, 0);
        }
    }
}
