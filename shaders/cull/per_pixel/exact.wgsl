// cull.exact: the exact oracle (exact_point.wgsl) at every covered sample of each pixel.
@group(1) @binding(4) var<storage, read_write> counts: array<vec4<u32>>;

// One sample of a pixel: (evaluated, needed, found) at its surface point (depth z, at the
// sample's position in the pixel).
fn sample_counts(pixel: vec2<u32>, z: f32, at: vec2<f32>) -> vec3<u32> {
    let ndc = vec4<f32>((f32(pixel.x) + at.x) * frame.viewport.z * 2.0 - 1.0, 1.0 - (f32(pixel.y) + at.y) * frame.viewport.w * 2.0, z, 1.0);
    let q = exact.world_from_clip * ndc;
    return point_counts(pixel, z, q.xyz / q.w);
}

// Per pixel: (evaluated, needed, found, covered), summed over its covered samples with MSAA
// (covered: how many), each sample checked against the list its own depth selects.
@compute @workgroup_size(8, 8)
fn exact_counts(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let i = id.y * size.x + id.x;
    var total = vec4<u32>(0u);
    if id.x % exact.stride == 0u && id.y % exact.stride == 0u {
        for (var sample_k = 0u; sample_k < DEPTH_SAMPLES; sample_k++) {
            let z = textureLoad(depth_tex, id.xy, sample_k);
            if z < 1.0 {
                total += vec4<u32>(sample_counts(id.xy, z, sample_position(sample_k)), 1u);
            }
        }
    }
    counts[i] = total;
}
