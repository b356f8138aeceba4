//! Z-binning with tile bitmasks (Drobot, "Improved Culling for Tiled and Clustered Rendering",
//! SIGGRAPH 2017 Advances, as Call of Duty: Infinite Warfare ships it; Unity URP's Forward+):
//! `shaders/cull/zbin/`; oracles [`crate::cpu::zbin_order`] and [`crate::cpu::zbin_lists`].
//! No list a bin: the lights sorted by view depth, each depth bin the range of sorted lights
//! that reach it, each tile a bit a sorted light; a pixel's lights are its tile's bits within
//! its depth bin's range (`shaders/cull/common/lookup.wgsl`). Memory is `bins` ranges, the sorted lights and
//! `tiles x lights / 8` bytes of masks, known before the run: nothing is counted, nothing can
//! overflow. The passes of a run:
//!
//! 1. `cull.depth_bounds` ([`crate::blocks::tile_depth`]), with the lights' tile rectangles.
//! 2. `cull.zbin.keys`: each light's sort key, the depth sub-bin of its centre.
//! 3. [`crate::radix_sort`] orders the lights by key (stably: ties in light order).
//! 4. `cull.zbin.bins`: each bin's range of sorted lights, from their depth extents.
//! 5. Each tile's mask, by one of two paths with the same bits
//!    ([`crate::Culler::zbin_scatter_min_lights`] picks):
//!    - gather: `cull.zbin.masks`, a workgroup a tile testing every sorted light of its cover
//!      (the bins of its depth bounds): work as tiles x the lights of a cover;
//!    - scatter: `cull.zbin.covers` (a workgroup a tile: its cover, its mask zeroed), then
//!      `cull.zbin.scatter` (`shaders/cull/zbin/zbin_scatter.wgsl`, four threads a sorted
//!      light: its bit in each tile of its rectangle that keeps it): work as the (light, tile)
//!      pairs.

use crate::Kernel;
use manylights_gpu::GpuError;

use crate::blocks::tile_depth::{self, Rows};
use crate::culler::{RunInputs, Timing};
use crate::frame::{Frame, Outputs};
use crate::layout::{GROUPS_X, GpuCullParams};
use crate::program::Program;
use crate::radix_sort::{SortedIn, key_bits_for};
use crate::record::{Buf, Step};
use crate::scan::groups_2d;
use crate::strategies::Plan;
use crate::{CullError, CullOutput};

/// Sub-bins of a depth bin in the sort keys (`ZBIN_KEY_SUB` in the shader).
pub const KEY_SUB: u32 = 64;

/// Threads of `cull.zbin.scatter` a sorted light (`ZBIN_SCATTER_LANES` in its shader).
const SCATTER_LANES: u32 = 4;

/// Z-binning's pipelines.
pub(crate) struct Pipelines {
    keys: Kernel,
    bins: Kernel,
    masks: Kernel,
    covers: Kernel,
    scatter: Kernel,
}

impl Pipelines {
    /// From z-binning's programs: its passes', and its scatter pass's.
    pub fn new(d: &wgpu::Device, program: &Program, scatter: &Program) -> Self {
        let [keys, bins, masks, covers] = program.pipelines(
            d,
            ["zbin_keys", "zbin_bins", "zbin_masks", "zbin_covers_pass"],
        );
        Self {
            keys,
            bins,
            masks,
            covers,
            scatter: scatter.pipeline(d, "zbin_scatter"),
        }
    }
}

/// Words of a tile's mask for `p`.
pub fn mask_words(p: &GpuCullParams) -> u64 {
    u64::from(p.light_count.div_ceil(32))
}

/// Words of `light_indices` for `p`: the sorted lights, then every tile's mask.
pub fn index_words(p: &GpuCullParams) -> u64 {
    u64::from(p.light_count) + u64::from(p.tiles_x * p.tiles_y) * mask_words(p)
}

/// Key bits of the sort for `p`.
pub fn key_bits(p: &GpuCullParams) -> u32 {
    key_bits_for(p.slices * KEY_SUB - 1)
}

/// Runs z-binning.
pub(crate) fn run(
    r: &RunInputs<'_>,
    params: GpuCullParams,
    t: Timing<'_>,
) -> Result<CullOutput, CullError> {
    if let Some(c) = r.settings.capacity {
        return Err(CullError::InvalidParameter {
            field: "capacity",
            value: c.to_string(),
            accepted: "none for zbin (its masks hold every light of a tile; there are no \
                       per-bin lists to cap)",
        });
    }
    r.check_bins(&params)?;
    tile_depth::check_rows(r.ctx, &params, true)?;
    r.ctx
        .check_storage("zbin masks and sorted lights", index_words(&params) * 4)?;
    let f = r.frame(params, 0);
    let done = r.execute(&f, ZBinPlan::new(r, &f), t)?;
    f.finish(done)
}

/// A run of z-binning.
struct ZBinPlan<'a> {
    r: &'a RunInputs<'a>,
    f: &'a Frame<'a>,
    keys: wgpu::Buffer,
    keys_tmp: wgpu::Buffer,
    /// The sort's values in and out: the one the sort leaves them in also holds the masks.
    vals: wgpu::Buffer,
    vals_tmp: wgpu::Buffer,
    sorted: SortedIn,
    /// Over the keys (binding 9) and the values as written (7).
    group_keys: wgpu::BindGroup,
    /// Over the rectangles (9), the sorted lights with the masks (7) and (the scatter path)
    /// the tiles' covers (11).
    group_lists: wgpu::BindGroup,
    /// Whether the masks take the scatter path.
    scatter: bool,
}

impl<'a> ZBinPlan<'a> {
    fn new(r: &'a RunInputs<'a>, f: &'a Frame<'a>) -> Self {
        let p = &f.params;
        let n = u64::from(p.light_count) * 4;
        let sorted = r.culler.sort.sorted_for(p.light_count, key_bits(p));
        let big = index_words(p) * 4;
        let (vals_bytes, tmp_bytes) = match sorted {
            SortedIn::Input => (big, n),
            SortedIn::Scratch => (n, big),
        };
        let vals = f.buf(Buf::Indices.name(), vals_bytes);
        let vals_tmp = f.buf("cull.light_indices.tmp", tmp_bytes);
        let keys = f.buf(Buf::PairKeys.name(), n);
        let keys_tmp = f.buf("cull.pair_keys.tmp", n);
        let rects = f.buf(Buf::LightRects.name(), n * 2);
        let placeholder = &r.culler.placeholder;
        let lists = match sorted {
            SortedIn::Input => &vals,
            SortedIn::Scratch => &vals_tmp,
        };
        let scatter = p.light_count >= r.culler.zbin_scatter_min_lights;
        let covers =
            scatter.then(|| f.buf(Buf::ZBinCovers.name(), u64::from(p.tiles_x * p.tiles_y) * 8));
        Self {
            r,
            f,
            group_keys: f.group(&vals, &keys, placeholder),
            group_lists: f.group(lists, &rects, covers.as_ref().unwrap_or(placeholder)),
            scatter,
            keys,
            keys_tmp,
            vals,
            vals_tmp,
            sorted,
        }
    }

    /// A thread a light.
    fn light_groups(&self) -> (u32, u32) {
        groups_2d(self.f.params.light_count.div_ceil(64), GROUPS_X)
    }
}

impl Plan for ZBinPlan<'_> {
    /// Nothing to count: every size is known up front.
    fn count(&self, _sized: bool) -> Vec<Step<'_>> {
        Vec::new()
    }

    fn total(&self) -> Result<u64, GpuError> {
        Ok(index_words(&self.f.params))
    }

    fn total_names(&self) -> (&'static str, &'static str) {
        ("zbin masks and sorted lights", "zbin index words")
    }

    fn size(&mut self, _total: u32) {}

    fn indices(&self) -> &wgpu::Buffer {
        match self.sorted {
            SortedIn::Input => &self.vals,
            SortedIn::Scratch => &self.vals_tmp,
        }
    }

    fn fill(&self, _sized: bool) -> Vec<Step<'_>> {
        let (f, q) = (self.f, self.r.pipelines);
        let p = &f.params;
        let z = q.zbin();
        let mut steps = vec![
            f.clear_ranges(),
            q.tile_depth.pass(p, &self.group_lists, Rows::Rects),
            Step::pass(
                "cull.zbin.keys",
                &z.keys,
                &self.group_keys,
                self.light_groups(),
                &[Buf::Lights],
                &[Buf::PairKeys, Buf::Indices],
            ),
            Step::Sort {
                keys: &self.keys,
                vals: &self.vals,
                keys_tmp: &self.keys_tmp,
                vals_tmp: &self.vals_tmp,
                pairs: p.light_count,
                bits: key_bits(p),
            },
            Step::pass(
                "cull.zbin.bins",
                &z.bins,
                &self.group_lists,
                self.light_groups(),
                &[Buf::Indices, Buf::Lights, Buf::Ranges],
                &[Buf::Ranges],
            ),
        ];
        let tiles = groups_2d(p.tiles_x * p.tiles_y, GROUPS_X);
        if self.scatter {
            steps.push(Step::pass(
                "cull.zbin.covers",
                &z.covers,
                &self.group_lists,
                tiles,
                &[Buf::Ranges, Buf::TileDepth],
                &[Buf::ZBinCovers, Buf::TileMasks],
            ));
            steps.push(Step::pass(
                "cull.zbin.scatter",
                &z.scatter,
                &self.group_lists,
                groups_2d(p.light_count.div_ceil(64 / SCATTER_LANES), GROUPS_X),
                &[
                    Buf::Indices,
                    Buf::ZBinCovers,
                    Buf::TileMasks,
                    Buf::TileDepth,
                    Buf::LightRects,
                    Buf::Lights,
                ],
                &[Buf::TileMasks],
            ));
        } else {
            steps.push(Step::pass(
                "cull.zbin.masks",
                &z.masks,
                &self.group_lists,
                tiles,
                &[
                    Buf::Indices,
                    Buf::Ranges,
                    Buf::TileDepth,
                    Buf::LightRects,
                    Buf::Lights,
                ],
                &[Buf::TileMasks],
            ));
        }
        steps
    }

    fn outputs(self) -> Outputs {
        Outputs {
            indices: self.indices().clone(),
            tile_masks: None,
            tile_lines: None,
        }
    }
}
