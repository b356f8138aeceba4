// cull.tiled_gather (Harada, McKee, Yang 2012, section 4.1) and, with CULL_FLAG_DEPTH_MASK,
// cull.depth_mask (2.5D culling, Harada 2012): lights tested against each tile's frustum
// between the tile's depth bounds (and the 2.5D masks). Entry points, in gather_scan.wgsl or,
// with subgroup operations, gather_scan_subgroup.wgsl (which also define the workgroup scan
// `scan_keep`): gather_count / gather_fill (count and fill passes, coarse-to-fine) and
// gather_count_flat / gather_fill_flat (the single level). A thread's
// `slot` (0..63) orders its light within a batch.
//
// Coarse-to-fine (cull.coarse = 8): cull.depth_bounds also stores each light's tile rectangle
// (light_tiles, as scatter and clusters use: its view-space box cut at the near plane,
// projected). Then workgroup (x, y, z) takes coarse tile (x, y), 8 x 8 tiles, one tile a
// thread, and chunk z of the lights (cull.chunk lights in light order). For each 64 lights of
// the chunk, each thread takes one: if its rectangle meets the coarse tile and it reaches the
// coarse tile's depth slab (between the smallest and largest depth bound of its tiles), it
// goes to workgroup memory at its slot, and its bit into the lines (the coarse tile's columns
// and rows) its rectangle spans. Each thread then tests, in slot order, only the lights whose
// bit is in both its column and its row, against its tile (frustum planes between its depth
// bounds, and the 2.5D masks). So a light is transformed once per coarse tile, not once per
// tile, a tile tests only the lights whose rectangle holds it, and a thread writes its tile's
// lights in light order without scans: the count pass stores each (tile, chunk)'s count, their
// exclusive scan gives each chunk's place in its tile's list, and the fill pass's first chunk
// writes a tile's range from its first chunk's offset to the next tile's. A tile's list is exactly the
// lights whose rectangle holds the tile and that pass its tile test: the coarse tests only
// skip lights that would fail those (a tile's slab lies within its coarse tile's, and the same
// floats are compared), and cpu::gather states the same.
//
// Tile masks (where tiles x lights bits fit the host's budget, as at the Forward+ paper's
// configuration; tile_masks.wgsl): the count pass stores each tile's kept lights as bits
// instead of counting per (tile, chunk), and sums the total (cull_stats[4]), from which the
// host sizes the lists. No scan: the fill pass (masks_expand, 64 threads a tile) turns the
// tile's words into its list, in light order, without testing any light again.
//
// The single level (cull.coarse = 0): the paper's one workgroup per tile over every light; the
// fill keeps each list in light order: in every batch of 64 lights, a light's slot is the
// number of kept lights before it in the batch (a workgroup scan of the batch's flags) plus
// those of earlier batches. Lists, and so the order in which shading sums a pixel's lights, are
// the same on every run: images are bit-identical across runs.

var<workgroup> wg_planes: array<vec4<f32>, 4>;
var<workgroup> wg_covered: u32;
var<workgroup> wg_cmin: atomic<u32>;
var<workgroup> wg_cmax: atomic<u32>;
var<workgroup> wg_ccov: atomic<u32>;
// A batch's lights (those that reach the coarse tile), at their slots.
var<workgroup> wg_light: array<CullLight, 64>;
// Two sets of a batch's lines, 32 words each: words 2c and 2c + 1 of a set have bit k set
// for the batch's light at slot 32 * (word % 2) + k when its rectangle spans column c of the
// coarse tile (c < 8), or row c - 8 (c >= 8). A tile's candidates are its column's bits and
// its row's.
var<workgroup> wg_lines: array<atomic<u32>, 64>;
// Each light's tile rectangle (from cull.depth_bounds, for coarse-to-fine gather and 2.5D).
@group(1) @binding(9) var<storage, read_write> light_rects: array<vec2<u32>>;

// What a coarse-to-fine pass does: count per (tile, chunk), fill, or store the tile masks and
// sum their total.
const CHUNK_COUNT: u32 = 0u;
const CHUNK_FILL: u32 = 1u;
const CHUNK_MASK: u32 = 2u;

// One batch of up to 64 candidate lights, light `i` at this thread (`valid` false past the
// end). The count pass adds the survivors to `counted`, this thread's own count (one atomic
// add per thread at the end, not one per light); the fill pass places them in light order.
// Returns (lights placed in the tile's list after the batch, counted). Called in uniform
// control flow.
fn gather_batch(bin: u32, slot: u32, i: u32, valid: bool, planes: array<vec4<f32>, 4>, b: array<vec3<f32>, 2>, t: TileDepth, fill: bool, acc: vec2<u32>) -> vec2<u32> {
    var keep = false;
    if valid {
        keep = tile_keeps(cull_light(lights[i]), planes, b, t);
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
    let b = tile_test_box(tile, t);
    var acc = vec2<u32>(0u);
    for (var first = 0u; first < cull.light_count; first += 64u) {
        let i = first + slot;
        acc = gather_batch(bin, slot, i, i < cull.light_count, planes, b, t, fill, acc);
    }
    count_done(bin, fill, acc);
}

// Coarse-to-fine over coarse tile wg.xy and light chunk wg.z (see the top of this file); this
// thread's tile is the slot-th of the coarse tile, row by row.
fn gather_chunk(wg: vec3<u32>, slot: u32, mode: u32) {
    let fill = mode == CHUNK_FILL;
    if slot == 0u {
        atomicStore(&wg_cmin, 0xffffffffu);
        atomicStore(&wg_cmax, 0u);
        atomicStore(&wg_ccov, 0u);
        atomicStore(&wg_kept, 0u);
    }
    atomicStore(&wg_lines[slot], 0u);
    workgroupBarrier();
    let local = vec2<u32>(slot % 8u, slot / 8u);
    let tile = wg.xy * 8u + local;
    let inside = tile.x < cull.tiles_x && tile.y < cull.tiles_y;
    let bin = tile.y * cull.tiles_x + tile.x;
    var t: TileDepth;
    var planes: array<vec4<f32>, 4>;
    var bx: array<vec3<f32>, 2>;
    if inside {
        t = tile_depth[bin];
        if t.covered != 0u {
            atomicMin(&wg_cmin, ordered_bits(t.dmin));
            atomicMax(&wg_cmax, ordered_bits(t.dmax));
            atomicAdd(&wg_ccov, t.covered);
            planes = tile_side_planes(tile);
            bx = tile_test_box(tile, t);
        }
    }
    workgroupBarrier();
    if slot == 0u {
        wg_covered = atomicLoad(&wg_ccov);
    }
    // Uniform, so the barriers below are reached by all threads or none.
    if workgroupUniformLoad(&wg_covered) == 0u {
        return;
    }
    let cmin = from_ordered_bits(atomicLoad(&wg_cmin));
    let cmax = from_ordered_bits(atomicLoad(&wg_cmax));
    let origin = vec2<i32>(wg.xy * 8u);
    let has_pixels = inside && t.covered != 0u;
    let chunks = (cull.light_count + cull.chunk - 1u) / cull.chunk;
    let entry = bin * chunks + wg.z;
    var at = 0u;
    if fill && has_pixels {
        at = bin_offsets[entry];
        // The first chunk's workgroup also writes the tile's range: from its first chunk's
        // offset to the next tile's. (Ranges start cleared: a tile without pixels keeps an
        // empty one.)
        if wg.z == 0u {
            out_ranges[bin] = vec2<u32>(at, bin_offsets[entry + chunks] - at);
        }
    }
    var kept = 0u;
    var lines = 0u;
    let first = wg.z * cull.chunk;
    let end = min(first + cull.chunk, cull.light_count);
    for (var b = first; b < end; b += 64u) {
        // This thread's light: its rectangle within the coarse tile, and the coarse tile's
        // depth slab. Its bit goes into the lines (columns, rows) the rectangle spans
        // (mark_lines, in gather_scan.wgsl or gather_scan_subgroup.wgsl).
        let i = b + slot;
        var spans = 0u;
        if i < end {
            let packed = light_rects[i];
            let rect = vec4<i32>(vec4<u32>(packed.x & 0xffffu, packed.x >> 16u, packed.y & 0xffffu, packed.y >> 16u)) - origin.xyxy;
            let lo = max(rect.xy, vec2<i32>(0));
            let hi = min(rect.zw, vec2<i32>(7));
            if all(lo <= hi) {
                let l = cull_light(lights[i]);
                if !outside_plane(vec4<f32>(0.0, 0.0, -1.0, -cmin), l) && !outside_plane(vec4<f32>(0.0, 0.0, 1.0, cmax), l) {
                    wg_light[slot] = l;
                    // Bits lo..=hi of the columns (0..7) and of the rows (8..15).
                    let span = (vec2<u32>(0xffu) << vec2<u32>(lo)) & (vec2<u32>(0xffu) >> vec2<u32>(7 - hi));
                    spans = span.x | (span.y << 8u);
                }
            }
        }
        mark_lines(slot, spans, lines);
        workgroupBarrier();
        // The other set of lines, read by the batch before, is cleared for the batch after.
        if slot < 32u {
            atomicStore(&wg_lines[(lines ^ 32u) + slot], 0u);
        }
        if has_pixels {
            for (var w = 0u; w < 2u; w++) {
                var m = atomicLoad(&wg_lines[lines + 2u * local.x + w]) & atomicLoad(&wg_lines[lines + 16u + 2u * local.y + w]);
                var word = 0u;
                while m != 0u {
                    let bit = firstTrailingBit(m);
                    let k = w * 32u + bit;
                    m &= m - 1u;
                    if tile_keeps(wg_light[k], planes, bx, t) {
                        if fill {
                            out_indices[at + kept] = b + k;
                        }
                        word |= 1u << bit;
                        kept += 1u;
                    }
                }
                if mode == CHUNK_MASK && word != 0u {
                    // Masks start each run at zero (the fill clears them), so only nonzero
                    // words are stored (chunks are whole batches, so b / 32 + w is this
                    // batch's word w).
                    tile_masks[bin * mask_words() + b / 32u + w] = word;
                }
            }
        }
        workgroupBarrier();
        lines ^= 32u;
    }
    if mode == CHUNK_COUNT && has_pixels {
        atomicStore(&bin_counts[entry], kept);
    }
    if mode == CHUNK_MASK {
        add_kept_total(slot, kept);
    }
}
