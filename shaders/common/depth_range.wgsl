// prepass.depth with MSAA lookup bounds (manylights_gpu::lookup_bounds): besides the depth, each
// sample a fragment wins keeps that fragment's depth range over its pixel. With MSAA the forward
// passes shade a fragment once, at its centroid, and look its list up at that point's depth; the
// centroid lies on the fragment's plane within the pixel, also where another primitive hides
// the sample there, so its depth need not be any sample's. Rasterised depth is affine in screen
// space: over the pixel's square it stays within the sum of the plane's two screen derivatives
// of any point of the square (the fragment's own depth is interpolated at one), widened by 0.1 %
// and two ulps of 1.0 against rounding.
@fragment
fn fs_depth_range(in: VertexOut) -> @location(0) vec2<f32> {
    let dz = depth_slope(in.clip.z);
    return vec2<f32>(in.clip.z - dz, in.clip.z + dz);
}

// prepass.transparent_near and prepass.transparent_far (manylights_gpu::lookup_bounds): the
// transparent surfaces into two depth targets, the nearest (test Less) and the farthest (test
// Greater) of their depth ranges over each pixel (as fs_depth_range's), whether or not an opaque
// surface hides them (which only widens the bounds).
fn depth_slope(z: f32) -> f32 {
    return (abs(dpdxFine(z)) + abs(dpdyFine(z))) * 1.001 + 2.4e-7;
}

@fragment
fn fs_transparent_near(in: VertexOut) -> @builtin(frag_depth) f32 {
    return clamp(in.clip.z - depth_slope(in.clip.z), 0.0, 1.0);
}

@fragment
fn fs_transparent_far(in: VertexOut) -> @builtin(frag_depth) f32 {
    return clamp(in.clip.z + depth_slope(in.clip.z), 0.0, 1.0);
}
