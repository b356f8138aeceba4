// cull.lights_per_pixel: the length of the list each pixel reads through lookup.wgsl (0 for
// background), one thread per pixel. Feeds the lights-per-pixel heatmaps and checks the shared
// lookup against the CPU's.
@group(1) @binding(4) var<storage, read_write> per_pixel: array<u32>;

@compute @workgroup_size(8, 8)
fn lights_per_pixel(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let z = textureLoad(depth_tex, id.xy, 0);
    var n = 0u;
    if z < 1.0 {
        n = list_length(id.xy, z);
    }
    per_pixel[id.y * size.x + id.x] = n;
}
