// Shading a pixel's list (shade.forward and shade.deferred): the one loop both backends run over
// the lights their culling kept, after lookup.wgsl's lookup: shade_list over a bin's list, or
// shade_zbin over z-binning's tile bits within a depth bin's range. Each backend has an entry
// point for each form of lists (the pipeline is chosen by the lists' form), so that neither
// pays for the other's loop in its registers: one shader with a uniform branch between the
// two was 6-7% slower on the bin lists (H100, docs/bench/HISTORY.md).
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
    var c = emitted(m);
    lights_walked += list.y;
    for (var k = 0u; k < list.y; k++) {
        let i = light_indices[list.x + k];
        let to_light = lights[i].position - p;
        let d = length(to_light);
        if !infinite && d >= lights[i].radius {
            continue;
        }
        c += shade_listed(lights[i], p, to_light, d, n, v, m);
    }
    return lights_checked(c);
}

// Z-binning's cell: its set bits in order, so lights are summed in depth order, the same order on
// every run; the same reject as shade_list.
fn shade_zbin(cell: ZBinCell, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    let infinite = (frame.flags & FRAME_FLAG_INFINITE_RANGE) != 0u;
    var c = emitted(m);
    if cell.first >= cell.end {
        return lights_checked(c);
    }
    for (var w = cell.first / 32u; w <= (cell.end - 1u) / 32u; w++) {
        var bits = zbin_bits(cell, w);
        lights_walked += countOneBits(bits);
        while bits != 0u {
            let k = w * 32u + firstTrailingBit(bits);
            bits &= bits - 1u;
            let i = light_indices[k];
            let to_light = lights[i].position - p;
            let d = length(to_light);
            if !infinite && d >= lights[i].radius {
                continue;
            }
            c += shade_listed(lights[i], p, to_light, d, n, v, m);
        }
    }
    return lights_checked(c);
}
