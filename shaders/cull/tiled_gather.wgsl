// cull.tiled_gather (Harada, McKee, Yang 2012, section 4.1) and, with CULL_FLAG_DEPTH_MASK,
// cull.depth_mask (2.5D culling, Harada 2012): one workgroup per tile tests lights against the
// tile frustum between the tile's depth bounds (and the 2.5D masks), 64 lights at a time.
// Entry points: gather_coarse (the coarse level), gather_count / gather_fill (count and fill
// passes over the coarse tile's lights) and gather_count_flat / gather_fill_flat (the single
// level, every light), in gather_scan.wgsl or, with subgroup operations, gather_scan_subgroup.wgsl,
// which also define the workgroup scan `scan_keep`. A thread's `slot` (0..63) orders its light
// within a batch.
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
var<workgroup> wg_total: u32;
// A chunk of candidates from the coarse mask: 64 words, up to 2,048 light indices.
var<workgroup> wg_cand: array<u32, 2048>;
var<workgroup> wg_cmin: atomic<u32>;
var<workgroup> wg_cmax: atomic<u32>;
var<workgroup> wg_ccov: atomic<u32>;

// One batch of up to 64 candidate lights, light `i` at this thread (`valid` false past the
// end). The count pass adds the survivors to `counted`, this thread's own count (one atomic
// add per thread at the end, not one per light); the fill pass places them in light order.
// Returns (lights placed in the tile's list after the batch, counted). Called in uniform
// control flow.
fn gather_batch(bin: u32, slot: u32, i: u32, valid: bool, planes: array<vec4<f32>, 4>, t: TileDepth, fill: bool, acc: vec2<u32>) -> vec2<u32> {
    var keep = false;
    if valid {
        keep = tile_keeps(cull_light(lights[i]), planes, t);
    }
    if !fill {
        return vec2<u32>(acc.x, acc.y + u32(keep));
    }
    let scan = scan_keep(slot, u32(keep));
    let at = acc.x + scan.x - u32(keep);
    if keep && (cull.capacity == 0u || at < cull.capacity) {
        out_indices[bin_offsets[bin] + at] = i;
    }
    return vec2<u32>(acc.x + scan.y, acc.y);
}

// The tile's planes (in workgroup memory) and depth data; false for an empty tile. Uniform, so
// the barriers after it are reached by all threads or none.
fn tile_setup(tile: vec2<u32>, slot: u32) -> bool {
    let t = tile_depth[tile.y * cull.tiles_x + tile.x];
    if slot == 0u {
        wg_planes = tile_side_planes(tile);
        wg_covered = t.covered;
    }
    return workgroupUniformLoad(&wg_covered) != 0u;
}

fn count_done(bin: u32, fill: bool, acc: vec2<u32>) {
    if !fill && acc.y != 0u {
        atomicAdd(&bin_counts[bin], acc.y);
    }
}

// The single level: every light, 64 at a time.
fn gather_flat(tile: vec2<u32>, slot: u32, fill: bool) {
    if !tile_setup(tile, slot) {
        return;
    }
    let bin = tile.y * cull.tiles_x + tile.x;
    let t = tile_depth[bin];
    let planes = wg_planes;
    var acc = vec2<u32>(0u);
    for (var first = 0u; first < cull.light_count; first += 64u) {
        let i = first + slot;
        acc = gather_batch(bin, slot, i, i < cull.light_count, planes, t, fill, acc);
    }
    count_done(bin, fill, acc);
}

// Over the coarse tile's lights, 64 mask words (2,048 lights) at a time: each thread writes its
// word's lights at its place in the chunk (a scan of the words' bit counts), in light order;
// then the chunk's candidates are tested 64 at a time.
fn gather(tile: vec2<u32>, slot: u32, fill: bool) {
    if !tile_setup(tile, slot) {
        return;
    }
    let bin = tile.y * cull.tiles_x + tile.x;
    let t = tile_depth[bin];
    let planes = wg_planes;
    var acc = vec2<u32>(0u);
    let words = (cull.light_count + 31u) / 32u;
    let row = ((tile.y / cull.coarse) * cull.coarse_x + tile.x / cull.coarse) * words;
    for (var w0 = 0u; w0 < words; w0 += 64u) {
        var word = 0u;
        if w0 + slot < words {
            word = coarse_mask[row + w0 + slot];
        }
        let n_bits = countOneBits(word);
        let scan = scan_keep(slot, n_bits);
        var at = scan.x - n_bits;
        let base = (w0 + slot) * 32u;
        while word != 0u {
            wg_cand[at] = base + firstTrailingBit(word);
            at += 1u;
            word &= word - 1u;
        }
        if slot == 0u {
            wg_total = scan.y;
        }
        let n = workgroupUniformLoad(&wg_total);
        for (var k = 0u; k < n; k += 64u) {
            let valid = k + slot < n;
            var i = 0u;
            if valid {
                i = wg_cand[k + slot];
            }
            acc = gather_batch(bin, slot, i, valid, planes, t, fill, acc);
        }
        workgroupBarrier();
    }
    count_done(bin, fill, acc);
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
