// The depth culling reads over a multisampled depth buffer (MSAA), in depth_input.wgsl's place:
// DEPTH_SAMPLES samples a pixel, the pipeline's override constant.
override DEPTH_SAMPLES: u32;

@group(1) @binding(1) var depth_tex: texture_depth_multisampled_2d;

// A pixel's nearest and farthest covered sample (NDC) and how many are covered; (1, 0, 0) where
// none is (the depth buffer's clear value is 1.0).
fn depth_span(p: vec2<u32>) -> DepthSpan {
    var s = DepthSpan(1.0, 0.0, 0u);
    for (var k = 0u; k < DEPTH_SAMPLES; k++) {
        let z = textureLoad(depth_tex, p, k);
        if z < 1.0 {
            s = DepthSpan(min(s.near, z), max(s.far, z), s.covered + 1u);
        }
    }
    return s;
}
