// shade.deferred over z-binning's lists a workgroup at a time (the entry points
// deferred_shade_zbin and deferred_shade_zbin_rounds of deferred.wgsl, and their stored-position
// twins): the walk of a workgroup's union of depth-bin ranges, and the same in rounds for many
// point lights.

var<workgroup> wg_range: array<atomic<u32>, 2>;
var<workgroup> wg_range_plain: vec2<u32>;

// Z-binning's lights, a workgroup at a time. Where a workgroup's 8 x 8 pixels lie in one tile
// (tiles of a multiple of 8 pixels), they share the tile's mask and differ only in their depth
// bins' ranges: the workgroup walks the mask's bits within the union of its pixels' ranges
// together, each light loaded once for all of them, and each pixel shades the lights of its own
// range. (A loop a pixel over its own range, shade_zbin, makes neighbouring threads load
// different lights at once.) Other tile sizes take the loop a pixel. With many lights in a
// POINT_LIGHTS pipeline the host picks shade_zbin_rounds_group instead.
fn shade_zbin_group(pixel: vec2<u32>, group: vec2<u32>, li: u32, stored: bool) {
    if cull.tile_size % 8u != 0u {
        shade_pixel(pixel, stored, true);
        return;
    }
    if li == 0u {
        atomicStore(&wg_range[0], 0u);
        atomicStore(&wg_range[1], 0u);
    }
    workgroupBarrier();
    let inside = all(pixel < vec2<u32>(frame.viewport.xy));
    var t = NO_TEXELS;
    if inside {
        t = load_texels(pixel);
    }
    let z = t.z;
    let covered = z < 1.0;
    var cell = ZBinCell(0u, 1u, 0u);
    if covered {
        cell = zbin_cell(pixel, z);
        if cell.first < cell.end {
            atomicMax(&wg_range[0], ~cell.first);
            atomicMax(&wg_range[1], cell.end);
        }
    }
    workgroupBarrier();
    if li == 0u {
        wg_range_plain = vec2<u32>(~atomicLoad(&wg_range[0]), atomicLoad(&wg_range[1]));
    }
    let range = workgroupUniformLoad(&wg_range_plain);
    var c = vec3<f32>(0.0);
    var s: Surface;
    if covered {
        s = surface(pixel, t, stored);
        c = emitted(s.m);
    }
    if range.x < range.y {
        let tile = group * 8u / cull.tile_size;
        let group_cell = ZBinCell(cull.light_count + (tile.y * cull.tiles_x + tile.x) * zbin_words(), range.x, range.y);
        let infinite = (frame.flags & FRAME_FLAG_INFINITE_RANGE) != 0u;
        for (var w = range.x / 32u; w <= (range.y - 1u) / 32u; w++) {
            var bits = zbin_bits(group_cell, w);
            while bits != 0u {
                let k = w * 32u + firstTrailingBit(bits);
                bits &= bits - 1u;
                let i = light_indices[k];
                if k < cell.first || k >= cell.end {
                    continue;
                }
                lights_walked += 1u;
                let to_light = lights[i].position - s.p;
                let d = length(to_light);
                if !infinite && d >= lights[i].radius {
                    continue;
                }
                c += shade_listed(lights[i], s.p, to_light, d, s.n, s.v, s.m);
            }
        }
    }
    if inside {
        textureStore(out_color, pixel, select(vec4<f32>(0.0), vec4<f32>(lights_checked(c), 1.0), covered));
    }
}

// shade_zbin_group in rounds (shade_zbin_rounds), with many lights in a POINT_LIGHTS pipeline
// (the entry points deferred_shade_zbin_rounds, their pipelines chosen by the host from
// ZBIN_ROUNDS_MIN_LIGHTS lights; layout.rs has the measurements). Its pixels' surfaces and box
// come before the barrier, so that the rounds' loads can test the box. An entry point of its
// own, so that the one walk's pipelines run the code they ran before (with both in one, the
// hall at 5,000 lights took 2.7% longer).
fn shade_zbin_rounds_group(pixel: vec2<u32>, group: vec2<u32>, li: u32, stored: bool) {
    if cull.tile_size % 8u != 0u || !POINT_LIGHTS {
        shade_zbin_group(pixel, group, li, stored);
        return;
    }
    if li == 0u {
        atomicStore(&wg_range[0], 0u);
        atomicStore(&wg_range[1], 0u);
    }
    workgroupBarrier();
    let inside = all(pixel < vec2<u32>(frame.viewport.xy));
    var t = NO_TEXELS;
    if inside {
        t = load_texels(pixel);
    }
    let z = t.z;
    let covered = z < 1.0;
    var cell = ZBinCell(0u, 1u, 0u);
    var c = vec3<f32>(0.0);
    var s: Surface;
    if covered {
        cell = zbin_cell(pixel, z);
        if cell.first < cell.end {
            atomicMax(&wg_range[0], ~cell.first);
            atomicMax(&wg_range[1], cell.end);
        }
        s = surface(pixel, t, stored);
        c = emitted(s.m);
        widen_part_box(li, s.p);
    }
    workgroupBarrier();
    if li == 0u {
        wg_range_plain = vec2<u32>(~atomicLoad(&wg_range[0]), atomicLoad(&wg_range[1]));
    }
    let range = workgroupUniformLoad(&wg_range_plain);
    if range.x < range.y {
        let tile = group * 8u / cull.tile_size;
        let group_cell = ZBinCell(cull.light_count + (tile.y * cull.tiles_x + tile.x) * zbin_words(), range.x, range.y);
        c = shade_zbin_rounds(group_cell, li, covered, cell, s, c);
    }
    if inside {
        textureStore(out_color, pixel, select(vec4<f32>(0.0), vec4<f32>(lights_checked(c), 1.0), covered));
    }
}

// The slot of each thread in a round of shade_zbin_rounds: its sorted light, or ZBIN_NO_SLOT.
const ZBIN_NO_SLOT: u32 = 0xffffffffu;
var<workgroup> wg_zslot: array<u32, POINT_BATCH>;
// Whether a thread has bits left after a round: two words, a round's and the next's, so that one
// is cleared while the other is set.
var<workgroup> wg_zmore: array<atomic<u32>, 2>;
var<workgroup> wg_zmore_plain: u32;

// Z-binning's lights of a workgroup in a POINT_LIGHTS pipeline (shade_zbin_group). The words of
// the union of its pixels' ranges (`group`) are split into POINT_BATCH runs, one a thread; in
// each round every thread walks its run to its next set bit and loads that light into its slot
// of wg_points (one load a thread, side by side, where the workgroup walking the bits together
// loads one light after another), kept where it may reach the workgroup's box of pixels
// (part_box_holds); then each pixel shades the slots' lights of its own range, in slot order
// (the same order every run). The rounds go on while any thread has bits left.
fn shade_zbin_rounds(group: ZBinCell, li: u32, takes: bool, cell: ZBinCell, s: Surface, c_in: vec3<f32>) -> vec3<f32> {
    var c = c_in;
    let infinite = (frame.flags & FRAME_FLAG_INFINITE_RANGE) != 0u;
    let first = group.first / 32u;
    let words = (group.end - 1u) / 32u + 1u - first;
    let run = (words + POINT_BATCH - 1u) / POINT_BATCH;
    var w = first + min(li * run, words);
    let end = first + min(li * run + run, words);
    var bits = 0u;
    if w < end {
        bits = zbin_bits(group, w);
    }
    var parity = 0u;
    loop {
        while bits == 0u && w + 1u < end {
            w += 1u;
            bits = zbin_bits(group, w);
        }
        var slot = ZBIN_NO_SLOT;
        if bits != 0u {
            let k = 32u * w + firstTrailingBit(bits);
            bits &= bits - 1u;
            let i = light_indices[k];
            let q = vec4<f32>(lights[i].position, lights[i].radius);
            if infinite || part_box_holds(WHOLE_BOX, q.xyz, q.w) {
                wg_points[li] = array<vec4<f32>, 2>(q, point_energy(lights[i].color, lights[i].intensity, lights[i].alpha));
                if BAND_POINTS {
                    wg_bands[li] = band_slot(lights[i]);
                }
                slot = k;
            }
        }
        wg_zslot[li] = slot;
        if bits != 0u || w + 1u < end {
            atomicStore(&wg_zmore[parity], 1u);
        }
        workgroupBarrier();
        if li == 0u {
            wg_zmore_plain = atomicLoad(&wg_zmore[parity]);
            atomicStore(&wg_zmore[1u - parity], 0u);
        }
        let more = workgroupUniformLoad(&wg_zmore_plain);
        parity = 1u - parity;
        for (var j = 0u; takes && j < POINT_BATCH; j++) {
            let k = wg_zslot[j];
            // (ZBIN_NO_SLOT lies past every range.)
            if k < cell.first || k >= cell.end {
                continue;
            }
            lights_walked += 1u;
            let q = wg_points[j];
            let light = point_light(q[0], q[1], slot_band(j));
            let to_light = light.position - s.p;
            let d = length(to_light);
            if !infinite && d >= light.radius {
                continue;
            }
            c += shade_listed(light, s.p, to_light, d, s.n, s.v, s.m);
        }
        workgroupBarrier();
        if more == 0u {
            break;
        }
    }
    return c;
}
