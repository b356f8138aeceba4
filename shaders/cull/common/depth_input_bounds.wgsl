// The depth culling reads where it culls over lookup bounds (Culler::with_bounds), in place of
// depth_input.wgsl: prepass.depth_bounds (shaders/common/depth_bounds.wgsl) wrote each pixel's
// nearest lookup depth into x and its farthest into y (both 1.0 where nothing covers it), read
// as two samples (DEPTH_SAMPLES is 2): every depth between them is one a list is looked up at.
@group(1) @binding(1) var depth_tex: texture_2d<f32>;

// "Sample" k's depth of pixel p: the nearest for k = 0, the farthest otherwise.
fn depth_at(p: vec2<u32>, k: u32) -> f32 {
    let b = textureLoad(depth_tex, p, 0).xy;
    return select(b.y, b.x, k == 0u);
}
