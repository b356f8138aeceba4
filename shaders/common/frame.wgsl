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
