// Tile masks: a bit per (tile, light), mask_words() words a tile, light k of tile `bin` at bit
// k % 32 of word bin * mask_words() + k / 32. Used where tiles x lights bits fit the host's
// budget (Culler::mask_budget). Two writers set the bits:
// - gather's and 2.5D's count pass (tiled_gather.wgsl, CHUNK_MASK): a thread a tile stores the
//   nonzero words of its tile's kept lights;
// - tiled scatter's count pass (scatter_masks, tiled_scatter.wgsl, which binds the masks as
//   atomics): a workgroup a light sets its bit in every tile of its rectangle that keeps it,
//   with atomicOr;
// and both sum the lights kept over all tiles into cull_stats[4], from which the host sizes the
// lists. One reader, the fill (masks_expand, 64 threads a tile), counts its tile's bits,
// takes the tile's place in the list buffer (place_tile: cull_stats[5]), writes its
// range, and turns the words into its list, in light order, clearing each nonzero word as it
// goes: the masks are all zero again after every fill, as they were when created, so the next
// count pass starts from zero without a clear. A tile's list is the same as without masks;
// only where it sits in the buffer differs from run to run (its range says where).
@group(1) @binding(11) var<storage, read_write> tile_masks: array<u32>;

// The fill's places for its tiles (and the lines path's).
var<workgroup> wg_mask_at: array<u32, TILE_SLOTS>;

// The place in the list buffer of tile j of the workgroup (`bin`, `total` lights; `has`: a tile
// of the image): its first thread takes it with one atomic add on cull_stats[5] and writes the
// tile's range; every thread of the tile gets it. (One atomic add a workgroup for its tiles
// together, with one more barrier, measured slower.) Called in uniform control flow.
fn place_tile(lane: u32, j: u32, bin: u32, total: u32, has: bool) -> u32 {
    if lane == 0u && has {
        var at = 0u;
        if total != 0u {
            at = atomicAdd(&cull_stats[5], total);
        }
        out_ranges[bin] = vec2<u32>(at, total);
        wg_mask_at[j] = at;
    }
    workgroupBarrier();
    return wg_mask_at[j];
}

// The fill: workgroup wg takes MASK_FILL_TILES tiles of a row (tiles MASK_FILL_TILES wg.x + j
// of row wg.y), 64 threads each (fewer, larger workgroups: launching them costs more than a
// tile's work). Thread `lane` of a tile takes words [lane k, lane k + k) of its mask (k = words
// / 64, rounded up), so that the threads' words follow light order; one scan of their bit
// counts over the tile's 64 threads gives each thread its place in the tile's list and the
// tile's total, from which the tile's first thread takes its place in the list buffer (one
// atomic add, place_tile) and writes its range. Each thread then turns its words into list
// entries, clearing each nonzero word. A tile without lights writes an empty range.
fn masks_expand(wg: vec2<u32>, slot: u32) {
    let j = slot / 64u;
    let lane = slot % 64u;
    let tile = vec2<u32>(wg.x * MASK_FILL_TILES + j, wg.y);
    let bin = tile.y * cull.tiles_x + tile.x;
    // A tile past the last column (in the last workgroup of a row) takes no words.
    let words = select(0u, mask_words(), tile.x < cull.tiles_x);
    let k = (words + 63u) / 64u;
    let first = bin * words + min(lane * k, words);
    let end = bin * words + min(lane * k + k, words);
    var c = 0u;
    for (var w = first; w < end; w++) {
        c += countOneBits(tile_masks[w]);
    }
    let scan = scan_keep(slot, c);
    var pos = place_tile(lane, j, bin, scan.y, words != 0u) + scan.x - c;
    if c == 0u {
        return;
    }
    for (var w = first; w < end; w++) {
        var m = tile_masks[w];
        if m != 0u {
            tile_masks[w] = 0u;
            let light = (w - bin * words) * 32u;
            while m != 0u {
                out_indices[pos] = light + firstTrailingBit(m);
                m &= m - 1u;
                pos += 1u;
            }
        }
    }
}
