//! Gather's and 2.5D's lines path (`shaders/cull/common/tile_lines.wgsl`), taken where a bit per
//! (tile, light) fits the mask budget (as at the Forward+ paper's configuration): two passes, no
//! stored tile masks, no chunks, no scan.
//!
//! 1. `cull.tile_lines` writes the tile lines: for each column of tiles, each row and each
//!    depth bin, a bit per light (the light's rectangle spans the line and it passes the line's
//!    two side planes; its depth extent's bins hold the bin), and after them each light's depth
//!    extent. A tile's column word AND its row word are the lights that pass its four side
//!    planes.
//! 2. `cull.<strategy>.fill`: [`line_threads`] threads a tile compute the tile's depth data,
//!    AND its words (and those of its depth bins), test the candidates' depth extents, and
//!    write the tile's list in light order. Alone, a count pass of the same kind
//!    (`cull.<strategy>.count`) sizes the lists first; back to back, a run is the two passes.
//!
//! The oracle is [`crate::cpu::tile_lines`]; docs/STRATEGIES.md has the method and its figures.

use crate::Kernel;
use manylights_gpu::GpuError;

use crate::frame::{Frame, Outputs};
use crate::layout::{
    DEPTH_TILES, GROUPS_X, GpuCullParams, LINE_GROUP_THREADS, LINE_THREAD_COUNTS, LINES_PER_GROUP,
    ZBINS, line_threads,
};
use crate::program::Program;
use crate::record::{Buf, Step};
use crate::scan::groups_2d;
use crate::strategies::Plan;

/// The lines path's pipelines: `cull.tile_lines`, and its list passes for each of
/// [`LINE_THREAD_COUNTS`] threads a tile.
pub(crate) struct TileLines {
    lines: Kernel,
    count: [Kernel; 3],
    fill: [Kernel; 3],
}

impl TileLines {
    /// `cull.tile_lines` from `cull.depth_bounds`'s program, the list passes from gather's
    /// (they use its workgroup scan).
    pub fn new(d: &wgpu::Device, depth: &Program, gather: &Program) -> Self {
        Self {
            lines: depth.pipeline(d, "tile_lines_pass"),
            count: line_pipelines(d, gather, "gather_lines_count"),
            fill: line_pipelines(d, gather, "gather_lines_fill"),
        }
    }

    /// The plan of a run of strategy `name` (`tiled_gather` or `depth_mask`) over `f`.
    pub fn plan<'a>(
        &'a self,
        f: &'a Frame<'a>,
        name: &'static str,
        placeholder: &'a wgpu::Buffer,
    ) -> LinesPlan<'a> {
        let lines = f.buf(Buf::TileLines.name(), buffer_bytes(&f.params));
        LinesPlan {
            block: self,
            f,
            name,
            group_a: f.group(placeholder, placeholder, &lines),
            lines,
            placeholder,
            sized: None,
        }
    }
}

/// Entry point `entry` of `program` built once for each of [`LINE_THREAD_COUNTS`] (the
/// shader's `LINE_THREADS` override).
fn line_pipelines(d: &wgpu::Device, program: &Program, entry: &'static str) -> [Kernel; 3] {
    // (Without zeroing workgroup memory, which these passes do not need, measured the same on
    // an H100.)
    LINE_THREAD_COUNTS.map(|t| program.pipeline_with(d, entry, &[("LINE_THREADS", f64::from(t))]))
}

/// The pipeline of `set` for `light_count` lights ([`line_threads`]).
fn line_pipeline(set: &[Kernel; 3], light_count: u32) -> &Kernel {
    let t = line_threads(light_count);
    let i = LINE_THREAD_COUNTS
        .iter()
        .position(|&c| c == t)
        .expect("line_threads returns one of LINE_THREAD_COUNTS");
    &set[i]
}

/// Workgroups of `cull.tile_lines`: one for each 64 [`DEPTH_TILES`] lights and
/// [`LINES_PER_GROUP`] lines of tiles.
fn lines_groups(p: &GpuCullParams) -> (u32, u32) {
    let chunks = (p.tiles_x + p.tiles_y + ZBINS).div_ceil(LINES_PER_GROUP);
    let groups = p.light_count.div_ceil(64 * DEPTH_TILES) * chunks;
    groups_2d(groups, GROUPS_X)
}

/// Workgroups of the list passes: [`LINE_GROUP_THREADS`] / [`line_threads`] tiles of a row each.
fn list_groups(p: &GpuCullParams) -> (u32, u32) {
    let tiles = LINE_GROUP_THREADS / line_threads(p.light_count);
    (p.tiles_x.div_ceil(tiles), p.tiles_y)
}

/// Bytes of the tile lines: two words a column or row of tiles or depth bin for each 64 lights.
pub(crate) fn bytes(p: &GpuCullParams) -> u64 {
    u64::from(p.tiles_x + p.tiles_y + ZBINS) * u64::from(p.light_count.div_ceil(64)) * 8
}

/// Bytes of the tile lines and, after them, each light's depth extent and view-space sphere
/// (eight f32).
fn buffer_bytes(p: &GpuCullParams) -> u64 {
    bytes(p) + u64::from(p.light_count) * 32
}

/// A run of the lines path.
pub(crate) struct LinesPlan<'a> {
    block: &'a TileLines,
    f: &'a Frame<'a>,
    name: &'static str,
    lines: wgpu::Buffer,
    /// The group before the lists exist (the lines at binding 11).
    group_a: wgpu::BindGroup,
    placeholder: &'a wgpu::Buffer,
    /// The lists and the group over them.
    sized: Option<(wgpu::Buffer, wgpu::BindGroup)>,
}

impl Plan for LinesPlan<'_> {
    fn count(&self, sized: bool) -> Vec<Step<'_>> {
        let p = &self.f.params;
        // No clear: `cull.tile_lines` zeroes the list passes' cursor, the only counter these
        // runs use (a clear is a transfer of its own between passes).
        let mut steps = vec![Step::pass(
            "cull.tile_lines",
            &self.block.lines,
            &self.group_a,
            lines_groups(p),
            &[Buf::Lights],
            &[Buf::TileLines, Buf::Stats],
        )];
        if !sized {
            steps.push(Step::pass(
                format!("cull.{}.count", self.name),
                line_pipeline(&self.block.count, p.light_count),
                &self.group_a,
                list_groups(p),
                &[Buf::Depth, Buf::TileLines],
                // Its tiles' depth data, as the fill pass writes them (tile_bounds).
                &[Buf::TileDepth, Buf::Stats],
            ));
        }
        steps
    }

    /// The total the count pass (and every fill) sums into `cull_stats[5]`.
    fn total(&self) -> Result<u64, GpuError> {
        Ok(u64::from(self.f.stats(5, 1)?[0]))
    }

    fn size(&mut self, total: u32) {
        self.sized = Some(self.f.lists(total, self.placeholder, &self.lines));
    }

    fn indices(&self) -> &wgpu::Buffer {
        &self.sized.as_ref().expect("sized before the indices").0
    }

    fn fill(&self, sized: bool) -> Vec<Step<'_>> {
        let (_, group) = self.sized.as_ref().expect("sized before the fill");
        let p = &self.f.params;
        let mut steps = Vec::with_capacity(2);
        if !sized {
            // The count pass left its total in the fill's cursor.
            steps.push(Step::Clear {
                what: Buf::Stats,
                buffer: &self.f.stats,
                offset: 20,
                size: Some(4),
            });
        }
        steps.push(Step::pass(
            format!("cull.{}.fill", self.name),
            line_pipeline(&self.block.fill, p.light_count),
            group,
            list_groups(p),
            &[Buf::Depth, Buf::TileLines],
            &[Buf::Indices, Buf::Ranges, Buf::TileDepth, Buf::Stats],
        ));
        steps
    }

    fn outputs(self) -> Outputs {
        Outputs {
            indices: self.sized.expect("sized before the output").0,
            tile_masks: None,
            tile_lines: Some(self.lines),
        }
    }
}
