//! The end of every strategy's lists (`shaders/cull/common/lists.wgsl`): lists are sized
//! exactly (a count pass counts each bin's lights, [`crate::scan`] turns the counts into
//! offsets, the host sizes `light_indices` from the total, a fill pass writes each light at its
//! bin's offset plus a cursor), so nothing is dropped unless a run asks for a capacity:
//! `cull.cap` then caps each count and counts the dropped lights (`cull_stats[0]`), and
//! `cull.finalize` writes each bin's `(offset, count)`.

use crate::Kernel;
use crate::frame::Frame;
use crate::layout::GROUPS_X;
use crate::program::Program;
use crate::record::{Buf, Step};
use crate::scan::groups_2d;

/// The pipelines of `cull.cap` and `cull.finalize` (in gather's program, which composes
/// `lists.wgsl`).
pub(crate) struct Lists {
    finalize: Kernel,
    cap: Kernel,
}

impl Lists {
    /// Its pipelines from gather's program.
    pub fn new(d: &wgpu::Device, program: &Program) -> Self {
        let [finalize, cap] = program.pipelines(d, ["finalize", "cap_counts"]);
        Self { finalize, cap }
    }

    /// After a count pass of `n` count entries: `cull.cap` where the run has a capacity, then
    /// the scan of the counts into offsets.
    pub fn count_tail<'a>(
        &'a self,
        f: &'a Frame<'_>,
        group: &'a wgpu::BindGroup,
        n: u32,
    ) -> Vec<Step<'a>> {
        let mut steps = Vec::with_capacity(2);
        if f.params.capacity != 0 {
            steps.push(Step::pass(
                "cull.cap",
                &self.cap,
                group,
                bin_groups(f),
                &[Buf::Counts],
                &[Buf::Counts, Buf::Stats],
            ));
        }
        steps.push(f.scan(n));
        steps
    }

    /// `cull.finalize`: each bin's `(offset, count)` from the offsets and counts.
    pub fn finalize<'a>(&'a self, f: &Frame<'_>, group: &'a wgpu::BindGroup) -> Step<'a> {
        Step::pass(
            "cull.finalize",
            &self.finalize,
            group,
            bin_groups(f),
            &[Buf::Offsets, Buf::Counts],
            &[Buf::Ranges],
        )
    }
}

/// Workgroups of a pass of a thread a bin.
pub(crate) fn bin_groups(f: &Frame<'_>) -> (u32, u32) {
    groups_2d(f.params.bins.div_ceil(64), GROUPS_X)
}
