// prepass.depth_bounds's inputs with MSAA (in depth_bounds_inputs.wgsl's place): each texture
// multisampled, DEPTH_SAMPLES samples a pixel (the pipeline's override constant).
override DEPTH_SAMPLES: u32 = 4u;

@group(0) @binding(0) var ranges: texture_multisampled_2d<f32>;
@group(0) @binding(1) var depth: texture_depth_multisampled_2d;
@group(0) @binding(2) var near: texture_depth_multisampled_2d;
@group(0) @binding(3) var far: texture_depth_multisampled_2d;
