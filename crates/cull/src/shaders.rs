//! The culling crate's shaders, laid out like its Rust modules: `shaders/cull/common/` holds what
//! several strategies share (the culling geometry, the lists, the lookup, and the building blocks'
//! passes: tile depth, tile lines, tile masks), `shaders/cull/<strategy>/` what one strategy
//! owns, and `shaders/cull/per_pixel/` the per-pixel list consumers (`crate::per_pixel`).
//!
//! A shader is a list of files after the generated prelude of [`CULL_CONSTS`]; a strategy whose
//! entry points call a building block's functions composes that block's file.

use manylights_gpu::shader_file;
use manylights_gpu::shaders::{BVH, FRAME, LIGHT, SCENE, ShaderDef, ShaderFile, VERTEX};

use crate::layout::CULL_CONSTS;

/// Shared culling geometry and parameters (the WGSL twin of [`crate::geometry`]).
pub const GEOMETRY: ShaderFile = shader_file!("cull/common/geometry.wgsl");
/// List buffers of the culling passes, the capacity cap and `cull.finalize`
/// ([`crate::blocks::lists`]).
pub const LISTS: ShaderFile = shader_file!("cull/common/lists.wgsl");
/// The pixel-to-list lookup of every list consumer.
pub const LOOKUP: ShaderFile = shader_file!("cull/common/lookup.wgsl");
/// The depth [`LOOKUP`] looks lists up at: the depth buffer, one sample a pixel.
pub const LOOKUP_DEPTH: ShaderFile = shader_file!("cull/common/lookup_depth.wgsl");
/// [`LOOKUP_DEPTH`]'s place over a multisampled depth buffer ([`MSAA_SWAPS`]).
pub const LOOKUP_DEPTH_MSAA: ShaderFile = shader_file!("cull/common/lookup_depth_msaa.wgsl");
/// [`LOOKUP_DEPTH`]'s place over a float depth a compute pass wrote.
pub const LOOKUP_DEPTH_FLOAT: ShaderFile = shader_file!("cull/common/lookup_depth_float.wgsl");
/// The files that take another's place where a list consumer reads a float depth.
pub const LOOKUP_FLOAT_SWAPS: &[(ShaderFile, ShaderFile)] = &[(LOOKUP_DEPTH, LOOKUP_DEPTH_FLOAT)];
/// The depth culling reads (`depth_span`, binding 1): the depth buffer, one sample a pixel.
pub const DEPTH_INPUT: ShaderFile = shader_file!("cull/common/depth_input.wgsl");
/// [`DEPTH_INPUT`]'s place over a multisampled depth buffer ([`MSAA_SWAPS`]).
pub const DEPTH_INPUT_MSAA: ShaderFile = shader_file!("cull/common/depth_input_msaa.wgsl");
/// [`DEPTH_INPUT`]'s place where culling reads lookup bounds (`Culler::with_bounds`).
pub const DEPTH_INPUT_BOUNDS: ShaderFile = shader_file!("cull/common/depth_input_bounds.wgsl");
/// The files that take another's place where culling reads lookup bounds (`Culler::with_bounds`;
/// the shader tests validate every culling shader so built).
pub const BOUNDS_SWAPS: &[(ShaderFile, ShaderFile)] = &[(DEPTH_INPUT, DEPTH_INPUT_BOUNDS)];
/// [`DEPTH_INPUT`]'s place where culling reads a depth a compute pass wrote
/// (a culler's pipelines over an `R32Float` texture, one sample a pixel).
pub const DEPTH_INPUT_FLOAT: ShaderFile = shader_file!("cull/common/depth_input_float.wgsl");
/// The files that take another's place where culling reads a float depth
/// (validated as [`BOUNDS_SWAPS`]' are).
pub const FLOAT_SWAPS: &[(ShaderFile, ShaderFile)] = &[(DEPTH_INPUT, DEPTH_INPUT_FLOAT)];
/// The files that take others' places over a multisampled depth buffer (MSAA): each declares
/// `DEPTH_SAMPLES` an `override` constant, whose value a pipeline takes from
/// [`sample_constants`].
pub const MSAA_SWAPS: &[(ShaderFile, ShaderFile)] = &[
    (DEPTH_INPUT, DEPTH_INPUT_MSAA),
    (LOOKUP_DEPTH, LOOKUP_DEPTH_MSAA),
];

/// The files a shader over a depth buffer of `samples` samples a pixel takes in others' places:
/// [`MSAA_SWAPS`] with more than one, none with one.
pub fn sample_swaps(samples: u32) -> &'static [(ShaderFile, ShaderFile)] {
    if samples > 1 { MSAA_SWAPS } else { &[] }
}

/// The values of the override constants of a shader composed with [`sample_swaps`]`(samples)`:
/// `DEPTH_SAMPLES` with more than one sample, none with one (the single-sample files declare
/// it a `const`, and a pipeline given a constant its module lacks fails).
pub fn sample_constants(samples: u32) -> Vec<(&'static str, f64)> {
    if samples > 1 {
        vec![("DEPTH_SAMPLES", f64::from(samples))]
    } else {
        Vec::new()
    }
}

/// Whether `def` reads the depth buffer (composes [`DEPTH_INPUT`] or [`LOOKUP_DEPTH`]), so that
/// it has a variant over a multisampled one.
pub fn reads_depth(def: &ShaderDef) -> bool {
    def.has_file(DEPTH_INPUT) || def.has_file(LOOKUP_DEPTH)
}

/// [`ShaderDef::create_swapped`] over a depth buffer of `samples` samples a pixel, with `swaps`
/// besides.
///
/// # Panics
/// For `samples` > 1 where `def` composes neither [`DEPTH_INPUT`] nor [`LOOKUP_DEPTH`]: it
/// could not read a multisampled depth buffer.
pub fn create_over_samples(
    d: &wgpu::Device,
    def: &ShaderDef,
    samples: u32,
    swaps: &[(ShaderFile, ShaderFile)],
) -> wgpu::ShaderModule {
    assert!(
        samples == 1 || reads_depth(def),
        "shader {} reads no depth it could read multisampled",
        def.name
    );
    let all: Vec<_> = swaps.iter().chain(sample_swaps(samples)).copied().collect();
    def.create_swapped(d, &all)
}
/// Tile masks and their fill ([`crate::blocks::tile_masks`]; composed into gather's module,
/// which holds the workgroup scan the fill uses; tiled scatter's count pass that sets them is in
/// its own module).
pub const TILE_MASKS: ShaderFile = shader_file!("cull/common/tile_masks.wgsl");
/// The tiles' depth data (`cull.depth_bounds`, and the lines path's list passes;
/// [`crate::blocks::tile_depth`]).
pub const TILE_DEPTH: ShaderFile = shader_file!("cull/common/tile_depth.wgsl");
/// The lines path's list passes ([`crate::blocks::tile_lines`]).
pub const TILE_LINES: ShaderFile = shader_file!("cull/common/tile_lines.wgsl");

/// `cull.depth_bounds` (with the lights' rectangles, or scatter's blocks), and `cull.tile_lines`
/// (the lines path's first pass).
pub const DEPTH_BOUNDS: ShaderDef = ShaderDef {
    name: "cull.depth_bounds",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        GEOMETRY,
        DEPTH_INPUT,
        shader_file!("cull/common/depth_bounds.wgsl"),
        TILE_DEPTH,
    ],
};
/// `cull.tiled_gather` (also `cull.depth_mask`, with its flag), `cull.finalize`, `cull.cap`, the
/// tile masks' fill (also tiled scatter's) and the lines path's list passes, with the portable
/// workgroup scan.
pub const TILED_GATHER: ShaderDef = ShaderDef {
    name: "cull.tiled_gather",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        GEOMETRY,
        DEPTH_INPUT,
        LISTS,
        shader_file!("cull/tiled_gather/tiled_gather.wgsl"),
        TILE_MASKS,
        TILE_LINES,
        TILE_DEPTH,
        shader_file!("cull/tiled_gather/gather_scan.wgsl"),
    ],
};
/// [`TILED_GATHER`] with its scans in subgroup operations (built only where the device has
/// them).
pub const TILED_GATHER_SUBGROUP: ShaderDef = ShaderDef {
    name: "cull.tiled_gather.subgroup",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        GEOMETRY,
        DEPTH_INPUT,
        LISTS,
        shader_file!("cull/tiled_gather/tiled_gather.wgsl"),
        TILE_MASKS,
        TILE_LINES,
        TILE_DEPTH,
        shader_file!("cull/tiled_gather/gather_scan_subgroup.wgsl"),
    ],
};
/// `cull.tiled_scatter`: its pairs, and with tile masks its count pass.
pub const TILED_SCATTER: ShaderDef = ShaderDef {
    name: "cull.tiled_scatter",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        GEOMETRY,
        LISTS,
        shader_file!("cull/tiled_scatter/tiled_scatter.wgsl"),
    ],
};
/// `cull.clustered`, `cull.clustered.order` and `cull.occupancy`.
pub const CLUSTERED: ShaderDef = ShaderDef {
    name: "cull.clustered",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        GEOMETRY,
        DEPTH_INPUT,
        LISTS,
        shader_file!("cull/clustered/clustered.wgsl"),
        shader_file!("cull/clustered/order.wgsl"),
        shader_file!("cull/clustered/order_rank.wgsl"),
        shader_file!("cull/clustered/cluster_tiles.wgsl"),
    ],
};
/// `cull.zbin`: its keys, bins, masks and covers (the scatter path's first pass).
pub const ZBIN: ShaderDef = ShaderDef {
    name: "cull.zbin",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        GEOMETRY,
        shader_file!("cull/zbin/zbin.wgsl"),
    ],
};
/// `cull.zbin.scatter`: z-binning's masks a light at a time (its scatter path; a module of
/// its own, with the masks as atomics).
pub const ZBIN_SCATTER: ShaderDef = ShaderDef {
    name: "cull.zbin.scatter",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        GEOMETRY,
        shader_file!("cull/zbin/zbin_scatter.wgsl"),
    ],
};
/// `cull.lights_per_pixel`: the shared lookup, per pixel.
pub const LIGHTS_PER_PIXEL: ShaderDef = ShaderDef {
    name: "cull.lights_per_pixel",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        GEOMETRY,
        LOOKUP,
        LOOKUP_DEPTH,
        shader_file!("cull/per_pixel/lights_per_pixel.wgsl"),
    ],
};
/// `cull.exact`: the exact per-pixel oracle on the GPU.
pub const EXACT: ShaderDef = ShaderDef {
    name: "cull.exact",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        GEOMETRY,
        LOOKUP,
        LOOKUP_DEPTH,
        BVH,
        EXACT_POINT,
        shader_file!("cull/per_pixel/exact.wgsl"),
    ],
};
/// The exact oracle at a surface point, shared by `cull.exact` and `cull.exact_transparent`.
const EXACT_POINT: ShaderFile = shader_file!("cull/per_pixel/exact_point.wgsl");
/// `cull.exact_transparent`: the exact oracle at every visible transparent fragment (a raster
/// pass over the transparent geometry).
pub const EXACT_TRANSPARENT: ShaderDef = ShaderDef {
    name: "cull.exact_transparent",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        VERTEX,
        GEOMETRY,
        LOOKUP,
        LOOKUP_DEPTH,
        BVH,
        EXACT_POINT,
        shader_file!("cull/per_pixel/exact_transparent.wgsl"),
    ],
};

/// Every shader of this crate.
pub const SHADERS: &[ShaderDef] = &[
    DEPTH_BOUNDS,
    TILED_GATHER,
    TILED_GATHER_SUBGROUP,
    TILED_SCATTER,
    CLUSTERED,
    ZBIN,
    ZBIN_SCATTER,
    LIGHTS_PER_PIXEL,
    EXACT,
    EXACT_TRANSPARENT,
    crate::scan::SHADER,
    crate::scan::SUBGROUP_SHADER,
    crate::radix_sort::SHADER,
    crate::radix_sort::ONESWEEP_SHADER,
    crate::occlusion::OCCLUDER_TEST,
    crate::blocks::occlusion::SHADER,
];
