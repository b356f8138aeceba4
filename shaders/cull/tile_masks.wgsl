// Tile masks: a bit per (tile, light), mask_words() words a tile, light k of tile `bin` at bit
// k % 32 of word bin * mask_words() + k / 32. Used where tiles x lights bits fit the host's
// budget (Culler::mask_budget). Two writers set the bits:
// - gather's and 2.5D's count pass (tiled_gather.wgsl, CHUNK_MASK): a thread a tile stores the
//   nonzero words of its tile's kept lights;
// - tiled scatter's count pass (scatter_masks, here): a workgroup a light sets its bit in every
//   tile of its rectangle that keeps it (the tile test of tile_keeps, as tiled_scatter.wgsl),
//   with atomicOr;
// and both sum the lights kept over all tiles into cull_stats[4], from which the host sizes the
// lists. One reader, the fill (masks_expand, a workgroup per tile), counts its tile's bits,
// takes the tile's place in the list buffer with one atomic add (cull_stats[5]), writes its
// range, and turns the words into its list, in light order, clearing each nonzero word as it
// goes: the masks are all zero again after every fill, as they were when created, so the next
// count pass starts from zero without a clear. A tile's list is the same as without masks;
// only where it sits in the buffer differs from run to run (its range says where).
@group(1) @binding(11) var<storage, read_write> tile_masks: array<atomic<u32>>;

// The fill's tile total and place, and the scatter's kept lights, shared by a workgroup.
var<workgroup> wg_mask_n: u32;
var<workgroup> wg_mask_at: u32;
var<workgroup> wg_mask_kept: atomic<u32>;

// Words of a tile's mask: two a batch of 64 lights.
fn mask_words() -> u32 {
    return (cull.light_count + 63u) / 64u * 2u;
}

// The fill: tile `tile`'s bits counted (a workgroup scan of each thread's words), its place in
// the list buffer and its range, then its list from its words, 64 words at a time, each
// thread's lights placed after those of the words before it. A tile without lights writes an
// empty range.
fn masks_expand(tile: vec2<u32>, slot: u32) {
    let bin = tile.y * cull.tiles_x + tile.x;
    let words = mask_words();
    let base = bin * words;
    var c = 0u;
    for (var w = slot; w < words; w += 64u) {
        c += countOneBits(atomicLoad(&tile_masks[base + w]));
    }
    let n = scan_keep(slot, c).y;
    if slot == 0u {
        var at = 0u;
        if n != 0u {
            at = atomicAdd(&cull_stats[5], n);
        }
        out_ranges[bin] = vec2<u32>(at, n);
        wg_mask_n = n;
        wg_mask_at = at;
    }
    // Uniform, so the scans' barriers are reached by all threads or none.
    if workgroupUniformLoad(&wg_mask_n) == 0u {
        return;
    }
    var acc = wg_mask_at;
    for (var first = 0u; first < words; first += 64u) {
        let w = first + slot;
        var m = 0u;
        if w < words {
            m = atomicLoad(&tile_masks[base + w]);
            if m != 0u {
                atomicStore(&tile_masks[base + w], 0u);
            }
        }
        let bits = countOneBits(m);
        let scan = scan_keep(slot, bits);
        var pos = acc + scan.x - bits;
        while m != 0u {
            out_indices[pos] = w * 32u + firstTrailingBit(m);
            m &= m - 1u;
            pos += 1u;
        }
        acc += scan.y;
    }
}

// Tiled scatter's count pass with tile masks: workgroup wg a light; its threads take every
// 64th tile of its rectangle.
@compute @workgroup_size(64)
fn scatter_masks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) slot: u32) {
    let i = wg.y * GROUPS_X + wg.x;
    if slot == 0u {
        atomicStore(&wg_mask_kept, 0u);
    }
    workgroupBarrier();
    var kept = 0u;
    if i < cull.light_count {
        let l = cull_light(lights[i]);
        let rect = light_tiles(l);
        if rect.x <= rect.z && rect.y <= rect.w {
            let width = u32(rect.z - rect.x + 1);
            let count = width * u32(rect.w - rect.y + 1);
            let word = i / 32u;
            let bit = 1u << (i % 32u);
            let words = mask_words();
            for (var k = slot; k < count; k += 64u) {
                let tile = vec2<u32>(u32(rect.x) + k % width, u32(rect.y) + k / width);
                let bin = tile.y * cull.tiles_x + tile.x;
                if tile_keeps(l, tile_side_planes(tile), tile_depth[bin]) {
                    atomicOr(&tile_masks[bin * words + word], bit);
                    kept += 1u;
                }
            }
        }
    }
    if kept != 0u {
        atomicAdd(&wg_mask_kept, kept);
    }
    workgroupBarrier();
    if slot == 0u {
        let k = atomicLoad(&wg_mask_kept);
        if k != 0u {
            atomicAdd(&cull_stats[4], k);
        }
    }
}
