// The depth a list consumer looks its pixel's list up at over a multisampled depth buffer
// (MSAA), in lookup_depth.wgsl's place: DEPTH_SAMPLES samples a pixel, the pipeline's override
// constant.
override DEPTH_SAMPLES: u32;

@group(1) @binding(3) var depth_tex: texture_depth_multisampled_2d;

// Where sample k of a pixel lies within it (the exact oracle's samples, deferred lighting's at
// edges): the standard sample positions of Vulkan (standardSampleLocations) and Direct3D for 2,
// 4 and 8 samples.
fn sample_position(k: u32) -> vec2<f32> {
    if DEPTH_SAMPLES == 2u {
        var p2 = array<vec2<f32>, 2>(vec2<f32>(0.75, 0.75), vec2<f32>(0.25, 0.25));
        return p2[k];
    }
    if DEPTH_SAMPLES == 4u {
        var p4 = array<vec2<f32>, 4>(vec2<f32>(0.375, 0.125), vec2<f32>(0.875, 0.375), vec2<f32>(0.125, 0.625), vec2<f32>(0.625, 0.875));
        return p4[k];
    }
    if DEPTH_SAMPLES == 8u {
        var p8 = array<vec2<f32>, 8>(
            vec2<f32>(0.5625, 0.3125), vec2<f32>(0.4375, 0.6875), vec2<f32>(0.8125, 0.5625), vec2<f32>(0.3125, 0.1875),
            vec2<f32>(0.1875, 0.8125), vec2<f32>(0.0625, 0.4375), vec2<f32>(0.6875, 0.9375), vec2<f32>(0.9375, 0.0625));
        return p8[k];
    }
    return vec2<f32>(0.5, 0.5);
}
