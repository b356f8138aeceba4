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
//! 2. `cull.occupancy` (clusters with `skip_empty`): clusters that hold covered pixels.
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
            Self::TiledGather { tile_size: 16 },
            Self::TiledScatter { tile_size: 16 },
            Self::DepthMask { tile_size: 16 },
            Self::Clustered {
                tile_size: 64,
                slices: 24,
                slicing: Slicing::Exponential,
                skip_empty: false,
                ordered: true,
            },
        ]
    }

    /// Tile side in pixels.
    pub fn tile_size(&self) -> u32 {
        match *self {
            Self::TiledGather { tile_size }
            | Self::TiledScatter { tile_size }
            | Self::DepthMask { tile_size }
            | Self::Clustered { tile_size, .. } => tile_size,
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
            _pad: [0; 3],
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
