//! The shaders of the backends' passes (composed from `shaders/render/` and the shared files)
//! and the files that take others' places in their variants.

use manylights_cull::layout::CULL_CONSTS;
use manylights_cull::shaders::{GEOMETRY, LOOKUP, LOOKUP_DEPTH, LOOKUP_FLOAT_SWAPS};
use manylights_gpu::shader_file;
use manylights_gpu::shaders::{
    BRDF, BVH, FRAME, LIGHT, SCENE, SHADING, ShaderDef, ShaderFile, VERTEX,
};

use crate::kinds::HdrFormat;

/// The loop over a pixel's list, with its per-pixel reject (forward and deferred).
pub const LIST_SHADING: ShaderFile = shader_file!("render/list_shading.wgsl");
/// Deferred lighting's image, `rgba32float`.
pub const OUT_COLOR: ShaderFile = shader_file!("render/out_color.wgsl");
/// [`OUT_COLOR`]'s place for a 16-bit image.
pub const OUT_COLOR_F16: ShaderFile = shader_file!("render/out_color_f16.wgsl");
/// The surface deferred lighting shades, from a G-buffer or a visibility buffer.
pub const SURFACE: ShaderFile = shader_file!("render/surface.wgsl");
/// `shade.forward` and `shade.naive`.
pub const FORWARD: ShaderDef = ShaderDef {
    name: "shade.forward",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        BVH,
        BRDF,
        SHADING,
        VERTEX,
        GEOMETRY,
        LOOKUP,
        LOOKUP_DEPTH,
        LIST_SHADING,
        shader_file!("render/forward.wgsl"),
    ],
};
/// `shade.gbuffer`.
pub const GBUFFER: ShaderDef = ShaderDef {
    name: "shade.gbuffer",
    consts: &[],
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        BVH,
        BRDF,
        SHADING,
        VERTEX,
        shader_file!("render/gbuffer.wgsl"),
    ],
};
/// `shade.gbuffer` with MSAA over the triangles' ids (`fs_gbuffer_ids`; needs
/// `PRIMITIVE_INDEX`).
pub const GBUFFER_IDS: ShaderDef = ShaderDef {
    name: "shade.gbuffer_ids",
    consts: &[],
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        BVH,
        BRDF,
        SHADING,
        VERTEX,
        shader_file!("render/gbuffer.wgsl"),
        shader_file!("render/gbuffer_ids.wgsl"),
    ],
};
/// `shade.visibility`: the visibility buffer's raster pass (the shared vertex stage and a
/// fragment writing the triangle id).
pub const VISIBILITY: ShaderDef = ShaderDef {
    name: "shade.visibility",
    consts: &[],
    files: &[FRAME, VERTEX, shader_file!("render/visibility.wgsl")],
};

/// `shade.deferred`.
pub const DEFERRED: ShaderDef = ShaderDef {
    name: "shade.deferred",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        BVH,
        BRDF,
        SHADING,
        GEOMETRY,
        LOOKUP,
        LOOKUP_DEPTH,
        LIST_SHADING,
        SURFACE,
        OUT_COLOR,
        shader_file!("render/deferred.wgsl"),
        shader_file!("render/deferred_zbin.wgsl"),
    ],
};

/// `shade.deferred` over a multisampled G-buffer (MSAA): a pixel at once, or its samples apart
/// at edges.
pub const DEFERRED_MSAA: ShaderDef = ShaderDef {
    name: "shade.deferred",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        BVH,
        BRDF,
        SHADING,
        GEOMETRY,
        LOOKUP,
        LOOKUP_DEPTH,
        LIST_SHADING,
        SURFACE,
        OUT_COLOR,
        shader_file!("render/deferred_msaa.wgsl"),
    ],
};

/// The files deferred lighting takes in others' places: its image in format `hdr`, and where
/// `float_depth` its depth an `R32Float` texture (the compute rasteriser's, which deferred.wgsl
/// reads through `vec4<f32>(...)`).
pub fn deferred_swaps(hdr: HdrFormat, float_depth: bool) -> Vec<(ShaderFile, ShaderFile)> {
    let mut swaps = Vec::new();
    if hdr == HdrFormat::F16 {
        swaps.push((OUT_COLOR, OUT_COLOR_F16));
    }
    if float_depth {
        swaps.extend_from_slice(LOOKUP_FLOAT_SWAPS);
    }
    swaps
}
