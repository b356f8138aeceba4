// The depth culling reads where a compute pass wrote it (Culler::with_float_depth: the visibility
// buffer's compute rasteriser, shaders/render/visibility_resolve.wgsl), in place of
// depth_input.wgsl: an R32Float texture of NDC depths, one sample a pixel, 1.0 where nothing
// covers it (a compute pass cannot write a depth texture).
@group(1) @binding(1) var depth_tex: texture_2d<f32>;

// Pixel p's depth (one sample: k is always 0).
fn depth_at(p: vec2<u32>, k: u32) -> f32 {
    return textureLoad(depth_tex, p, 0).x;
}
