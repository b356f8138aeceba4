// prepass.depth_bounds's inputs at one sample a pixel (depth_bounds_inputs_msaa.wgsl takes this
// file's place with MSAA): the forward prepass's depth ranges, the depth, and the transparent
// surfaces' nearest and farthest depth.
const DEPTH_SAMPLES: u32 = 1u;

@group(0) @binding(0) var ranges: texture_2d<f32>;
@group(0) @binding(1) var depth: texture_depth_2d;
@group(0) @binding(2) var near: texture_depth_2d;
@group(0) @binding(3) var far: texture_depth_2d;
