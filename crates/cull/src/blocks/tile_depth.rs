//! `cull.depth_bounds` (Harada 2012, GPU Pro 4 section 5.6.1): per tile, the nearest and
//! farthest covered linear depth, the covered pixels and the 2.5D geometry mask (32 cells over
//! [dmin, dmax]), [`crate::layout::DEPTH_TILES`] tiles a workgroup
//! (`shaders/cull/common/depth_bounds.wgsl`, `tile_depth.wgsl`; oracle [`crate::cpu::depth_bounds`]).
//! Rows of workgroups before the tiles' store each light's tile rectangle where a strategy asks
//! for them (gather's coarse-to-fine passes and stored masks), or also queue the light's blocks
//! of tiles (tiled scatter with tile masks): one pass, not two, as each pass has a fixed cost
//! larger than this work.

use manylights_gpu::{GpuContext, GpuError};

use crate::layout::{DEPTH_TILES, GpuCullParams};
use crate::program::Program;
use crate::record::{Buf, Step};

/// The pass's pipelines.
pub(crate) struct TileDepth {
    depth_bounds: wgpu::ComputePipeline,
    depth_bounds_blocks: wgpu::ComputePipeline,
}

/// What `cull.depth_bounds` writes besides the tiles' depth.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Rows {
    /// Nothing.
    None,
    /// Each light's tile rectangle.
    Rects,
    /// Each light's rectangle and its blocks of tiles (tiled scatter's masks).
    Blocks,
}

impl TileDepth {
    /// Its pipelines from `cull.depth_bounds`'s program.
    pub fn new(d: &wgpu::Device, program: &Program) -> Self {
        let [depth_bounds, depth_bounds_blocks] =
            program.pipelines(d, ["depth_bounds", "depth_bounds_blocks"]);
        Self {
            depth_bounds,
            depth_bounds_blocks,
        }
    }

    /// The pass over `group`, with the light rows `rows` asks for.
    pub fn pass<'a>(
        &'a self,
        p: &GpuCullParams,
        group: &'a wgpu::BindGroup,
        rows: Rows,
    ) -> Step<'a> {
        let (pipeline, reads, writes): (_, &'static [Buf], &'static [Buf]) = match rows {
            Rows::None => (&self.depth_bounds, &[Buf::Depth], &[Buf::TileDepth]),
            Rows::Rects => (
                &self.depth_bounds,
                &[Buf::Depth, Buf::Lights],
                &[Buf::TileDepth, Buf::LightRects],
            ),
            Rows::Blocks => (
                &self.depth_bounds_blocks,
                &[Buf::Depth, Buf::Lights],
                &[Buf::TileDepth, Buf::LightRects, Buf::BlockQueue, Buf::Stats],
            ),
        };
        Step::pass(
            "cull.depth_bounds",
            pipeline,
            group,
            groups(p, rows != Rows::None),
            reads,
            writes,
        )
    }
}

/// Workgroups of `cull.depth_bounds`: [`DEPTH_TILES`] tiles of a row each, and with `rects`
/// rows before the tiles' that store the lights' tile rectangles, a light a thread.
pub(crate) fn groups(p: &GpuCullParams, rects: bool) -> (u32, u32) {
    let x = p.tiles_x.div_ceil(DEPTH_TILES);
    let rows = if rects {
        p.light_count.div_ceil(x * 64 * DEPTH_TILES)
    } else {
        0
    };
    (x, p.tiles_y + rows)
}

/// Checks that the pass's rows of workgroups (tiles, and with `rects` light rectangles) fit
/// the device's dispatch.
pub(crate) fn check_rows(ctx: &GpuContext, p: &GpuCullParams, rects: bool) -> Result<(), GpuError> {
    let (_, rows) = groups(p, rects);
    let limit = ctx.limits.max_compute_workgroups_per_dimension;
    if rows > limit {
        return Err(GpuError::OverLimit {
            what: "cull.depth_bounds workgroup rows (tiles and light rectangles)".into(),
            value: rows.into(),
            limit: limit.into(),
            limit_name: "max_compute_workgroups_per_dimension",
        });
    }
    Ok(())
}
