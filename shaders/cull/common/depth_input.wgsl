// The depth culling reads (binding 1 of the culling group), through depth_at: the depth buffer,
// DEPTH_SAMPLES samples a pixel (a texture_depth_multisampled_2d where more than one:
// manylights_gpu::shaders::with_samples). Where culling reads lookup bounds instead
// (Culler::with_bounds), depth_input_bounds.wgsl takes this file's place.
@group(1) @binding(1) var depth_tex: texture_depth_2d;

// Sample k's depth of pixel p: 1.0 (the clear value) where nothing covers it.
fn depth_at(p: vec2<u32>, k: u32) -> f32 {
    return textureLoad(depth_tex, p, k);
}
