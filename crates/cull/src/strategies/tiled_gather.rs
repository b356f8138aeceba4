//! Forward+ tiled gather (Harada, McKee, Yang 2012, section 4.1): each tile tests the lights
//! against its frustum between its depth bounds (`shaders/cull/tiled_gather/`; oracle
//! [`crate::cpu::gather`], which 2.5D shares). Three paths, chosen per run:
//!
//! 1. **Tile lines** ([`crate::blocks::tile_lines`]): where a bit per (tile, light) fits the
//!    mask budget and [`crate::Culler::gather_lines`] is on (the default).
//! 2. **Coarse-to-fine** (`coarse` = 8): `cull.depth_bounds` also stores each light's tile
//!    rectangle; a workgroup per (coarse tile of 8 x 8 tiles, chunk of lights) tests each light
//!    once per coarse tile and each tile only against the survivors whose rectangle holds it.
//!    Within the mask budget its count pass stores tile masks and the masks' fill expands them
//!    ([`crate::blocks::tile_masks`]; "stored masks"); otherwise a count per (tile, chunk), the
//!    scan, and a fill that tests again and writes each tile's range itself.
//! 3. **Single level** (`coarse` = 0, or a capacity): a workgroup a tile tests every light,
//!    then the scan, the fill and `cull.finalize` ([`crate::blocks::lists`]).
//!
//! The chunk of lights a workgroup takes is fitted to the device by [`crate::fit_chunks`].

use crate::Kernel;
use manylights_gpu::GpuError;

use crate::blocks::tile_depth::{self, Rows};
use crate::blocks::tile_masks;
use crate::culler::{RunInputs, Timing};
use crate::frame::{Frame, Outputs};
use crate::layout::GpuCullParams;
use crate::program::Program;
use crate::record::{Buf, Step};
use crate::strategies::Plan;
use crate::{CullError, CullOutput};

/// Gather's own pipelines (2.5D's too: the same entry points with its flag).
pub(crate) struct Pipelines {
    count: Kernel,
    fill: Kernel,
    count_masks: Kernel,
    count_flat: Kernel,
    fill_flat: Kernel,
}

impl Pipelines {
    /// From gather's program (portable or subgroup scans).
    pub fn new(d: &wgpu::Device, program: &Program) -> Self {
        let [count, fill, count_masks, count_flat, fill_flat] = program.pipelines(
            d,
            [
                "gather_count",
                "gather_fill",
                "gather_count_masks",
                "gather_count_flat",
                "gather_fill_flat",
            ],
        );
        Self {
            count,
            fill,
            count_masks,
            count_flat,
            fill_flat,
        }
    }
}

/// Runs gather (or 2.5D, whose `params` carry its flag): decides the path, checks it against
/// the device, and records it.
pub(crate) fn run(
    r: &RunInputs<'_>,
    mut params: GpuCullParams,
    t: Timing<'_>,
) -> Result<CullOutput, CullError> {
    let c = r.culler;
    let ctx = r.ctx;
    // Decided before the chunks are fitted (with masks they are smaller); fitting may still drop
    // the coarse level, and the masks with it.
    let budget = r.settings.mask_budget.unwrap_or(c.mask_budget);
    let masked = params.coarse > 0 && tile_masks::fits(ctx, &params, budget);
    let min_chunk = if masked {
        c.gather_min_chunk_masked
    } else {
        c.gather_min_chunk
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
    let masked = masked && params.coarse > 0;
    r.check_bins(&params)?;
    tile_depth::check_rows(ctx, &params, params.coarse > 0)?;
    let entries = u64::from(params.bins) * chunks(&params);
    let f = r.frame(params, entries);
    let name = r.strategy.name();
    let done = if masked && c.gather_lines {
        r.execute(&f, r.pipelines.tile_lines.plan(&f, name, &c.placeholder), t)?
    } else {
        r.execute(&f, BinnedPlan::new(r, &f, masked), t)?
    };
    f.finish(done)
}

/// Chunks of lights per bin in the count entries: `ceil(lights / chunk)` for the
/// coarse-to-fine passes, 1 otherwise.
fn chunks(p: &GpuCullParams) -> u64 {
    if p.coarse > 0 && p.chunk > 0 {
        u64::from(p.light_count.div_ceil(p.chunk)).max(1)
    } else {
        1
    }
}

/// A run of the coarse-to-fine or the single-level path.
struct BinnedPlan<'a> {
    r: &'a RunInputs<'a>,
    f: &'a Frame<'a>,
    /// Coarse-to-fine (with the lights' rectangles).
    chunked: bool,
    /// With stored tile masks (coarse-to-fine only).
    masked: bool,
    /// The lights' rectangles (binding 9) where coarse-to-fine.
    rects: Option<wgpu::Buffer>,
    /// The tile masks (binding 11) where masked.
    masks: Option<wgpu::Buffer>,
    group_a: wgpu::BindGroup,
    sized: Option<(wgpu::Buffer, wgpu::BindGroup)>,
}

impl<'a> BinnedPlan<'a> {
    fn new(r: &'a RunInputs<'a>, f: &'a Frame<'a>, masked: bool) -> Self {
        let p = &f.params;
        let chunked = p.coarse > 0;
        let rects = chunked.then(|| f.buf(Buf::LightRects.name(), u64::from(p.light_count) * 8));
        let masks = masked.then(|| tile_masks::buffer(f));
        let placeholder = &r.culler.placeholder;
        // Binding 9: the lights' rectangles; 11: the tile masks (the lists at 7 come later).
        let group_a = f.group(
            placeholder,
            rects.as_ref().unwrap_or(placeholder),
            masks.as_ref().unwrap_or(placeholder),
        );
        Self {
            r,
            f,
            chunked,
            masked,
            rects,
            masks,
            group_a,
            sized: None,
        }
    }

    /// The count and fill passes' workgroups: a workgroup per (coarse tile, chunk of lights),
    /// or a tile.
    fn groups(&self) -> [u32; 3] {
        let p = &self.f.params;
        if self.chunked {
            [
                p.coarse_x,
                p.tiles_y.div_ceil(p.coarse.max(1)),
                p.light_count.div_ceil(p.chunk.max(1)),
            ]
        } else {
            [p.tiles_x, p.tiles_y, 1]
        }
    }

    /// Count entries: a count per bin, or per (bin, chunk of lights).
    fn entries(&self) -> u32 {
        u32::try_from(u64::from(self.f.params.bins) * chunks(&self.f.params))
            .expect("fit_chunks bounds the entries")
    }

    fn name(&self, what: &str) -> String {
        format!("cull.{}.{what}", self.r.strategy.name())
    }
}

impl Plan for BinnedPlan<'_> {
    fn count(&self, _sized: bool) -> Vec<Step<'_>> {
        let (f, q) = (self.f, self.r.pipelines);
        let mut steps = f.clears(self.masked);
        let rows = if self.chunked {
            Rows::Rects
        } else {
            Rows::None
        };
        steps.push(q.tile_depth.pass(&f.params, &self.group_a, rows));
        let g = &q.gather;
        let (pipeline, reads, writes): (_, &'static [Buf], &'static [Buf]) = if self.masked {
            (
                &g.count_masks,
                &[Buf::TileDepth, Buf::LightRects, Buf::Lights],
                &[Buf::TileMasks, Buf::Stats],
            )
        } else if self.chunked {
            (
                &g.count,
                &[Buf::TileDepth, Buf::LightRects, Buf::Lights],
                &[Buf::Counts],
            )
        } else {
            (
                &g.count_flat,
                &[Buf::TileDepth, Buf::Lights],
                &[Buf::Counts],
            )
        };
        steps.push(Step::pass(
            self.name("count"),
            pipeline,
            &self.group_a,
            self.groups(),
            reads,
            writes,
        ));
        // (With tile masks the count pass sums the total itself and the fill places each
        // tile's list with an atomic add: no scan.)
        if !self.masked {
            steps.extend(q.lists.count_tail(f, &self.group_a, self.entries()));
        }
        steps
    }

    fn total(&self) -> Result<u64, GpuError> {
        if self.masked {
            tile_masks::total(self.f)
        } else {
            self.f.bins_total(self.entries())
        }
    }

    fn size(&mut self, total: u32) {
        let placeholder = &self.r.culler.placeholder;
        self.sized = Some(self.f.lists(
            total,
            self.rects.as_ref().unwrap_or(placeholder),
            self.masks.as_ref().unwrap_or(placeholder),
        ));
    }

    fn indices(&self) -> &wgpu::Buffer {
        &self.sized.as_ref().expect("sized before the indices").0
    }

    fn fill(&self, _sized: bool) -> Vec<Step<'_>> {
        let (_, group) = self.sized.as_ref().expect("sized before the fill");
        let (f, q) = (self.f, self.r.pipelines);
        if self.masked {
            return vec![q.tile_masks.fill(self.name("fill"), &f.params, group)];
        }
        if self.chunked {
            // The coarse-to-fine fill writes the ranges itself.
            return vec![Step::pass(
                self.name("fill"),
                &q.gather.fill,
                group,
                self.groups(),
                &[Buf::TileDepth, Buf::LightRects, Buf::Lights, Buf::Offsets],
                &[Buf::Indices, Buf::Ranges],
            )];
        }
        vec![
            Step::pass(
                self.name("fill"),
                &q.gather.fill_flat,
                group,
                self.groups(),
                &[Buf::TileDepth, Buf::Lights, Buf::Offsets],
                // Each workgroup writes its tile's list from its offset, with no cursor.
                &[Buf::Indices],
            ),
            q.lists.finalize(f, group),
        ]
    }

    fn outputs(self) -> Outputs {
        Outputs {
            indices: self.sized.expect("sized before the output").0,
            tile_masks: self.masks,
            tile_lines: None,
        }
    }
}
