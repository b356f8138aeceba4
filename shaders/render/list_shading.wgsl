// Shading a pixel's list (shade.forward and shade.deferred): the one loop both backends run over
// the lights their culling kept, after lookup.wgsl's light_list.
//
// The per-pixel reject: each light's position and radius are read first (its first 16 bytes),
// and a light at d >= r is skipped before the rest of its 64 bytes are loaded. It adds exactly
// nothing there (light_window is zero for d >= r, and d is computed as shade_light computes it),
// so the image is the same with and without it; on an H100 it took 9-36% off culling and
// deferred lighting together (docs/STRATEGIES.md, "What shading pays for a list"). Lists do
// not change: lights_per_pixel_mean still counts every light a list hands a pixel. The
// infinite-range falloff (FRAME_FLAG_INFINITE_RANGE) skips nothing.
fn shade_list(list: vec2<u32>, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    let infinite = (frame.flags & FRAME_FLAG_INFINITE_RANGE) != 0u;
    var c = vec3<f32>(0.0);
    for (var k = 0u; k < list.y; k++) {
        let i = light_indices[list.x + k];
        if !infinite && length(lights[i].position - p) >= lights[i].radius {
            continue;
        }
        c += shade_light(lights[i], p, n, v, m);
    }
    return c;
}
