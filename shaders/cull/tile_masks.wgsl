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

// The fill's place for its tile, and the scatter's kept lights, shared by a workgroup.
var<workgroup> wg_mask_at: u32;
var<workgroup> wg_mask_kept: atomic<u32>;

// Words of a tile's mask: two a batch of 64 lights.
fn mask_words() -> u32 {
    return (cull.light_count + 63u) / 64u * 2u;
}

// The fill: thread `slot` takes words [slot k, slot k + k) of tile `tile`'s mask (k = words /
// 64, rounded up), so that the threads' words follow light order; one workgroup scan of their
// bit counts gives each thread its place in the tile's list and the tile's total, from which
// the first thread takes the tile's place in the list buffer (one atomic add) and writes its
// range. Each thread then turns its words into list entries, clearing each nonzero word. A
// tile without lights writes an empty range.
fn masks_expand(tile: vec2<u32>, slot: u32) {
    let bin = tile.y * cull.tiles_x + tile.x;
    let words = mask_words();
    let k = (words + 63u) / 64u;
    let first = bin * words + min(slot * k, words);
    let end = bin * words + min(slot * k + k, words);
    var c = 0u;
    for (var w = first; w < end; w++) {
        c += countOneBits(atomicLoad(&tile_masks[w]));
    }
    let scan = scan_keep(slot, c);
    if slot == 0u {
        var at = 0u;
        if scan.y != 0u {
            at = atomicAdd(&cull_stats[5], scan.y);
        }
        out_ranges[bin] = vec2<u32>(at, scan.y);
        wg_mask_at = at;
    }
    var pos = workgroupUniformLoad(&wg_mask_at) + scan.x - c;
    if c == 0u {
        return;
    }
    for (var w = first; w < end; w++) {
        var m = atomicLoad(&tile_masks[w]);
        if m != 0u {
            atomicStore(&tile_masks[w], 0u);
            let light = (w - bin * words) * 32u;
            while m != 0u {
                out_indices[pos] = light + firstTrailingBit(m);
                m &= m - 1u;
                pos += 1u;
            }
        }
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
