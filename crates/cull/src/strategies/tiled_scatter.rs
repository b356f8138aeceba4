//! Forward+ tiled scatter (Harada, McKee, Yang 2012, section 4.2): the work goes by light, not
//! by tile (`shaders/cull/tiled_scatter/`; oracle [`crate::cpu::scatter`]). Two paths:
//!
//! 1. **Tile masks** ([`crate::blocks::tile_masks`], within the mask budget): `cull.depth_bounds`
//!    also stores each light's rectangle and queues its blocks of
//!    [`crate::layout::SCATTER_MASK_THREADS`] tiles; `cull.tiled_scatter.count` sets each
//!    light's bit in every tile of its rectangle that keeps it, a block a workgroup at a time;
//!    the masks' fill expands each tile's bits into its list. No pairs, no sort.
//! 2. **Pairs**, as the paper has it: [`crate::layout::SCATTER_LANES`] threads a light count
//!    the tiles that keep it, the scan of those counts places its (tile, light) pairs
//!    (`cull.tiled_scatter.pairs`), [`crate::radix_sort`] orders them by tile, and
//!    `cull.tiled_scatter.ranges` and `cull.finalize` find each tile's start and end.

use crate::Kernel;
use manylights_gpu::GpuError;

use crate::blocks::tile_depth::{self, Rows};
use crate::blocks::tile_masks;
use crate::culler::{RunInputs, Timing};
use crate::frame::{Frame, Outputs};
use crate::layout::{
    GROUPS_X, GpuCullParams, SCATTER_LANES, SCATTER_MASK_GROUPS, SCATTER_MASK_THREADS,
};
use crate::program::Program;
use crate::radix_sort::{SortedIn, key_bits_for};
use crate::record::{Buf, Step};
use crate::scan::groups_2d;
use crate::strategies::Plan;
use crate::{CullError, CullOutput};

/// Tiled scatter's pipelines.
pub(crate) struct Pipelines {
    count: Kernel,
    pairs: Kernel,
    ranges: Kernel,
    finalize: Kernel,
    masks: Kernel,
}

impl Pipelines {
    /// From tiled scatter's program.
    pub fn new(d: &wgpu::Device, program: &Program) -> Self {
        let [count, pairs, ranges, finalize, masks] = program.pipelines(
            d,
            [
                "scatter_count",
                "scatter_pairs",
                "scatter_ranges",
                "scatter_finalize",
                "scatter_masks",
            ],
        );
        Self {
            count,
            pairs,
            ranges,
            finalize,
            masks,
        }
    }
}

/// Runs tiled scatter: tile masks where they fit, pairs otherwise.
pub(crate) fn run(
    r: &RunInputs<'_>,
    params: GpuCullParams,
    t: Timing<'_>,
) -> Result<CullOutput, CullError> {
    let (c, ctx) = (r.culler, r.ctx);
    let budget = r.settings.mask_budget.unwrap_or(c.mask_budget);
    let masked = tile_masks::fits(ctx, &params, budget);
    r.check_bins(&params)?;
    tile_depth::check_rows(ctx, &params, masked)?;
    if masked {
        let f = r.frame(params, u64::from(params.bins));
        let done = r.execute(&f, MasksPlan::new(r, &f)?, t)?;
        return f.finish(done);
    }
    // Counts and offsets hold one entry per (light, lane).
    let lanes = u64::from(params.light_count) * u64::from(SCATTER_LANES);
    ctx.check_storage("tiled scatter per-lane counts", (lanes + 1) * 4)?;
    let f = r.frame(params, u64::from(params.bins).max(lanes));
    let done = r.execute(&f, PairsPlan::new(r, &f), t)?;
    f.finish(done)
}

/// The path with tile masks.
struct MasksPlan<'a> {
    r: &'a RunInputs<'a>,
    f: &'a Frame<'a>,
    masks: wgpu::Buffer,
    rects: wgpu::Buffer,
    /// Queued blocks of tiles, at most [`SCATTER_MASK_GROUPS`] workgroups' worth at a time.
    groups: u32,
    /// Binding 7: the block queue, until the fill binds the lists there.
    group_a: wgpu::BindGroup,
    sized: Option<(wgpu::Buffer, wgpu::BindGroup)>,
}

impl<'a> MasksPlan<'a> {
    fn new(r: &'a RunInputs<'a>, f: &'a Frame<'a>) -> Result<Self, GpuError> {
        let p = &f.params;
        let masks = tile_masks::buffer(f);
        let rects = f.buf(Buf::LightRects.name(), u64::from(p.light_count) * 8);
        // At most every tile of the screen for each light, in blocks.
        let blocks = u64::from(p.light_count) * u64::from(p.bins.div_ceil(SCATTER_MASK_THREADS));
        r.ctx
            .check_storage("tiled scatter's block queue", blocks * 8)?;
        let queue = f.buf(Buf::BlockQueue.name(), blocks * 8);
        let group_a = f.group(&queue, &rects, &masks);
        Ok(Self {
            r,
            f,
            groups: u32::try_from(blocks.min(u64::from(SCATTER_MASK_GROUPS)))
                .expect("at most SCATTER_MASK_GROUPS"),
            masks,
            rects,
            group_a,
            sized: None,
        })
    }
}

impl Plan for MasksPlan<'_> {
    fn count(&self, _sized: bool) -> Vec<Step<'_>> {
        let (f, q) = (self.f, self.r.pipelines);
        let mut steps = f.clears(true);
        steps.push(q.tile_depth.pass(&f.params, &self.group_a, Rows::Blocks));
        steps.push(Step::pass(
            "cull.tiled_scatter.count",
            &q.scatter().masks,
            &self.group_a,
            (self.groups, 1),
            &[
                Buf::BlockQueue,
                Buf::LightRects,
                Buf::TileDepth,
                Buf::Lights,
                Buf::Stats,
            ],
            &[Buf::TileMasks, Buf::Stats],
        ));
        steps
    }

    fn total(&self) -> Result<u64, GpuError> {
        tile_masks::total(self.f)
    }

    fn size(&mut self, total: u32) {
        self.sized = Some(self.f.lists(total, &self.rects, &self.masks));
    }

    fn indices(&self) -> &wgpu::Buffer {
        &self.sized.as_ref().expect("sized before the indices").0
    }

    fn fill(&self, _sized: bool) -> Vec<Step<'_>> {
        let (_, group) = self.sized.as_ref().expect("sized before the fill");
        let q = self.r.pipelines;
        vec![
            q.tile_masks
                .fill("cull.tiled_scatter.fill".into(), &self.f.params, group),
        ]
    }

    fn outputs(self) -> Outputs {
        Outputs {
            indices: self.sized.expect("sized before the output").0,
            tile_masks: Some(self.masks),
            tile_lines: None,
        }
    }
}

/// The paper's path: pairs and their sort.
struct PairsPlan<'a> {
    r: &'a RunInputs<'a>,
    f: &'a Frame<'a>,
    /// Workgroups of the passes of a thread a (light, lane).
    light_groups: (u32, u32),
    group_a: wgpu::BindGroup,
    sized: Option<Pairs>,
}

/// The pairs' buffers, sized from the count phase's total, and the groups over them.
struct Pairs {
    n: u32,
    keys: wgpu::Buffer,
    vals: wgpu::Buffer,
    keys_tmp: wgpu::Buffer,
    vals_tmp: wgpu::Buffer,
    /// Over the pairs as written.
    group_pairs: wgpu::BindGroup,
    /// Over the pairs in the scratch buffers, where the sort leaves them there.
    group_scratch: Option<wgpu::BindGroup>,
    sorted: SortedIn,
}

impl Pairs {
    /// The group over the pairs where the sort leaves them.
    fn group_sorted(&self) -> &wgpu::BindGroup {
        self.group_scratch.as_ref().unwrap_or(&self.group_pairs)
    }
}

impl<'a> PairsPlan<'a> {
    fn new(r: &'a RunInputs<'a>, f: &'a Frame<'a>) -> Self {
        let work = f.params.light_count * SCATTER_LANES;
        let placeholder = &r.culler.placeholder;
        Self {
            r,
            f,
            light_groups: groups_2d(work.div_ceil(64), GROUPS_X),
            group_a: f.group(placeholder, placeholder, placeholder),
            sized: None,
        }
    }

    /// Key bits of the pairs: enough for the last tile.
    fn bits(&self) -> u32 {
        key_bits_for(self.f.params.bins.saturating_sub(1))
    }
}

impl Plan for PairsPlan<'_> {
    fn count(&self, _sized: bool) -> Vec<Step<'_>> {
        let (f, q) = (self.f, self.r.pipelines);
        let mut steps = f.clears(false);
        steps.push(q.tile_depth.pass(&f.params, &self.group_a, Rows::None));
        steps.push(Step::pass(
            "cull.tiled_scatter.count",
            &q.scatter().count,
            &self.group_a,
            self.light_groups,
            &[Buf::TileDepth, Buf::Lights],
            &[Buf::Counts, Buf::Stats],
        ));
        steps.push(f.scan(f.params.light_count * SCATTER_LANES));
        steps
    }

    /// The pair total, which the count pass sums in 64 bits (`cull_stats[1]`, with the carries
    /// in `cull_stats[2]`).
    fn total(&self) -> Result<u64, GpuError> {
        let sum = self.f.stats(1, 2)?;
        Ok(u64::from(sum[0]) | (u64::from(sum[1]) << 32))
    }

    fn total_names(&self) -> (&'static str, &'static str) {
        ("tiled scatter pairs", "tiled scatter pairs")
    }

    fn size(&mut self, n: u32) {
        let (f, placeholder) = (self.f, &self.r.culler.placeholder);
        let bytes = u64::from(n) * 4;
        let (keys, vals) = (
            f.buf(Buf::PairKeys.name(), bytes),
            f.buf(Buf::Indices.name(), bytes),
        );
        let (keys_tmp, vals_tmp) = (
            f.buf("cull.pair_keys.tmp", bytes),
            f.buf("cull.light_indices.tmp", bytes),
        );
        let sorted = self.r.culler.sort.sorted_for(n, self.bits());
        let group_pairs = f.group(&vals, &keys, placeholder);
        let group_scratch =
            (sorted == SortedIn::Scratch).then(|| f.group(&vals_tmp, &keys_tmp, placeholder));
        self.sized = Some(Pairs {
            n,
            keys,
            vals,
            keys_tmp,
            vals_tmp,
            group_pairs,
            group_scratch,
            sorted,
        });
    }

    fn indices(&self) -> &wgpu::Buffer {
        let s = self.sized.as_ref().expect("sized before the indices");
        match s.sorted {
            SortedIn::Input => &s.vals,
            SortedIn::Scratch => &s.vals_tmp,
        }
    }

    fn fill(&self, _sized: bool) -> Vec<Step<'_>> {
        let s = self.sized.as_ref().expect("sized before the fill");
        let (f, q) = (self.f, self.r.pipelines);
        vec![
            Step::pass(
                "cull.tiled_scatter.pairs",
                &q.scatter().pairs,
                &s.group_pairs,
                self.light_groups,
                &[Buf::TileDepth, Buf::Lights, Buf::Offsets],
                &[Buf::PairKeys, Buf::Indices],
            ),
            Step::Sort {
                keys: &s.keys,
                vals: &s.vals,
                keys_tmp: &s.keys_tmp,
                vals_tmp: &s.vals_tmp,
                pairs: s.n,
                bits: self.bits(),
            },
            Step::pass(
                "cull.tiled_scatter.ranges",
                &q.scatter().ranges,
                s.group_sorted(),
                groups_2d(s.n.div_ceil(64), GROUPS_X),
                &[Buf::PairKeys, Buf::Offsets],
                &[Buf::Ranges, Buf::Cursors],
            ),
            Step::pass(
                "cull.finalize",
                &q.scatter().finalize,
                s.group_sorted(),
                crate::blocks::lists::bin_groups(f),
                &[Buf::Ranges, Buf::Cursors],
                &[Buf::Ranges, Buf::Stats],
            ),
        ]
    }

    fn outputs(self) -> Outputs {
        Outputs {
            indices: self.indices().clone(),
            tile_masks: None,
            tile_lines: None,
        }
    }
}
