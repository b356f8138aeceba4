//! The culling strategies, a module each. A strategy owns its pipelines (built once from its
//! shader, `shaders/cull/<strategy>/`: gather's and 2.5D's in [`crate::Culler::new`], the others'
//! at their first run, `Culler::scatter`, `clustered`, `zbin`), decides its path for a
//! run (its checks against the device's limits, its buffers), and declares the steps of the run
//! as a `Plan`; `frame::execute` records the plan, once or back to back, and
//! [`crate::Culler::run`] picks the strategy's `run`. What several strategies share are the
//! building blocks of [`crate::blocks`] (tile depth, tile lines, tile masks, list finalisation),
//! [`crate::scan`] and [`crate::radix_sort`].
//!
//! Adding a strategy: docs/ARCHITECTURE.md, "Adding a strategy".

use manylights_gpu::GpuError;

use crate::frame::Outputs;
use crate::record::Step;

pub mod clustered;
pub mod depth_mask;
pub mod tiled_gather;
pub mod tiled_scatter;
pub mod zbin;

/// The steps of one culling run, in two phases: the count phase, up to an exact list total,
/// and the fill phase, whose buffers are sized from that total.
pub(crate) trait Plan {
    /// The count phase. `sized`: the lists are already sized (back-to-back runs), so only
    /// what the fill needs (a pass that only sizes the lists is left out).
    fn count(&self, sized: bool) -> Vec<Step<'_>>;
    /// The exact total of entries after the count phase, read back.
    fn total(&self) -> Result<u64, GpuError>;
    /// What the total counts, for the error when it is over a limit: (its bytes, its entries).
    fn total_names(&self) -> (&'static str, &'static str) {
        ("light list bytes", "light list entries")
    }
    /// Creates the fill's buffers (the lists' indices, at least) for `total` entries.
    fn size(&mut self, total: u32);
    /// The lists' indices (after `size`).
    fn indices(&self) -> &wgpu::Buffer;
    /// The fill phase (after [`Plan::size`]).
    fn fill(&self, sized: bool) -> Vec<Step<'_>>;
    /// The buffers the output keeps.
    fn outputs(self) -> Outputs;
}
