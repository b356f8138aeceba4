// Per-frame camera and viewport, bound at group 0, binding 0 in every pass.
// Host mirror: manylights_gpu::layout::GpuFrame (size and offsets checked by a naga test).
// Conventions (docs/ARCHITECTURE.md): right-handed world, view space looks down -Z, clip depth in
// [0, 1] with near at 0 (no reversed-Z), pixel (0, 0) at the top-left.
struct Frame {
    clip_from_world: mat4x4<f32>,
    view_from_world: mat4x4<f32>,
    clip_from_view: mat4x4<f32>,
    // Inverse of view_from_world (computed on the host).
    world_from_view: mat4x4<f32>,
    // Perspective: (eye position, 1). Orthographic: (unit direction towards the viewer, 0).
    eye: vec4<f32>,
    // (width, height, 1 / width, 1 / height) in pixels.
    viewport: vec4<f32>,
    light_count: u32,
    // FRAME_FLAG_* bits.
    flags: u32,
    // The lighting grid hierarchy's ramps (light_band; LightModel::band_ramp) and
    // 1 / (band_ramp - 1).
    band_ramp: f32,
    band_slope: f32,
    // The frame number stochastic shadow rays draw their lights by (shadow_draws_begin).
    shadow_frame: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;

// Unit vector from surface point `p` towards the viewer, for both projections.
fn view_dir(p: vec3<f32>) -> vec3<f32> {
    return normalize(frame.eye.xyz - p * frame.eye.w);
}

// The view-space point on the ray through NDC (x, y) at view-space z: with rows of
// clip_from_view, x_c = P00 x + P02 z + P03 and w_c = P32 z + P33, so x = (ndc_x w_c - P02 z -
// P03) / P00 (and y alike). Exact for perspective and orthographic cameras. (Also the deferred
// lighting pass's position rebuild.)
fn view_point(ndc: vec2<f32>, z: f32) -> vec3<f32> {
    let m = frame.clip_from_view;
    let w = m[2][3] * z + m[3][3];
    return vec3<f32>((ndc.x * w - m[2][0] * z - m[3][0]) / m[0][0], (ndc.y * w - m[2][1] * z - m[3][1]) / m[1][1], z);
}

// NDC of a point of the screen in pixels (x right, y down).
fn screen_ndc(q: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(q.x * frame.viewport.z * 2.0 - 1.0, 1.0 - q.y * frame.viewport.w * 2.0);
}

// Where sample k of a pixel of `samples` samples lies within it: the standard sample positions
// of Vulkan (standardSampleLocations) and Direct3D for 2, 4 and 8 samples, the centre for one
// (what the H200 and lavapipe use: examples/sample_positions.rs).
fn standard_sample_position(samples: u32, k: u32) -> vec2<f32> {
    if samples == 2u {
        var p2 = array<vec2<f32>, 2>(vec2<f32>(0.75, 0.75), vec2<f32>(0.25, 0.25));
        return p2[k];
    }
    if samples == 4u {
        var p4 = array<vec2<f32>, 4>(vec2<f32>(0.375, 0.125), vec2<f32>(0.875, 0.375), vec2<f32>(0.125, 0.625), vec2<f32>(0.625, 0.875));
        return p4[k];
    }
    if samples == 8u {
        var p8 = array<vec2<f32>, 8>(
            vec2<f32>(0.5625, 0.3125), vec2<f32>(0.4375, 0.6875), vec2<f32>(0.8125, 0.5625), vec2<f32>(0.3125, 0.1875),
            vec2<f32>(0.1875, 0.8125), vec2<f32>(0.0625, 0.4375), vec2<f32>(0.6875, 0.9375), vec2<f32>(0.9375, 0.0625));
        return p8[k];
    }
    return vec2<f32>(0.5, 0.5);
}
