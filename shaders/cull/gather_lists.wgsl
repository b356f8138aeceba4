// cull.tiled_gather.lists and cull.depth_mask.lists: gather and 2.5D in one pass after
// cull.light_rects, where a block's tile masks fit workgroup memory (at most LISTS_MAX_LIGHTS
// lights). Workgroup (x, y) takes the block of LISTS_BLOCK x LISTS_BLOCK tiles from tile
// (LISTS_BLOCK x, LISTS_BLOCK y), LISTS_TILE_THREADS threads a tile (tile slot / 16, row by
// row), and every light: it owns its tiles from depth to lists, so there is no count pass, no
// fill pass and no mask in memory.
//
// 1. Depth: each tile's depth data (tile_bounds.wgsl), also stored in tile_depth; each
//    column's pair of side planes and each row's (tile_side_planes: a tile's planes 0 and 1
//    depend only on its column, 2 and 3 only on its row).
// 2. Candidates: each thread takes every LISTS_THREADS-th light; those whose rectangle (from
//    cull.light_rects) meets the block go to a list in workgroup memory, with the span of
//    columns and rows of the block it covers.
// 3. Tests: a thread a candidate transforms the light once, tests it against the side planes
//    of the columns and rows it spans, then against the depth data of each tile at a column and
//    a row it passes (depth_keeps), and sets its bit in the masks of the tiles that keep it
//    (a bit a (tile, light), in workgroup memory).
// 4. Lists: each tile's 16 threads count the bits of a 16th of its words each; one atomic add
//    (cull_stats[5]) places the block's lists, tile after tile, in the list buffer; each tile
//    writes its range, and each thread turns its words into list entries, in light order.
//    Where the list buffer is too short (the host's sizing run, before it knows the total)
//    nothing is written, but the total is still summed, and the host reads it.
//
// A tile's list is what the count and fill passes give (and cpu::gather states): the lights
// whose rectangle holds the tile and that pass its tile test (tile_keeps is sides_keep for its
// column and its row and depth_keeps, the same floats).
@group(1) @binding(9) var<storage, read_write> light_rects: array<vec2<u32>>;

// The block's tile masks: tile slot f's light k at bit k % 32 of word f LISTS_WORDS + k / 32.
var<workgroup> wl_masks: array<atomic<u32>, LISTS_BLOCK * LISTS_BLOCK * LISTS_WORDS>;
// Candidates: light index | span << 16, the span being the block's columns lo.x..=hi.x and
// rows lo.y..=hi.y its rectangle covers (two bits each: lo.x, lo.y, hi.x, hi.y).
var<workgroup> wl_cand: array<u32, LISTS_MAX_LIGHTS>;
var<workgroup> wl_ncand: atomic<u32>;
var<workgroup> wl_n: u32;
var<workgroup> wl_any: atomic<u32>;
var<workgroup> wl_covered: u32;
var<workgroup> wl_tile: array<TileDepth, LISTS_BLOCK * LISTS_BLOCK>;
// Column c's side planes at 2c and 2c + 1, row r's at 2 LISTS_BLOCK + 2r and + 1.
var<workgroup> wl_side: array<vec4<f32>, 4 * LISTS_BLOCK>;
// Each thread's bits, each tile's total and first place among the block's lists, the block's
// place in the list buffer and total.
var<workgroup> wl_count: array<u32, LISTS_THREADS>;
var<workgroup> wl_tile_total: array<u32, LISTS_BLOCK * LISTS_BLOCK>;
var<workgroup> wl_start: array<u32, LISTS_BLOCK * LISTS_BLOCK>;
var<workgroup> wl_base: u32;
var<workgroup> wl_total: u32;

// The columns and rows (lo.x, lo.y, hi.x, hi.y) of the block at tile `o` that a light's packed
// rectangle covers; none where lo > hi.
fn block_span(packed: vec2<u32>, o: vec4<i32>) -> vec4<i32> {
    let rect = vec4<i32>(vec4<u32>(packed.x & 0xffffu, packed.x >> 16u, packed.y & 0xffffu, packed.y >> 16u)) - o;
    return vec4<i32>(max(rect.xy, vec2<i32>(0)), min(rect.zw, vec2<i32>(i32(LISTS_BLOCK) - 1)));
}

@compute @workgroup_size(LISTS_THREADS)
fn gather_lists(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) slot: u32) {
    let j = slot / LISTS_TILE_THREADS;
    let li = slot % LISTS_TILE_THREADS;
    let origin = wg.xy * LISTS_BLOCK;
    let tile = origin + vec2<u32>(j % LISTS_BLOCK, j / LISTS_BLOCK);
    let inside = tile.x < cull.tiles_x && tile.y < cull.tiles_y;
    let bin = tile.y * cull.tiles_x + tile.x;
    for (var w = slot; w < LISTS_BLOCK * LISTS_BLOCK * LISTS_WORDS; w += LISTS_THREADS) {
        atomicStore(&wl_masks[w], 0u);
    }
    if slot == 0u {
        atomicStore(&wl_ncand, 0u);
        atomicStore(&wl_any, 0u);
    }

    // 1. Depth (tile_depth_of starts with a barrier, after the stores above).
    let t = tile_depth_of(tile, j, li, LISTS_TILE_THREADS);
    if li == 0u {
        wl_tile[j] = t;
        if inside {
            tile_depth[bin] = t;
        }
        if t.covered != 0u {
            atomicOr(&wl_any, 1u);
        }
    }
    if slot < LISTS_BLOCK {
        let p = tile_side_planes(origin + vec2<u32>(slot));
        wl_side[2u * slot] = p[0];
        wl_side[2u * slot + 1u] = p[1];
        wl_side[2u * LISTS_BLOCK + 2u * slot] = p[2];
        wl_side[2u * LISTS_BLOCK + 2u * slot + 1u] = p[3];
    }
    workgroupBarrier();
    if slot == 0u {
        wl_covered = atomicLoad(&wl_any);
    }
    // Uniform, so the barriers below are reached by all threads or none. A block without
    // covered pixels has empty lists.
    if workgroupUniformLoad(&wl_covered) == 0u {
        if inside && li == 0u {
            out_ranges[bin] = vec2<u32>(0u);
        }
        return;
    }

    // 2. Candidates.
    // A thread takes `q` consecutive lights (at most 16), finds which meet the block, takes
    // room for them with one atomic add, and writes them in light order.
    let o = vec4<i32>(vec4<u32>(origin, origin));
    let q = (cull.light_count + LISTS_THREADS - 1u) / LISTS_THREADS;
    let first = slot * q;
    let end = min(first + q, cull.light_count);
    var hits = 0u;
    for (var i = first; i < end; i++) {
        let span = block_span(light_rects[i], o);
        if all(span.xy <= span.zw) {
            hits |= 1u << (i - first);
        }
    }
    if hits != 0u {
        var c = atomicAdd(&wl_ncand, countOneBits(hits));
        while hits != 0u {
            let i = first + firstTrailingBit(hits);
            hits &= hits - 1u;
            let span = vec4<u32>(block_span(light_rects[i], o));
            wl_cand[c] = i | (span.x << 16u) | (span.y << 18u) | (span.z << 20u) | (span.w << 22u);
            c += 1u;
        }
    }
    workgroupBarrier();
    if slot == 0u {
        wl_n = atomicLoad(&wl_ncand);
    }
    let n = workgroupUniformLoad(&wl_n);

    // 3. Tests.
    // A thread takes consecutive candidates, so that the threads of a subgroup set bits of
    // different words (lights far apart) rather than contend for one.
    let q2 = (n + LISTS_THREADS - 1u) / LISTS_THREADS;
    let c_end = min(slot * q2 + q2, n);
    for (var c = slot * q2; c < c_end; c++) {
        let e = wl_cand[c];
        let i = e & 0xffffu;
        let lo = vec2<u32>((e >> 16u) & 3u, (e >> 18u) & 3u);
        let hi = vec2<u32>((e >> 20u) & 3u, (e >> 22u) & 3u);
        let l = cull_light(lights[i]);
        var cols = 0u;
        for (var x = lo.x; x <= hi.x; x++) {
            if sides_keep(wl_side[2u * x], wl_side[2u * x + 1u], l) {
                cols |= 1u << x;
            }
        }
        if cols == 0u {
            continue;
        }
        let word = i / 32u;
        let bit = 1u << (i % 32u);
        for (var y = lo.y; y <= hi.y; y++) {
            if !sides_keep(wl_side[2u * LISTS_BLOCK + 2u * y], wl_side[2u * LISTS_BLOCK + 2u * y + 1u], l) {
                continue;
            }
            for (var x = lo.x; x <= hi.x; x++) {
                let f = y * LISTS_BLOCK + x;
                if ((cols >> x) & 1u) != 0u && depth_keeps(l, wl_tile[f]) {
                    atomicOr(&wl_masks[f * LISTS_WORDS + word], bit);
                }
            }
        }
    }
    workgroupBarrier();

    // 4. Lists: this thread's words of its tile's mask.
    let words = (cull.light_count + 31u) / 32u;
    let per = (words + LISTS_TILE_THREADS - 1u) / LISTS_TILE_THREADS;
    let w0 = min(li * per, words);
    let w1 = min(w0 + per, words);
    var count = 0u;
    for (var w = w0; w < w1; w++) {
        count += countOneBits(atomicLoad(&wl_masks[j * LISTS_WORDS + w]));
    }
    wl_count[slot] = count;
    workgroupBarrier();
    if slot < LISTS_BLOCK * LISTS_BLOCK {
        var s = 0u;
        for (var k = 0u; k < LISTS_TILE_THREADS; k++) {
            s += wl_count[slot * LISTS_TILE_THREADS + k];
        }
        wl_tile_total[slot] = s;
    }
    workgroupBarrier();
    if slot == 0u {
        var s = 0u;
        for (var k = 0u; k < LISTS_BLOCK * LISTS_BLOCK; k++) {
            wl_start[k] = s;
            s += wl_tile_total[k];
        }
        var base = 0u;
        if s != 0u {
            base = atomicAdd(&cull_stats[5], s);
        }
        wl_base = base;
        wl_total = s;
    }
    workgroupBarrier();
    if !inside {
        return;
    }
    let base = wl_base;
    var pos = base + wl_start[j];
    if li == 0u {
        out_ranges[bin] = vec2<u32>(pos, wl_tile_total[j]);
    }
    if count == 0u || base + wl_total > arrayLength(&out_indices) {
        return;
    }
    for (var k = 0u; k < li; k++) {
        pos += wl_count[j * LISTS_TILE_THREADS + k];
    }
    for (var w = w0; w < w1; w++) {
        var m = atomicLoad(&wl_masks[j * LISTS_WORDS + w]);
        while m != 0u {
            out_indices[pos] = w * 32u + firstTrailingBit(m);
            m &= m - 1u;
            pos += 1u;
        }
    }
}
