// cull.exact_transparent: the exact oracle (exact_point.wgsl) at every transparent fragment
// the frame shades, after cull.exact has written the opaque samples' counts: the transparent
// geometry drawn over the depth buffer (read only), each fragment nearer than the opaque surface
// at its pixel (with MSAA: than the farthest of its samples) adding its (evaluated, needed,
// found) and one point to its pixel's counts. It is looked up and shaded where the forward
// passes look it up: at its interpolated point, at the depth buffer's own depth with one
// sample a pixel, at its centroid's with MSAA.
@group(1) @binding(4) var<storage, read_write> point_counts_out: array<atomic<u32>>;

@fragment
fn fs_exact_transparent(in: VertexOut) {
    let pixel = vec2<u32>(in.clip.xy);
    if pixel.x % exact.stride != 0u || pixel.y % exact.stride != 0u {
        return;
    }
    var opaque = 0.0;
    for (var sample_k = 0u; sample_k < DEPTH_SAMPLES; sample_k++) {
        opaque = max(opaque, textureLoad(depth_tex, pixel, sample_k));
    }
    if in.clip.z >= opaque {
        return;
    }
    var z = in.clip.z;
    if DEPTH_SAMPLES > 1u {
        let c = frame.clip_from_world * vec4<f32>(in.world, 1.0);
        z = c.z / c.w;
    }
    let r = point_counts(pixel, z, in.world);
    let i = (pixel.y * u32(frame.viewport.x) + pixel.x) * 4u;
    atomicAdd(&point_counts_out[i], r.x);
    atomicAdd(&point_counts_out[i + 1u], r.y);
    atomicAdd(&point_counts_out[i + 2u], r.z);
    atomicAdd(&point_counts_out[i + 3u], 1u);
}
