// cull.tiled_gather.lists and cull.depth_mask.lists: gather and 2.5D with tile masks in one
// pass after cull.depth_bounds, a workgroup of LISTS_THREADS (256) threads a coarse tile (8 x 8
// tiles), four threads a tile (tile slot / 4, quarter slot % 4), over every light: no chunks
// of lights, so a workgroup owns its tiles' masks from start to end, and places and writes its
// tiles' lists itself. No count pass, no fill pass, and one atomic add a coarse tile to place
// its lists, not one a tile.
//
// 1. Candidates: windows of LISTS_WINDOW lights, LISTS_RECTS a thread, in light order; the
//    lights whose rectangle (from cull.depth_bounds) meets the coarse tile go, compacted by a
//    workgroup scan and still in light order, into a ring (wl_cand) of candidates.
// 2. Batches of LISTS_BATCH candidates, taken as soon as a batch is full (and the rest after
//    the last window): as in the count pass of tiled_gather.wgsl, a thread a candidate tests
//    the coarse tile's depth slab, transforms the light once into workgroup memory and marks
//    the lines (the coarse tile's columns and rows) its rectangle spans; then each tile's
//    quarter q tests, against its tile (tile_keeps), the candidates at slots 32 q .. 32 q + 31
//    whose bit is in both its column and its row, and sets the bits of those kept in the tile's
//    mask (tile_masks.wgsl), a word at a time with atomicOr, as two quarters may share a word.
// 3. Lists: a quarter's part of its tile's mask is a quarter of its words (light order), so one
//    workgroup scan of the quarters' bit counts gives each quarter its place among the coarse
//    tile's lists (tile by tile, in light order within each), and their total; one atomic add
//    (cull_stats[5]) places the coarse tile's lists in the list buffer. Each tile writes its
//    range, and each quarter turns its words into list entries, clearing each nonzero word: the
//    masks are zero again, as the next run needs. Where the list buffer is too short
//    (the host's sizing run, before it knows the total) nothing is written, but the total is
//    still summed, and the host reads it.
//
// A tile's list is the same as the count and fill passes give (and cpu::gather states): the
// lights whose rectangle holds the tile and that pass its tile test; the coarse tests only skip
// lights that would fail those.

// The ring of candidates (light indices), LISTS_RING entries, a power of two: at most
// LISTS_BATCH - 1 wait from one window when the next adds up to LISTS_WINDOW.
var<workgroup> wl_cand: array<u32, LISTS_RING>;
// A batch's lights (those that reach the coarse tile's depth slab), at their slots.
var<workgroup> wl_light: array<CullLight, LISTS_BATCH>;
// Two sets of a batch's lines, LISTS_LINE_WORDS words a line: word w of line c of a set has bit
// k set for the batch's candidate at slot 32 w + k when its rectangle spans column c of the
// coarse tile (c < 8), or row c - 8 (c >= 8).
var<workgroup> wl_lines: array<atomic<u32>, 32 * LISTS_LINE_WORDS>;
// The four 64-slot segments' totals of a workgroup scan, its total, and the lists' place.
var<workgroup> wl_seg: array<u32, 4>;
var<workgroup> wl_total: u32;
var<workgroup> wl_base: u32;

// (exclusive prefix of `value` over the workgroup's 256 slots, total): scan_keep over each 64
// slots, then the segments' totals. The total is uniform (workgroupUniformLoad), so that loops
// over it may hold barriers. Called in uniform control flow.
fn scan_lists(slot: u32, value: u32) -> vec2<u32> {
    let r = scan_keep(slot, value);
    if slot % 64u == 63u {
        wl_seg[slot / 64u] = r.y;
    }
    workgroupBarrier();
    var before = r.x - value;
    var total = 0u;
    for (var s = 0u; s < 4u; s++) {
        let v = wl_seg[s];
        if s < slot / 64u {
            before += v;
        }
        total += v;
    }
    if slot == 0u {
        wl_total = total;
    }
    return vec2<u32>(before, workgroupUniformLoad(&wl_total));
}

// Light `i`'s rectangle less `origin` (the coarse tile's first tile), clipped to the coarse
// tile: empty where lo > hi.
fn coarse_span(i: u32, origin: vec2<i32>) -> vec4<i32> {
    let packed = light_rects[i];
    let rect = vec4<i32>(vec4<u32>(packed.x & 0xffffu, packed.x >> 16u, packed.y & 0xffffu, packed.y >> 16u)) - origin.xyxy;
    return vec4<i32>(max(rect.xy, vec2<i32>(0)), min(rect.zw, vec2<i32>(7)));
}

// Light i's bit in the tile's mask (its first word at `first`), gathered into `word` (the
// word at index `at`), which goes to the masks when the next bit is in another word.
fn set_mask_bit(first: u32, i: u32, at: ptr<function, u32>, word: ptr<function, u32>) {
    let w = first + i / 32u;
    if w != *at {
        if *word != 0u {
            atomicOr(&tile_masks[*at], *word);
        }
        *at = w;
        *word = 0u;
    }
    *word |= 1u << (i % 32u);
}

// One batch: candidates head .. head + n of the ring, into the masks of the tiles that keep
// them. `lines_at` (0 or 16 LISTS_LINE_WORDS) is this batch's set of lines; the other is cleared
// for the next. Called in uniform control flow.
fn lists_batch(slot: u32, head: u32, n: u32, lines_at: u32, origin: vec2<i32>, cmin: f32, cmax: f32, local: vec2<u32>, quarter: u32, bin: u32, has_pixels: bool, planes: array<vec4<f32>, 4>, t: TileDepth) {
    var spans = 0u;
    if slot < n {
        let i = wl_cand[(head + slot) % LISTS_RING];
        let s = coarse_span(i, origin);
        let l = cull_light(lights[i]);
        if !outside_plane(vec4<f32>(0.0, 0.0, -1.0, -cmin), l) && !outside_plane(vec4<f32>(0.0, 0.0, 1.0, cmax), l) {
            wl_light[slot] = l;
            // Bits lo..=hi of the columns (0..7) and of the rows (8..15).
            let span = (vec2<u32>(0xffu) << vec2<u32>(s.xy)) & (vec2<u32>(0xffu) >> vec2<u32>(7 - s.zw));
            spans = span.x | (span.y << 8u);
        }
    }
    mark_lines_lists(slot, spans, lines_at);
    workgroupBarrier();
    let other = (16u * LISTS_LINE_WORDS) ^ lines_at;
    if slot < 16u * LISTS_LINE_WORDS {
        atomicStore(&wl_lines[other + slot], 0u);
    }
    if has_pixels && quarter < LISTS_LINE_WORDS {
        var m = atomicLoad(&wl_lines[lines_at + LISTS_LINE_WORDS * local.x + quarter]) & atomicLoad(&wl_lines[lines_at + LISTS_LINE_WORDS * (8u + local.y) + quarter]);
        let words = mask_words();
        // The word being gathered (its index in the masks) and its bits; candidates come in
        // light order, so a quarter's kept lights in one word are set together.
        var at = 0xffffffffu;
        var word = 0u;
        // Two candidates at a time, their tests overlapping (tile_keeps has no branches).
        while m != 0u {
            let b0 = firstTrailingBit(m);
            m &= m - 1u;
            let two = m != 0u;
            let b1 = select(b0, firstTrailingBit(m), two);
            m &= m - 1u;
            let k0 = 32u * quarter + b0;
            let k1 = 32u * quarter + b1;
            let keep0 = tile_keeps(wl_light[k0], planes, t);
            let keep1 = two & tile_keeps(wl_light[k1], planes, t);
            if keep0 {
                set_mask_bit(bin * words, wl_cand[(head + k0) % LISTS_RING], &at, &word);
            }
            if keep1 {
                set_mask_bit(bin * words, wl_cand[(head + k1) % LISTS_RING], &at, &word);
            }
        }
        if word != 0u {
            atomicOr(&tile_masks[at], word);
        }
    }
    workgroupBarrier();
}

// Coarse tile wg (see the top of this file).
fn gather_lists(wg: vec2<u32>, slot: u32) {
    let j = slot / 4u;
    let quarter = slot % 4u;
    if slot == 0u {
        atomicStore(&wg_cmin, 0xffffffffu);
        atomicStore(&wg_cmax, 0u);
        atomicStore(&wg_ccov, 0u);
    }
    if slot < 32u * LISTS_LINE_WORDS {
        atomicStore(&wl_lines[slot], 0u);
    }
    workgroupBarrier();
    let local = vec2<u32>(j % 8u, j / 8u);
    let tile = wg * 8u + local;
    let inside = tile.x < cull.tiles_x && tile.y < cull.tiles_y;
    let bin = tile.y * cull.tiles_x + tile.x;
    var t: TileDepth;
    var planes: array<vec4<f32>, 4>;
    if inside {
        t = tile_depth[bin];
        if t.covered != 0u {
            if quarter == 0u {
                atomicMin(&wg_cmin, ordered_bits(t.dmin));
                atomicMax(&wg_cmax, ordered_bits(t.dmax));
                atomicAdd(&wg_ccov, t.covered);
            }
            planes = tile_side_planes(tile);
        }
    }
    workgroupBarrier();
    if slot == 0u {
        wg_covered = atomicLoad(&wg_ccov);
    }
    // Uniform, so the barriers below are reached by all threads or none. (Tiles without
    // pixels keep the empty ranges they start with.)
    if workgroupUniformLoad(&wg_covered) == 0u {
        return;
    }
    let cmin = from_ordered_bits(atomicLoad(&wg_cmin));
    let cmax = from_ordered_bits(atomicLoad(&wg_cmax));
    let origin = vec2<i32>(wg * 8u);
    let has_pixels = inside && t.covered != 0u;

    // 1 and 2: candidates, then batches.
    var head = 0u;
    var pending = 0u;
    var lines_at = 0u;
    for (var w0 = 0u; w0 < cull.light_count; w0 += LISTS_WINDOW) {
        let first = w0 + LISTS_RECTS * slot;
        var hits = 0u;
        for (var r = 0u; r < LISTS_RECTS; r++) {
            if first + r < cull.light_count {
                let s = coarse_span(first + r, origin);
                if all(s.xy <= s.zw) {
                    hits |= 1u << r;
                }
            }
        }
        let scan = scan_lists(slot, countOneBits(hits));
        var at = head + pending + scan.x;
        for (var r = 0u; r < LISTS_RECTS; r++) {
            if ((hits >> r) & 1u) != 0u {
                wl_cand[at % LISTS_RING] = first + r;
                at += 1u;
            }
        }
        pending += scan.y;
        workgroupBarrier();
        let last = w0 + LISTS_WINDOW >= cull.light_count;
        while pending >= LISTS_BATCH || (last && pending > 0u) {
            let n = min(pending, LISTS_BATCH);
            lists_batch(slot, head, n, lines_at, origin, cmin, cmax, local, quarter, bin, has_pixels, planes, t);
            head = (head + n) % LISTS_RING;
            pending -= n;
            lines_at ^= 16u * LISTS_LINE_WORDS;
        }
    }

    // 3: the lists. The masks' words set by other threads are visible after the barrier.
    storageBarrier();
    workgroupBarrier();
    let words = mask_words();
    let per = (words + 3u) / 4u;
    let w_first = bin * words + min(quarter * per, words);
    let w_end = bin * words + min(quarter * per + per, words);
    var c = 0u;
    if inside {
        for (var w = w_first; w < w_end; w++) {
            c += countOneBits(atomicLoad(&tile_masks[w]));
        }
    }
    let scan = scan_lists(slot, c);
    // Each quarter's place among the coarse tile's lists, in the ring (free now): a tile's
    // count is the next tile's place less its own.
    wl_cand[slot] = scan.x;
    if slot == 0u {
        var base = 0u;
        if scan.y != 0u {
            base = atomicAdd(&cull_stats[5], scan.y);
        }
        wl_base = base;
    }
    let base = workgroupUniformLoad(&wl_base);
    if !inside {
        return;
    }
    if quarter == 0u {
        var next = scan.y;
        if slot + 4u < LISTS_THREADS {
            next = wl_cand[slot + 4u];
        }
        out_ranges[bin] = vec2<u32>(base + scan.x, next - scan.x);
    }
    if c == 0u {
        return;
    }
    let fits = base + scan.y <= arrayLength(&out_indices);
    var pos = base + scan.x;
    for (var w = w_first; w < w_end; w++) {
        var m = atomicLoad(&tile_masks[w]);
        if m != 0u {
            atomicStore(&tile_masks[w], 0u);
            let light = (w - bin * words) * 32u;
            while m != 0u {
                if fits {
                    out_indices[pos] = light + firstTrailingBit(m);
                }
                m &= m - 1u;
                pos += 1u;
            }
        }
    }
}
