//! Building blocks that strategies compose: each owns its pipelines, the sizes of its buffers
//! and dispatches, and the steps it adds to a plan. The scan ([`crate::scan`]) and the radix
//! sort ([`crate::radix_sort`]) are building blocks too, with shaders of their own.
//!
//! - [`tile_depth`]: `cull.depth_bounds`, each tile's depth bounds and 2.5D geometry mask
//!   (gather, 2.5D, tiled scatter);
//! - [`tile_masks`]: a bit per (tile, light) set by a strategy's count pass and expanded into
//!   lists by one fill (gather's and 2.5D's stored masks, tiled scatter's masks);
//! - [`tile_lines`]: gather's and 2.5D's lines path, a bit per (column or row of tiles or depth
//!   bin, light), ANDed per tile by the list passes;
//! - [`lists`]: the capacity cap and `cull.finalize`, which every strategy's lists end with;
//! - [`occlusion`]: `cull.occlusion`, culling by visibility after any strategy's lists of a
//!   list a bin (`CullSettings::occlusion`).

pub mod lists;
pub mod occlusion;
pub mod tile_depth;
pub mod tile_lines;
pub mod tile_masks;
