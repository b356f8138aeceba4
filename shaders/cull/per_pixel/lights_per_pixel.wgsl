// cull.lights_per_pixel: the length of the list each pixel reads through lookup.wgsl (0 for
// background), one thread per pixel; with MSAA the longest of its covered samples' lists. Feeds the lights-per-pixel heatmaps and checks the shared
// lookup against the CPU's.
@group(1) @binding(4) var<storage, read_write> per_pixel: array<u32>;

@compute @workgroup_size(8, 8)
fn lights_per_pixel(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    var n = 0u;
    for (var sample_k = 0u; sample_k < DEPTH_SAMPLES; sample_k++) {
        let z = textureLoad(depth_tex, id.xy, sample_k);
        if z < 1.0 {
            n = max(n, list_length(id.xy, z));
        }
    }
    per_pixel[id.y * size.x + id.x] = n;
}

// cull.depth_samples: every sample's depth of each pixel (DEPTH_SAMPLES words a pixel, the f32
// bits), for the host: a multisampled depth buffer cannot be copied back.
@compute @workgroup_size(8, 8)
fn depth_samples(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    for (var sample_k = 0u; sample_k < DEPTH_SAMPLES; sample_k++) {
        per_pixel[(id.y * size.x + id.x) * DEPTH_SAMPLES + sample_k] = bitcast<u32>(textureLoad(depth_tex, id.xy, sample_k));
    }
}
