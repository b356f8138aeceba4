// The depth culling reads where it culls over lookup bounds (Culler::with_bounds), in place of
// depth_input.wgsl: prepass.depth_bounds (shaders/common/depth_bounds.wgsl) wrote each pixel's
// nearest lookup depth into x and its farthest into y (both 1.0 where nothing covers it), read
// as two samples: every depth between them is one a list is looked up at.
const DEPTH_SAMPLES: u32 = 2u;

@group(1) @binding(1) var depth_tex: texture_2d<f32>;

// A pixel's nearest and farthest lookup depth and how many of the two are covered; (1, 0, 0)
// where nothing covers it.
fn depth_span(p: vec2<u32>) -> DepthSpan {
    let b = textureLoad(depth_tex, p, 0).xy;
    var s = DepthSpan(1.0, 0.0, 0u);
    if b.x < 1.0 {
        s = DepthSpan(b.x, b.x, 1u);
    }
    if b.y < 1.0 {
        s = DepthSpan(min(s.near, b.y), max(s.far, b.y), s.covered + 1u);
    }
    return s;
}
