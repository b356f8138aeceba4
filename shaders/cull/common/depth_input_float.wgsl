// The depth culling reads where a compute pass wrote it (Culler::with_float_depth: the visibility
// buffer's compute rasteriser, shaders/render/visibility_resolve.wgsl), in place of
// depth_input.wgsl: an R32Float texture of NDC depths, one sample a pixel, 1.0 where nothing
// covers it (a compute pass cannot write a depth texture).
const DEPTH_SAMPLES: u32 = 1u;

@group(1) @binding(1) var depth_tex: texture_2d<f32>;

// A pixel's depth as its nearest and farthest, one sample covered; (1, 0, 0) where nothing
// covers it.
fn depth_span(p: vec2<u32>) -> DepthSpan {
    let z = textureLoad(depth_tex, p, 0).x;
    if z < 1.0 {
        return DepthSpan(z, z, 1u);
    }
    return DepthSpan(1.0, 0.0, 0u);
}
