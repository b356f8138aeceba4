// The depth culling reads (binding 1 of the culling group): the depth buffer, one sample a
// pixel. Its variants take this file's place (MSAA_SWAPS, BOUNDS_SWAPS and FLOAT_SWAPS in
// crates/cull/src/shaders.rs): depth_input_msaa.wgsl over a multisampled depth buffer,
// depth_input_bounds.wgsl over lookup bounds (Culler::with_bounds), depth_input_float.wgsl over
// a depth a compute pass wrote.
const DEPTH_SAMPLES: u32 = 1u;

@group(1) @binding(1) var depth_tex: texture_depth_2d;

// A pixel's nearest and farthest covered depth (NDC) and its covered samples; (1, 0, 0) where
// nothing covers it (the depth buffer's clear value is 1.0).
fn depth_span(p: vec2<u32>) -> DepthSpan {
    let z = textureLoad(depth_tex, p, 0);
    if z < 1.0 {
        return DepthSpan(z, z, 1u);
    }
    return DepthSpan(1.0, 0.0, 0u);
}
