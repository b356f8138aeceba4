// prepass.depth with MSAA lookup bounds (manylights_gpu::msaa_bounds): besides the depth, each
// sample a fragment wins keeps that fragment's depth range over its pixel. With MSAA the forward
// passes shade a fragment once, at its centroid, and look its list up at that point's depth; the
// centroid lies on the fragment's plane within the pixel, also where another primitive hides
// the sample there, so its depth need not be any sample's. Rasterised depth is affine in screen
// space: over the pixel's square it stays within the sum of the plane's two screen derivatives
// of any point of the square (the fragment's own depth is interpolated at one), widened by 0.1 %
// and two ulps of 1.0 against rounding.
@fragment
fn fs_depth_range(in: VertexOut) -> @location(0) vec2<f32> {
    let z = in.clip.z;
    let dz = (abs(dpdxFine(z)) + abs(dpdyFine(z))) * 1.001 + 2.4e-7;
    return vec2<f32>(z - dz, z + dz);
}
