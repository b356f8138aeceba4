// The depth a list consumer looks its pixel's list up at (lookup.wgsl), in lookup_depth.wgsl's
// place: an R32Float texture a compute pass wrote (the visibility buffer's compute rasteriser),
// one sample a pixel; deferred.wgsl reads it through vec4<f32>(...), which takes either.
const DEPTH_SAMPLES: u32 = 1u;

@group(1) @binding(3) var depth_tex: texture_2d<f32>;
