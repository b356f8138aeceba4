// The one pixel-to-list lookup every shading backend uses, whatever the strategy.
// Bindings of group 1 for list consumers: 0 = CullParams, 1 = bin_ranges, 2 = light_indices,
// 3 = the depth buffer, 4 = a per-pixel output, 5 = a pass-specific uniform (host:
// manylights_cull::Culler::lists_layout).
@group(1) @binding(1) var<storage, read> bin_ranges: array<vec2<u32>>;
@group(1) @binding(2) var<storage, read> light_indices: array<u32>;

// (offset, count) of the light list of a pixel.
fn light_list(pixel: vec2<u32>, z: f32) -> vec2<u32> {
    return bin_ranges[bin_of(pixel, z)];
}

@group(1) @binding(3) var depth_tex: texture_depth_2d;
