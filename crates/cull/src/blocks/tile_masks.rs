//! Tile masks (`shaders/cull/common/tile_masks.wgsl`): a bit per (tile, light), two words a
//! tile for each 64 lights. A strategy's count pass sets the bits of the lights it keeps and
//! sums the list total (`cull_stats[4]`; gather's and 2.5D's stored masks, tiled scatter's masks);
//! one fill, [`crate::layout::MASK_FILL_TILES`] tiles a workgroup, expands each tile's bits into
//! its list in light order without testing again, places the list with one atomic add a tile
//! (no scan), writes its range, and leaves the words zero for the next count pass.
//! Used where the masks fit [`crate::Culler::mask_budget`] (`fits`).

use crate::Kernel;
use manylights_gpu::{GpuContext, GpuError};

use crate::frame::Frame;
use crate::layout::{GpuCullParams, MASK_FILL_TILES};
use crate::program::Program;
use crate::record::{Buf, Step};

/// The fill's pipeline (in gather's program, which holds the workgroup scan it uses).
pub(crate) struct TileMasks {
    fill: Kernel,
}

impl TileMasks {
    /// Its pipeline from gather's program.
    pub fn new(d: &wgpu::Device, program: &Program) -> Self {
        Self {
            fill: program.pipeline(d, "gather_fill_masks"),
        }
    }

    /// The fill, named `name` (`cull.<strategy>.fill`), over `group` (the lists at binding 7,
    /// the masks at 11).
    pub fn fill<'a>(
        &'a self,
        name: String,
        p: &GpuCullParams,
        group: &'a wgpu::BindGroup,
    ) -> Step<'a> {
        Step::pass(
            name,
            &self.fill,
            group,
            fill_groups(p),
            &[Buf::TileMasks],
            &[Buf::Indices, Buf::Ranges, Buf::TileMasks, Buf::Stats],
        )
    }
}

/// Bytes of the tile masks: two words a tile for each 64 lights.
pub(crate) fn bytes(p: &GpuCullParams) -> u64 {
    u64::from(p.bins) * u64::from(p.light_count.div_ceil(64)) * 8
}

/// Whether tile masks may serve `p`: no capacity, masks within `budget` and the device's
/// buffers, and bins x lights within u32 (the masked count passes sum the total in a u32).
pub(crate) fn fits(ctx: &GpuContext, p: &GpuCullParams, budget: u64) -> bool {
    p.capacity == 0
        && p.light_count > 0
        && u64::from(p.bins) * u64::from(p.light_count) < 1 << 32
        && bytes(p)
            <= budget.min(
                ctx.limits
                    .max_storage_buffer_binding_size
                    .min(ctx.limits.max_buffer_size),
            )
}

/// Workgroups of the fill: [`MASK_FILL_TILES`] tiles of a row each.
fn fill_groups(p: &GpuCullParams) -> (u32, u32) {
    (p.tiles_x.div_ceil(MASK_FILL_TILES), p.tiles_y)
}

/// The masks of `f`.
pub(crate) fn buffer(f: &Frame<'_>) -> wgpu::Buffer {
    f.buf(Buf::TileMasks.name(), bytes(&f.params))
}

/// The list total the masked count pass summed (`cull_stats[4]`; it cannot wrap: [`fits`]
/// bounds bins x lights below 2^32).
pub(crate) fn total(f: &Frame<'_>) -> Result<u64, GpuError> {
    Ok(u64::from(f.stats(4, 1)?[0]))
}
