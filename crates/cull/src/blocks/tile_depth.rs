//! `cull.depth_bounds` (Harada 2012, GPU Pro 4 section 5.6.1): per tile, the nearest and
//! farthest covered linear depth, the covered pixels and the 2.5D geometry mask (32 cells over
//! [dmin, dmax]), [`crate::layout::DEPTH_TILES`] tiles a workgroup
//! (`shaders/cull/common/depth_bounds.wgsl`, `tile_depth.wgsl`; oracle [`crate::cpu::depth_bounds`]).
//! Rows of workgroups before the tiles' store each light's tile rectangle where a strategy asks
//! for them (gather's coarse-to-fine passes and stored masks), or also queue the light's blocks
//! of tiles (tiled scatter with tile masks): one pass, not two, as each pass has a fixed cost
//! larger than this work.

use crate::Kernel;
use manylights_gpu::{GpuContext, GpuError};

use crate::layout::{DEPTH_TILES, GpuCullParams};
use crate::program::Program;
use crate::record::{Buf, Step};

/// The pass's pipelines.
pub(crate) struct TileDepth {
    depth_bounds: Kernel,
    depth_bounds_blocks: Kernel,
    /// The device's most workgroups along a dispatch dimension.
    max_groups: u32,
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
    /// Its pipelines from `cull.depth_bounds`'s program, dispatched within `ctx`'s limits.
    pub fn new(ctx: &GpuContext, program: &Program) -> Self {
        let [depth_bounds, depth_bounds_blocks] =
            program.pipelines(&ctx.device, ["depth_bounds", "depth_bounds_blocks"]);
        Self {
            depth_bounds,
            depth_bounds_blocks,
            max_groups: ctx.limits.max_compute_workgroups_per_dimension,
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
            groups(p, rows != Rows::None, self.max_groups),
            reads,
            writes,
        )
    }
}

/// Workgroups of `cull.depth_bounds`: [`DEPTH_TILES`] tiles of a row each, and with `rects`
/// rows before the tiles' that store the lights' tile rectangles, 64 [`DEPTH_TILES`] lights a
/// workgroup. The rows are as wide as the tiles' unless the lights' rows would then pass
/// `max_groups` (millions of lights over a narrow target): then wider, the tile rows' extra
/// workgroups holding no tile.
pub(crate) fn groups(p: &GpuCullParams, rects: bool, max_groups: u32) -> (u32, u32) {
    let x = p.tiles_x.div_ceil(DEPTH_TILES);
    if !rects {
        return (x, p.tiles_y);
    }
    let lights = p.light_count.div_ceil(64 * DEPTH_TILES);
    let x = x.max(lights.div_ceil(max_groups.saturating_sub(p.tiles_y).max(1)));
    (x, p.tiles_y + lights.div_ceil(x))
}

/// Checks that the pass's workgroups (tiles, and with `rects` light rectangles) fit the
/// device's dispatch.
pub(crate) fn check_rows(ctx: &GpuContext, p: &GpuCullParams, rects: bool) -> Result<(), GpuError> {
    let limit = ctx.limits.max_compute_workgroups_per_dimension;
    let (x, rows) = groups(p, rects, limit);
    if rows > limit || x > limit {
        return Err(GpuError::OverLimit {
            what: "cull.depth_bounds workgroups along one dimension (tiles and light rectangles)"
                .into(),
            value: rows.max(x).into(),
            limit: limit.into(),
            limit_name: "max_compute_workgroups_per_dimension",
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(tiles: (u32, u32), lights: u32) -> GpuCullParams {
        GpuCullParams {
            tiles_x: tiles.0,
            tiles_y: tiles.1,
            light_count: lights,
            ..bytemuck::Zeroable::zeroed()
        }
    }

    /// Every tile and every light has a workgroup, within the limit, and the light rows are as
    /// wide as the tiles' unless the limit makes them wider.
    #[test]
    fn groups_cover_tiles_and_lights_within_the_limit() {
        let per = 64 * DEPTH_TILES;
        for (tiles, lights, limit) in [
            ((120, 68), 1 << 20, 65_535),
            ((1, 1), 1 << 27, 65_535),
            ((1, 1), 100_000, 32),
            ((9, 5), 3_000, 7),
            ((4, 2), 0, 4),
        ] {
            let p = params(tiles, lights);
            let (x, rows) = groups(&p, true, limit);
            assert!(
                x <= limit && rows <= limit,
                "{tiles:?} {lights} {limit}: {x} x {rows}"
            );
            assert!(x * DEPTH_TILES >= tiles.0);
            assert!(
                (rows - tiles.1) * x * per >= lights,
                "{tiles:?} {lights}: {x} x {rows}"
            );
            if lights.div_ceil(per) + tiles.1 <= limit {
                assert_eq!(x, tiles.0.div_ceil(DEPTH_TILES));
            }
            assert_eq!(
                groups(&p, false, limit),
                (tiles.0.div_ceil(DEPTH_TILES), tiles.1)
            );
        }
    }
}
