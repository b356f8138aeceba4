// The depth a list consumer looks its pixel's list up at over a multisampled depth buffer
// (MSAA), in lookup_depth.wgsl's place: DEPTH_SAMPLES samples a pixel, the pipeline's override
// constant.
override DEPTH_SAMPLES: u32;

@group(1) @binding(3) var depth_tex: texture_depth_multisampled_2d;

// Where sample k of a pixel lies within it (the exact oracle's samples, deferred lighting's at
// edges): the standard sample positions (frame.wgsl).
fn sample_position(k: u32) -> vec2<f32> {
    return standard_sample_position(DEPTH_SAMPLES, k);
}
