// Gather's and 2.5D's lines path (where a bit per (tile, light) fits the host's budget, as at
// the Forward+ paper's configuration): two passes, no stored tile masks, no chunks, no scan.
//
// 1. cull.tile_lines (store_light_lines in depth_bounds.wgsl) writes the tile lines: for each
//    column of tiles and each row, a bit per light, set when the light's tile rectangle spans
//    the line and the light is inside the line's two side planes; for each depth bin (zbin), a
//    bit per light whose depth extent's bins hold it; and after the lines each light's depth
//    extent (light_depth_extent). A tile's side planes 0 and 1 are its column's and 2 and 3
//    its row's, so the AND of a tile's column word and row word is exactly the lights of that
//    word whose rectangle holds the tile and that pass its four side planes.
// 2. The count or fill pass (lines_tile), LINE_THREADS threads a tile (32 to
//    LINE_GROUP_THREADS, the fewest that leave a thread at most layout::LINE_WORDS words: 32
//    up to 8,192 lights, half the masks' fill's 64 in tile_masks.wgsl, measured faster) and as
//    many tiles as fill a workgroup of LINE_GROUP_THREADS, first computes its tiles' depth data
//    (tile_bounds, tile_depth.wgsl, the code of cull.depth_bounds; the 2.5D mask only for
//    2.5D). Thread `lane` of a tile takes words
//    [lane k, lane k + k) of the tile's mask (k = words / LINE_THREADS, rounded up), ANDs the
//    tile's column and row words and the OR of its depth bins' words (only lights that share a
//    bin with the tile can pass its depth test; skipped for tiles over ZBIN_MAX_SPAN bins), and
//    keeps each candidate whose depth extent passes the tile's depth bounds and 2.5D mask
//    (extent_keeps). Its first two words go together (lines_decide_pair), so that their loads
//    are in flight at once. So the kept bits are those of tile_keeps with the rectangle, as
//    cpu::gather states them (up to rounding in its borderline band). One scan of the threads'
//    bit counts over the tile's threads gives the tile's total and each thread's place in the
//    tile's list. The count pass adds each tile's total to cull_stats[5]; the fill pass places
//    each tile with one atomic add on cull_stats[5] (place_tile; so it too ends holding the
//    total), writes the tile's range, and turns the words into list entries in light order,
//    writing none past the buffer's end (the host checks the total against the buffer's size).
//    A thread keeps its first two words' verdicts in registers and decides any others again
//    for the fill. A tile without covered pixels takes no words and gets an empty range.
//
// Back to back (the host already knows the total, Culler::run_repeated), a run is the two
// passes and no clear (cull.tile_lines zeroes cull_stats[5]). Alone, the count pass runs first
// and the host sizes the lists from its total.
//
// Binding 11 (declared as tile_masks in tile_masks.wgsl) holds the tile lines in these runs.

fn line_word(line: u32, w: u32) -> u32 {
    return tile_masks[line * mask_words() + w];
}

// Light i's depth extent (light_depth_extent), stored after the lines.
fn light_extent(i: u32) -> vec4<f32> {
    let at = (cull.tiles_x + cull.tiles_y + ZBINS) * mask_words() + 8u * i;
    return bitcast<vec4<f32>>(vec4<u32>(tile_masks[at], tile_masks[at + 1u], tile_masks[at + 2u], tile_masks[at + 3u]));
}

// Whether light i's sphere (view-space centre, radius + slack, stored after its extent) meets
// the box `b` (tile_box): tile_keeps' box test, where CULL_FLAG_TILE_BOX asks for it.
fn light_box_keeps(i: u32, b: array<vec3<f32>, 2>) -> bool {
    if !tile_boxes() {
        return true;
    }
    let at = (cull.tiles_x + cull.tiles_y + ZBINS) * mask_words() + 8u * i + 4u;
    let s = bitcast<vec4<f32>>(vec4<u32>(tile_masks[at], tile_masks[at + 1u], tile_masks[at + 2u], tile_masks[at + 3u]));
    return sphere_meets_box(s.xyz, s.w, b);
}


// Word w of tile `tile`'s kept lights; `bins`: the tile's depth bins (first, last).
fn lines_decide(tile: vec2<u32>, w: u32, t: TileDepth, bins: vec2<u32>, b: array<vec3<f32>, 2>) -> u32 {
    var m = line_word(tile.x, w) & line_word(cull.tiles_x + tile.y, w);
    if m != 0u && bins.y - bins.x < ZBIN_MAX_SPAN {
        // The depth bins' prefilter: only lights sharing a bin with the tile can pass its depth
        // test (both bin ranges are monotone images of overlapping intervals).
        var z = 0u;
        for (var b = bins.x; b <= bins.y; b++) {
            z |= line_word(cull.tiles_x + cull.tiles_y + b, w);
        }
        m &= z;
    }
    var keep = 0u;
    while m != 0u {
        let bit = firstTrailingBit(m);
        m &= m - 1u;
        let i = w * 32u + bit;
        if extent_keeps(light_extent(i), t) && light_box_keeps(i, b) {
            keep |= 1u << bit;
        }
    }
    return keep;
}

// Words w and (with `two`) w + 1 of tile `tile`'s kept lights, as lines_decide, with their
// loads side by side: both words' side words, then both words' bin words, then candidates two
// at a time, so that each step's loads of the two words are in flight together.
fn lines_decide_pair(tile: vec2<u32>, w: u32, two: bool, t: TileDepth, bins: vec2<u32>, b: array<vec3<f32>, 2>) -> vec2<u32> {
    let column = tile.x;
    let row = cull.tiles_x + tile.y;
    var m = vec2<u32>(line_word(column, w) & line_word(row, w), 0u);
    if two {
        m.y = line_word(column, w + 1u) & line_word(row, w + 1u);
    }
    if any(m != vec2<u32>(0u)) && bins.y - bins.x < ZBIN_MAX_SPAN {
        var z = vec2<u32>(0u);
        for (var b = bins.x; b <= bins.y; b++) {
            let line = cull.tiles_x + cull.tiles_y + b;
            z.x |= line_word(line, w);
            if two {
                z.y |= line_word(line, w + 1u);
            }
        }
        m &= z;
    }
    var keep = vec2<u32>(0u);
    while any(m != vec2<u32>(0u)) {
        // Up to two candidates: the lowest bits of the first word, then of the second.
        let a0 = m.x != 0u;
        let bit0 = firstTrailingBit(select(m.y, m.x, a0));
        if a0 {
            m.x &= m.x - 1u;
        } else {
            m.y &= m.y - 1u;
        }
        let a1 = m.x != 0u;
        let second = select(m.y, m.x, a1);
        let bit1 = firstTrailingBit(second);
        if second != 0u {
            if a1 {
                m.x &= m.x - 1u;
            } else {
                m.y &= m.y - 1u;
            }
        }
        let i0 = (w + select(1u, 0u, a0)) * 32u + bit0;
        let i1 = select(i0, (w + select(1u, 0u, a1)) * 32u + bit1, second != 0u);
        let e0 = light_extent(i0);
        let e1 = light_extent(i1);
        if extent_keeps(e0, t) && light_box_keeps(i0, b) {
            if a0 {
                keep.x |= 1u << bit0;
            } else {
                keep.y |= 1u << bit0;
            }
        }
        if second != 0u && extent_keeps(e1, t) && light_box_keeps(i1, b) {
            if a1 {
                keep.x |= 1u << bit1;
            } else {
                keep.y |= 1u << bit1;
            }
        }
    }
    return keep;
}

// Threads a tile: each list pass is built once for each of layout::LINE_THREAD_COUNTS, and the
// host takes the one for its light count (layout::line_threads), which also sizes the
// dispatch. An override, so that the divisions by it are by a constant.
override LINE_THREADS: u32 = 32u;

// Tile (LINE_GROUP_THREADS / LINE_THREADS) wg.x + j of row wg.y, LINE_THREADS threads each
// (see the top of this file). Called in uniform control flow.
fn lines_tile(wg: vec2<u32>, slot: u32, fill: bool) {
    let threads = LINE_THREADS;
    let tiles = LINE_GROUP_THREADS / threads;
    let j = slot / threads;
    let lane = slot % threads;
    let tile = vec2<u32>(wg.x * tiles + j, wg.y);
    let inside = tile.x < cull.tiles_x;
    let bin = tile.y * cull.tiles_x + tile.x;
    // The tiles' depth data, computed here (and stored) rather than read from an earlier pass;
    // the 2.5D mask only for 2.5D (gather's tile depth keeps mask 0).
    let t = tile_bounds(vec3<u32>(wg, 0u), slot, (cull.flags & CULL_FLAG_DEPTH_MASK) != 0u, tiles, threads);
    var words = 0u;
    var bins = vec2<u32>(0u);
    if inside && t.covered != 0u {
        words = mask_words();
        bins = vec2<u32>(zbin(t.dmin), zbin(t.dmax));
    }
    // The tile's box for the box test, once a thread.
    let b = tile_test_box(tile, t);
    let k = (mask_words() + threads - 1u) / threads;
    let first = min(lane * k, words);
    let end = min(lane * k + k, words);
    var w0 = 0u;
    var w1 = 0u;
    var c = 0u;
    if first < end {
        let d = lines_decide_pair(tile, first, first + 1u < end, t, bins, b);
        w0 = d.x;
        w1 = d.y;
        c = countOneBits(d.x) + countOneBits(d.y);
    }
    for (var w = first + 2u; w < end; w++) {
        c += countOneBits(lines_decide(tile, w, t, bins, b));
    }
    let scan = scan_keep_n(slot, c, threads);
    if !fill {
        if lane == 0u && scan.y != 0u {
            atomicAdd(&cull_stats[5], scan.y);
        }
        return;
    }
    let at = place_tile(lane, j, bin, scan.y, inside);
    if c == 0u {
        return;
    }
    var pos = at + scan.x - c;
    let cap = arrayLength(&out_indices);
    for (var w = first; w < end; w++) {
        var m: u32;
        if w == first {
            m = w0;
        } else if w == first + 1u {
            m = w1;
        } else {
            m = lines_decide(tile, w, t, bins, b);
        }
        let light = w * 32u;
        while m != 0u {
            if pos < cap {
                out_indices[pos] = light + firstTrailingBit(m);
            }
            m &= m - 1u;
            pos += 1u;
        }
    }
}
