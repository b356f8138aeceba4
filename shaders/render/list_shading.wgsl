// Shading a pixel's list (shade.forward and shade.deferred): the one loop both backends run over
// the lights their culling kept, after lookup.wgsl's lookup (shade_pixel_lights; either form of
// lists: a bin's list, or z-binning's tile bits within a depth bin's range).
//
// The per-pixel reject: each light's position and radius are read first (its first 16 bytes),
// and a light at d >= r is skipped before the rest of its 64 bytes are loaded. It adds exactly
// nothing there (light_window is zero for d >= r, and d is computed as shade_light computes it),
// so the image is the same with and without it; on an H100 it took 9-36% off culling and
// deferred lighting together (docs/STRATEGIES.md, "What shading pays for a list"). Lists do
// not change: lights_per_pixel_mean still counts every light a list hands a pixel. The
// infinite-range falloff (FRAME_FLAG_INFINITE_RANGE) skips nothing.
fn shade_listed(i: u32, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, m: Material, infinite: bool) -> vec3<f32> {
    if !infinite && length(lights[i].position - p) >= lights[i].radius {
        return vec3<f32>(0.0);
    }
    return shade_light(lights[i], p, n, v, m);
}

fn shade_list(list: vec2<u32>, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    let infinite = (frame.flags & FRAME_FLAG_INFINITE_RANGE) != 0u;
    var c = vec3<f32>(0.0);
    for (var k = 0u; k < list.y; k++) {
        c += shade_listed(light_indices[list.x + k], p, n, v, m, infinite);
    }
    return c;
}

// Z-binning's cell: its set bits in order, so lights are summed in depth order, the same order
// on every run.
fn shade_zbin(cell: ZBinCell, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    let infinite = (frame.flags & FRAME_FLAG_INFINITE_RANGE) != 0u;
    var c = vec3<f32>(0.0);
    if cell.first >= cell.end {
        return c;
    }
    for (var w = cell.first / 32u; w <= (cell.end - 1u) / 32u; w++) {
        var bits = zbin_bits(cell, w);
        while bits != 0u {
            let k = w * 32u + firstTrailingBit(bits);
            bits &= bits - 1u;
            c += shade_listed(light_indices[k], p, n, v, m, infinite);
        }
    }
    return c;
}

// The lights of pixel `pixel` (depth buffer value z) shaded at p.
fn shade_pixel_lights(pixel: vec2<u32>, z: f32, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    if zbin_lists() {
        return shade_zbin(zbin_cell(pixel, z), p, n, v, m);
    }
    return shade_list(light_list(pixel, z), p, n, v, m);
}
