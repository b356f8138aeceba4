// The depth a list consumer looks its pixel's list up at (lookup.wgsl): the depth buffer
// (multisampled where the consumer's DEPTH_SAMPLES is more than one). lookup_depth_float.wgsl takes
// this file's place over the compute rasteriser's R32Float depth.
@group(1) @binding(3) var depth_tex: texture_depth_2d;
