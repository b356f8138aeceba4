// cull.tiled_gather (Harada, McKee, Yang 2012, section 4.1) and, with CULL_FLAG_DEPTH_MASK,
// cull.depth_mask (2.5D culling, Harada 2012): one workgroup per tile tests lights against the
// tile frustum between the tile's depth bounds (and the 2.5D masks), 64 lights at a time.
// Entry points: gather_coarse (the coarse level), gather_count (count pass) and gather_fill
// (fill pass).
//
// Coarse-to-fine (cull.coarse > 0): gather_coarse tests every light against each coarse tile
// (cull.coarse x cull.coarse tiles, between the depth bounds of its covered tiles) and writes a
// bit mask of the survivors, one bit per light. A tile then tests only its coarse tile's lights,
// in light order. The coarse frustum contains each of its tiles' frusta (its outer planes are
// their outer planes, the same floats), so the lists are those of the single level.
//
// The fill keeps each list in light order: in every batch of 64 lights, a light's slot is the
// number of kept lights before it in the batch (a workgroup scan of the batch's flags) plus
// those of earlier batches. Lists, and so the order in which shading sums a pixel's lights, are the same
// on every run: images are bit-identical across runs.

// Coarse masks: ceil(light_count / 32) words per coarse tile, coarse tiles row by row.
@group(1) @binding(9) var<storage, read_write> coarse_mask: array<u32>;

var<workgroup> wg_planes: array<vec4<f32>, 4>;
var<workgroup> wg_covered: u32;
var<workgroup> wg_keep: array<u32, 64>;
var<workgroup> wg_total: u32;
// A chunk of candidates from the coarse mask: 64 words, up to 2,048 light indices.
var<workgroup> wg_cand: array<u32, 2048>;
var<workgroup> wg_cmin: atomic<u32>;
var<workgroup> wg_cmax: atomic<u32>;
var<workgroup> wg_ccov: atomic<u32>;

// Inclusive Hillis-Steele scan of wg_keep over the workgroup (6 steps for 64 threads); returns
// this thread's inclusive prefix and leaves the total in wg_keep[63]. Called in uniform control
// flow.
fn scan_keep(li: u32, value: u32) -> u32 {
    wg_keep[li] = value;
    workgroupBarrier();
    for (var off = 1u; off < 64u; off <<= 1u) {
        var v = 0u;
        if li >= off {
            v = wg_keep[li - off];
        }
        workgroupBarrier();
        wg_keep[li] += v;
        workgroupBarrier();
    }
    return wg_keep[li];
}

// One batch of up to 64 candidate lights, light `i` at this thread (`valid` false past the
// end): counts or places the survivors; returns how many lights the tile's list holds after
// the batch. Called in uniform control flow.
fn gather_batch(bin: u32, li: u32, i: u32, valid: bool, planes: array<vec4<f32>, 4>, t: TileDepth, fill: bool, placed: u32) -> u32 {
    var keep = false;
    if valid {
        keep = tile_keeps(cull_light(lights[i]), planes, t);
    }
    if !fill {
        if keep {
            atomicAdd(&bin_counts[bin], 1u);
        }
        return placed;
    }
    let before = scan_keep(li, u32(keep));
    let total = wg_keep[63];
    let slot = placed + before - u32(keep);
    if keep && (cull.capacity == 0u || slot < cull.capacity) {
        out_indices[bin_offsets[bin] + slot] = i;
    }
    workgroupBarrier();
    return placed + total;
}

fn gather(tile: vec2<u32>, li: u32, fill: bool) {
    let bin = tile.y * cull.tiles_x + tile.x;
    let t = tile_depth[bin];
    if li == 0u {
        wg_planes = tile_side_planes(tile);
        wg_covered = t.covered;
    }
    // Uniform across the workgroup, so the barriers below are reached by all or none.
    if workgroupUniformLoad(&wg_covered) == 0u {
        return;
    }
    let planes = wg_planes;
    var placed = 0u;
    if cull.coarse == 0u {
        for (var first = 0u; first < cull.light_count; first += 64u) {
            let i = first + li;
            placed = gather_batch(bin, li, i, i < cull.light_count, planes, t, fill, placed);
        }
        return;
    }
    // The coarse tile's lights, 64 mask words (2,048 lights) at a time: each thread writes
    // its word's lights at its place in the chunk (a scan of the words' bit counts), in light
    // order; then the chunk's candidates are tested 64 at a time.
    let words = (cull.light_count + 31u) / 32u;
    let row = ((tile.y / cull.coarse) * cull.coarse_x + tile.x / cull.coarse) * words;
    for (var w0 = 0u; w0 < words; w0 += 64u) {
        var word = 0u;
        if w0 + li < words {
            word = coarse_mask[row + w0 + li];
        }
        let n_bits = countOneBits(word);
        var at = scan_keep(li, n_bits) - n_bits;
        if li == 63u {
            wg_total = wg_keep[63];
        }
        let base = (w0 + li) * 32u;
        while word != 0u {
            wg_cand[at] = base + firstTrailingBit(word);
            at += 1u;
            word &= word - 1u;
        }
        let n = workgroupUniformLoad(&wg_total);
        for (var k = 0u; k < n; k += 64u) {
            let valid = k + li < n;
            var i = 0u;
            if valid {
                i = wg_cand[k + li];
            }
            placed = gather_batch(bin, li, i, valid, planes, t, fill, placed);
        }
        workgroupBarrier();
    }
}

@compute @workgroup_size(64)
fn gather_count(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    gather(wg.xy, li, false);
}

@compute @workgroup_size(64)
fn gather_fill(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    gather(wg.xy, li, true);
}

// A float's bits mapped so that unsigned order is the float order (negative depths of an
// orthographic camera included), and back.
fn ordered_bits(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn from_ordered_bits(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u & 0x7fffffffu, (u & 0x80000000u) != 0u));
}

// cull.tiled_gather.coarse: workgroup (x, y, z) writes coarse tile (x, y)'s mask words
// 64 z .. 64 z + 63, each thread one word (32 lights). The coarse tile's depth bounds are the
// smallest dmin and largest dmax of its covered tiles; the 2.5D masks are left to the tiles.
@compute @workgroup_size(64)
fn gather_coarse(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let f = cull.coarse;
    if li == 0u {
        atomicStore(&wg_cmin, 0xffffffffu);
        atomicStore(&wg_cmax, 0u);
        atomicStore(&wg_ccov, 0u);
    }
    workgroupBarrier();
    for (var k = li; k < f * f; k += 64u) {
        let tile = wg.xy * f + vec2<u32>(k % f, k / f);
        if tile.x < cull.tiles_x && tile.y < cull.tiles_y {
            let t = tile_depth[tile.y * cull.tiles_x + tile.x];
            if t.covered != 0u {
                atomicMin(&wg_cmin, ordered_bits(t.dmin));
                atomicMax(&wg_cmax, ordered_bits(t.dmax));
                atomicAdd(&wg_ccov, t.covered);
            }
        }
    }
    workgroupBarrier();
    let words = (cull.light_count + 31u) / 32u;
    let word = wg.z * 64u + li;
    if word >= words {
        return;
    }
    var t: TileDepth;
    t.covered = atomicLoad(&wg_ccov);
    t.dmin = from_ordered_bits(atomicLoad(&wg_cmin));
    t.dmax = from_ordered_bits(atomicLoad(&wg_cmax));
    t.mask = 0xffffffffu;
    var bits = 0u;
    if t.covered != 0u {
        let planes = square_side_planes(wg.xy, f * cull.tile_size);
        let end = min(word * 32u + 32u, cull.light_count);
        for (var i = word * 32u; i < end; i++) {
            if tile_keeps(cull_light(lights[i]), planes, t) {
                bits |= 1u << (i - word * 32u);
            }
        }
    }
    coarse_mask[(wg.y * cull.coarse_x + wg.x) * words + word] = bits;
}
