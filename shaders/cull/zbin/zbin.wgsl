// cull.zbin: z-binning with tile bitmasks (Drobot, "Improved Culling for Tiled and Clustered
// Rendering", SIGGRAPH 2017 Advances, as Call of Duty: Infinite Warfare ships it; Unity URP's
// Forward+). The lists are not per bin: the lights are sorted by view depth, each depth bin
// holds the range of sorted lights that reach it, and each tile a bit per sorted light; a pixel
// reads its tile's bits within its depth bin's range (lookup.wgsl, zbin_cell). The passes:
//
// 1. cull.depth_bounds (the tiles' depth) with the lights' tile rectangles.
// 2. cull.zbin.keys: a thread a light, its sort key (the depth bin of its centre, in 64 sub-bins
//    a bin) and its index.
// 3. The radix sort: light_indices[0 .. light_count) holds the lights in depth order.
// 4. cull.zbin.bins: a thread a sorted light widens the range (first, end) of every bin its
//    depth extent touches; a workgroup's lights, neighbours in depth, first reduce theirs in
//    workgroup memory.
// 5. The masks, by one of two paths that set the same bits: sorted light k's bit in a tile is
//    set when k lies within the tile's cover (the union of the ranges of the bins of its depth
//    bounds, one bin of margin either side), its rectangle holds the tile and gather's tile test
//    keeps it (tile_keeps).
//    - Gather: cull.zbin.masks, a workgroup a tile, tests every sorted light of its cover and
//      writes its whole mask (zero outside the cover), so the masks need no clear. Its work
//      grows as tiles x the lights of a cover (docs/bench/HISTORY.md has its time at 1M lights).
//    - Scatter (many lights): cull.zbin.covers, a workgroup a tile, stores its cover and zeroes
//      its mask; then cull.zbin.scatter (zbin_scatter.wgsl) sets each light's bit in the tiles
//      of its rectangle: work as the (light, tile) pairs.
//
// Group 1 here: 2 the tiles' depth, 6 bin_ranges as (~first, end) words widened atomically
// (cleared before each run; an untouched bin reads (0, 0), empty), 7 light_indices (the sorted
// lights, then the masks), 9 the sort keys (cull.zbin.keys) or the lights' tile rectangles
// (cull.zbin.masks, as cull.depth_bounds stores them), 11 the tiles' covers (first, end; the
// scatter path).
@group(1) @binding(2) var<storage, read_write> tile_depth: array<TileDepth>;
@group(1) @binding(6) var<storage, read_write> zbin_ranges: array<atomic<u32>>;
@group(1) @binding(7) var<storage, read_write> zbin_lists: array<u32>;
@group(1) @binding(9) var<storage, read_write> zbin_aux: array<u32>;
@group(1) @binding(11) var<storage, read_write> zbin_covers: array<u32>;

// Sub-bins of a depth bin in the sort keys.
const ZBIN_KEY_SUB: u32 = 64u;
// Bins a workgroup of cull.zbin.ranges reduces in workgroup memory.
const ZBIN_LOCAL: u32 = 256u;

// Words of a tile's mask.
fn zbin_mask_words() -> u32 {
    return (cull.light_count + 31u) / 32u;
}

// A thread a light: its key (the sub-bin of its centre's depth, depth_slice's coordinate times
// ZBIN_KEY_SUB) and itself as the value.
@compute @workgroup_size(64)
fn zbin_keys(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * GROUPS_X * 64u + id.x;
    if i >= cull.light_count {
        return;
    }
    let d = -cull_light(lights[i]).center.z;
    var s: f32;
    if cull.slicing == SLICING_EXPONENTIAL {
        s = log(max(d, cull.near) / cull.near) * cull.slice_scale;
    } else {
        s = (d - cull.near) * cull.slice_scale;
    }
    zbin_aux[i] = u32(clamp(floor(s * f32(ZBIN_KEY_SUB)), 0.0, f32(cull.slices * ZBIN_KEY_SUB - 1u)));
    zbin_lists[i] = i;
}

var<workgroup> wg_span: array<atomic<u32>, 2>;
var<workgroup> wg_span_plain: vec2<u32>;
var<workgroup> wg_first: array<atomic<u32>, ZBIN_LOCAL>;
var<workgroup> wg_end: array<atomic<u32>, ZBIN_LOCAL>;

// Widens bin b's range by sorted light k: (~first, end), both by atomicMax.
fn widen(b: u32, k: u32) {
    atomicMax(&zbin_ranges[2u * b], ~k);
    atomicMax(&zbin_ranges[2u * b + 1u], k + 1u);
}

// A thread a sorted light: the bins of its depth extent (light_depth_extent, as gather's lines
// path has it; a cone's narrowed extent may be empty, lo > hi, and then the bins between count)
// take it into their ranges. Lights wholly beyond the far plane reach no bin.
@compute @workgroup_size(64)
fn zbin_bins(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let k = (wg.y * GROUPS_X + wg.x) * 64u + li;
    if li == 0u {
        atomicStore(&wg_span[0], 0xffffffffu);
        atomicStore(&wg_span[1], 0u);
    }
    for (var j = li; j < ZBIN_LOCAL; j += 64u) {
        atomicStore(&wg_first[j], 0u);
        atomicStore(&wg_end[j], 0u);
    }
    workgroupBarrier();
    var b0 = 1u;
    var b1 = 0u;
    if k < cull.light_count {
        let e = light_depth_extent(cull_light(lights[zbin_lists[k]]));
        let lo = min(e.x, e.y);
        if lo <= cull.far {
            b0 = depth_slice(lo);
            b1 = depth_slice(max(e.x, e.y));
            atomicMin(&wg_span[0], b0);
            atomicMax(&wg_span[1], b1);
        }
    }
    workgroupBarrier();
    if li == 0u {
        wg_span_plain = vec2<u32>(atomicLoad(&wg_span[0]), atomicLoad(&wg_span[1]));
    }
    let span = workgroupUniformLoad(&wg_span_plain);
    // Neighbours in depth share bins: where the workgroup's bins fit workgroup memory, one
    // global widening a bin, not one a light and bin.
    let local = span.x <= span.y && span.y - span.x < ZBIN_LOCAL;
    for (var b = b0; b <= b1; b++) {
        if local {
            atomicMax(&wg_first[b - span.x], ~k);
            atomicMax(&wg_end[b - span.x], k + 1u);
        } else {
            widen(b, k);
        }
    }
    if !local {
        return;
    }
    workgroupBarrier();
    for (var j = li; j <= span.y - span.x; j += 64u) {
        let end = atomicLoad(&wg_end[j]);
        if end != 0u {
            atomicMax(&zbin_ranges[2u * (span.x + j)], atomicLoad(&wg_first[j]));
            atomicMax(&zbin_ranges[2u * (span.x + j) + 1u], end);
        }
    }
}

var<workgroup> wg_planes: array<vec4<f32>, 4>;
var<workgroup> wg_box: array<vec3<f32>, 2>;
var<workgroup> wg_keys: array<atomic<u32>, 2>;
var<workgroup> wg_keys_plain: vec2<u32>;
var<workgroup> wg_words: array<atomic<u32>, 64>;

// The sorted lights a tile's pixels may read: the union of the ranges of the bins of its depth
// bounds, a bin of margin either side (a pixel's bin comes from its own depth, which rounding
// may put a bin past the tile's bounds). (first, end); empty for an uncovered tile.
fn tile_keys(td: TileDepth, li: u32) -> vec2<u32> {
    if li == 0u {
        atomicStore(&wg_keys[0], 0u);
        atomicStore(&wg_keys[1], 0u);
    }
    workgroupBarrier();
    if td.covered != 0u {
        let b0 = max(depth_slice(td.dmin), 1u) - 1u;
        let b1 = min(depth_slice(td.dmax) + 1u, cull.slices - 1u);
        for (var b = b0 + li; b <= b1; b += 64u) {
            let end = atomicLoad(&zbin_ranges[2u * b + 1u]);
            if end != 0u {
                atomicMax(&wg_keys[0], atomicLoad(&zbin_ranges[2u * b]));
                atomicMax(&wg_keys[1], end);
            }
        }
    }
    workgroupBarrier();
    if li == 0u {
        wg_keys_plain = vec2<u32>(~atomicLoad(&wg_keys[0]), atomicLoad(&wg_keys[1]));
    }
    return workgroupUniformLoad(&wg_keys_plain);
}

// Whether sorted light k may reach tile `tile`: its rectangle holds the tile and gather's tile
// test keeps it.
fn zbin_keeps(k: u32, tile: vec2<u32>, td: TileDepth) -> bool {
    let i = zbin_lists[k];
    let r0 = zbin_aux[2u * i];
    let r1 = zbin_aux[2u * i + 1u];
    if tile.x < (r0 & 0xffffu) || tile.x > (r1 & 0xffffu) || tile.y < (r0 >> 16u) || tile.y > (r1 >> 16u) {
        return false;
    }
    let planes = array<vec4<f32>, 4>(wg_planes[0], wg_planes[1], wg_planes[2], wg_planes[3]);
    return tile_keeps(cull_light(lights[i]), planes, array<vec3<f32>, 2>(wg_box[0], wg_box[1]), td);
}

// A workgroup a tile: its mask, 64 words (2,048 sorted lights) a round, the kept lights' bits
// set in workgroup memory and each word stored once.
@compute @workgroup_size(64)
fn zbin_masks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let t = wg.y * GROUPS_X + wg.x;
    if t >= cull.tiles_x * cull.tiles_y {
        return;
    }
    let tile = vec2<u32>(t % cull.tiles_x, t / cull.tiles_x);
    let td = tile_depth[t];
    if li == 0u {
        let p = tile_side_planes(tile);
        wg_planes[0] = p[0];
        wg_planes[1] = p[1];
        wg_planes[2] = p[2];
        wg_planes[3] = p[3];
        let b = tile_test_box(tile, td);
        wg_box[0] = b[0];
        wg_box[1] = b[1];
    }
    let keys = tile_keys(td, li);
    let words = zbin_mask_words();
    let base = cull.light_count + t * words;
    for (var c = 0u; c < words; c += 64u) {
        let k0 = max(c * 32u, keys.x);
        let k1 = min(c * 32u + 2048u, keys.y);
        if k0 >= k1 {
            // No light of this round within the tile's ranges.
            if c + li < words {
                zbin_lists[base + c + li] = 0u;
            }
            continue;
        }
        atomicStore(&wg_words[li], 0u);
        workgroupBarrier();
        for (var k = k0 + li; k < k1; k += 64u) {
            if zbin_keeps(k, tile, td) {
                atomicOr(&wg_words[k / 32u - c], 1u << (k % 32u));
            }
        }
        workgroupBarrier();
        if c + li < words {
            zbin_lists[base + c + li] = atomicLoad(&wg_words[li]);
        }
    }
}

// The scatter path's first pass, a workgroup a tile: its cover (first, end; empty, first >=
// end, for an uncovered tile) for cull.zbin.scatter, and its mask zeroed where bits may be set:
// the words of this run's cover and of the run's before (read from zbin_covers before it is
// overwritten; zero, empty, in a new buffer). Every set bit lies within its run's cover, so
// the mask is then all zero (a frame's buffers start zeroed), at the cost of the covers' words,
// not the whole mask's.
@compute @workgroup_size(256)
fn zbin_covers_pass(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let t = wg.y * GROUPS_X + wg.x;
    if t >= cull.tiles_x * cull.tiles_y {
        return;
    }
    let old = vec2<u32>(zbin_covers[2u * t], zbin_covers[2u * t + 1u]);
    // (tile_keys' loops step by 64 threads; the threads past 64 repeat their bins' atomicMax.)
    let keys = tile_keys(tile_depth[t], li);
    if li == 0u {
        zbin_covers[2u * t] = keys.x;
        zbin_covers[2u * t + 1u] = keys.y;
    }
    var first = 0xffffffffu;
    var end = 0u;
    if old.x < old.y {
        first = old.x;
        end = old.y;
    }
    if keys.x < keys.y {
        first = min(first, keys.x);
        end = max(end, keys.y);
    }
    let base = cull.light_count + t * zbin_mask_words();
    for (var w = first / 32u + li; w < (end + 31u) / 32u; w += 256u) {
        zbin_lists[base + w] = 0u;
    }
}
