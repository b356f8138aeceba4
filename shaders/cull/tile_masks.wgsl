// Tile masks: a bit per (tile, light), mask_words() words a tile, light k of tile `bin` at bit
// k % 32 of word bin * mask_words() + k / 32. Used where tiles x lights bits fit the host's
// budget (Culler::mask_budget). Two writers set the bits:
// - gather's and 2.5D's count pass (tiled_gather.wgsl, CHUNK_MASK): a thread a tile stores the
//   nonzero words of its tile's kept lights;
// - tiled scatter's count pass (scatter_masks, tiled_scatter.wgsl, which binds the masks as
//   atomics): a workgroup a light sets its bit in every tile of its rectangle that keeps it,
//   with atomicOr;
// and both add each tile's kept lights to bin_counts and sum them over all tiles into
// cull_stats[4], from which the host sizes the lists. One reader, the fill (masks_expand, 64
// threads a tile), takes each tile's place in the list buffer with one atomic add
// (cull_stats[5]), writes its range, and turns the words into its list, in light order,
// clearing each nonzero word as it goes: the masks are all zero again after every fill, as they were when created, so the next
// count pass starts from zero without a clear. A tile's list is the same as without masks;
// only where it sits in the buffer differs from run to run (its range says where).
@group(1) @binding(11) var<storage, read_write> tile_masks: array<u32>;

// The fill's tiles' list lengths and places, and whether any of them has a light.
var<workgroup> wg_mask_n: array<u32, MASK_FILL_TILES>;
var<workgroup> wg_mask_at: array<u32, MASK_FILL_TILES>;
var<workgroup> wg_mask_any: u32;

// The fill: workgroup wg takes MASK_FILL_TILES tiles of a row (tiles MASK_FILL_TILES wg.x + j
// of row wg.y), 64 threads each (fewer, larger workgroups: launching them costs more than a
// tile's work). A tile's first thread takes the tile's place in the list buffer for the count
// its count pass left in bin_counts (one atomic add) and writes its range; then the tile's
// threads take its words 64 at a time, a word a thread, each thread's lights placed after
// those of the words before it (a scan of their bit counts over the tile's 64 threads),
// clearing each nonzero word. A tile without lights writes an empty range and reads nothing;
// a workgroup whose tiles have none stops there.
fn masks_expand(wg: vec2<u32>, slot: u32) {
    let j = slot / 64u;
    let lane = slot % 64u;
    let tile = vec2<u32>(wg.x * MASK_FILL_TILES + j, wg.y);
    let bin = tile.y * cull.tiles_x + tile.x;
    // A tile past the last column (in the last workgroup of a row) has no lights.
    let inside = tile.x < cull.tiles_x;
    if lane == 0u {
        var n = 0u;
        var at = 0u;
        if inside {
            n = atomicLoad(&bin_counts[bin]);
            if n != 0u {
                at = atomicAdd(&cull_stats[5], n);
            }
            out_ranges[bin] = vec2<u32>(at, n);
        }
        wg_mask_n[j] = n;
        wg_mask_at[j] = at;
    }
    workgroupBarrier();
    if slot == 0u {
        var any = 0u;
        for (var t = 0u; t < MASK_FILL_TILES; t++) {
            any |= wg_mask_n[t];
        }
        wg_mask_any = any;
    }
    // Uniform, so the scans' barriers are reached by all threads or none.
    if workgroupUniformLoad(&wg_mask_any) == 0u {
        return;
    }
    let n = wg_mask_n[j];
    var acc = wg_mask_at[j];
    let words = mask_words();
    let base = bin * words;
    for (var first = 0u; first < words; first += 64u) {
        let w = first + lane;
        var m = 0u;
        if n != 0u && w < words {
            m = tile_masks[base + w];
            if m != 0u {
                tile_masks[base + w] = 0u;
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
