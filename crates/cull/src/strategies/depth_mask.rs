//! 2.5D culling (Harada, SIGGRAPH Asia 2012 technical brief; GPU Pro 4 section 5.6.1): tiled
//! gather in which a light is kept only where its 32-cell depth mask over the tile's
//! [dmin, dmax] meets the tile's geometry mask (`cull.depth_bounds` builds the geometry masks,
//! [`crate::blocks::tile_depth`]). It is gather with the `CULL_FLAG_DEPTH_MASK` flag in its
//! parameters ([`crate::Strategy::params`]): the same paths, pipelines and shaders (the flag
//! decides `depth_keeps` in `shaders/cull/common/geometry.wgsl`), so this module has no
//! pipelines of its own; its passes are named `cull.depth_mask.*`. The oracle is
//! [`crate::cpu::gather`] with the same flag.

use crate::culler::{RunInputs, Timing};
use crate::layout::{CULL_FLAG_DEPTH_MASK, GpuCullParams};
use crate::{CullError, CullOutput};

/// Runs 2.5D culling: gather's run with the depth-mask flag.
pub(crate) fn run(
    r: &RunInputs<'_>,
    params: GpuCullParams,
    t: Timing<'_>,
) -> Result<CullOutput, CullError> {
    debug_assert!(params.flags & CULL_FLAG_DEPTH_MASK != 0);
    super::tiled_gather::run(r, params, t)
}
