//! The shaders of the backends' passes (composed from `shaders/render/` and the shared files)
//! and the text edits that specialise them at run time.

use manylights_cull::layout::CULL_CONSTS;
use manylights_cull::shaders::{GEOMETRY, LOOKUP};
use manylights_gpu::shader_file;
use manylights_gpu::shaders::{BRDF, FRAME, LIGHT, SCENE, SHADING, ShaderDef, ShaderFile, VERTEX};

use crate::kinds::HdrFormat;

/// The loop over a pixel's list, with its per-pixel reject (forward and deferred).
pub const LIST_SHADING: ShaderFile = shader_file!("render/list_shading.wgsl");
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
        BRDF,
        SHADING,
        VERTEX,
        GEOMETRY,
        LOOKUP,
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
        BRDF,
        SHADING,
        VERTEX,
        shader_file!("render/gbuffer.wgsl"),
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
        BRDF,
        SHADING,
        GEOMETRY,
        LOOKUP,
        LIST_SHADING,
        SURFACE,
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
        BRDF,
        SHADING,
        GEOMETRY,
        LOOKUP,
        LIST_SHADING,
        SURFACE,
        shader_file!("render/deferred_msaa.wgsl"),
    ],
};

/// The deferred lighting passes' image (`out_color`, declared `rgba32float`) in format `hdr`.
pub(crate) fn hdr_storage(source: String, hdr: HdrFormat) -> String {
    redeclare(
        source,
        "var out_color: texture_storage_2d<rgba32float, write>;",
        &format!("var out_color: texture_storage_2d<{}, write>;", hdr.wgsl()),
    )
}

/// The deferred lighting passes' depth (`depth_tex`, declared a depth texture in lookup.wgsl) as
/// an `R32Float` texture: what the compute rasteriser writes (deferred.wgsl reads it through
/// `vec4<f32>(...)`, which takes either).
pub(crate) fn float_depth(source: String) -> String {
    redeclare(
        source,
        "@group(1) @binding(3) var depth_tex: texture_depth_2d;",
        "@group(1) @binding(3) var depth_tex: texture_2d<f32>;",
    )
}

/// `source` with its declaration `declared` (which it must hold) replaced by `with`.
fn redeclare(source: String, declared: &str, with: &str) -> String {
    assert!(source.contains(declared), "the shader declares {declared}");
    source.replace(declared, with)
}
