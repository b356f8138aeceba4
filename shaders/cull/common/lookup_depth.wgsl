// The depth a list consumer looks its pixel's list up at (lookup.wgsl): the depth buffer, one
// sample a pixel. lookup_depth_msaa.wgsl takes this file's place over a multisampled depth
// buffer, lookup_depth_float.wgsl over the compute rasteriser's R32Float depth (MSAA_SWAPS and
// LOOKUP_FLOAT_SWAPS in crates/cull/src/shaders.rs).
const DEPTH_SAMPLES: u32 = 1u;

@group(1) @binding(3) var depth_tex: texture_depth_2d;

// Where sample k of a pixel lies within it (the exact oracle's samples): the centre, the one
// sample's (lookup_depth_msaa.wgsl has the multisampled positions).
fn sample_position(k: u32) -> vec2<f32> {
    return vec2<f32>(0.5, 0.5);
}
