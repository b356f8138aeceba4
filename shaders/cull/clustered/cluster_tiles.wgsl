// cull.clustered.tiles_count / tiles_fill: the clusters' lists a workgroup a tile, for runs of
// few lights (at most Culler::cluster_tiles_max_lights) and at most CLUSTER_TILE_SLICES slices.
// With few lights, the per-light passes (clustered.wgsl) leave most of the GPU idle and pay for
// what surrounds them: an occupancy pass, a queue of wide lights and its indirect dispatches,
// global atomics on the clusters' counters (every light of a cluster adds to the same word), and
// order passes. Here a workgroup takes one tile:
//
// 1. Each thread reduces some of the tile's pixels to the depth bounds of each slice they fall
//    in (nothing for slices without pixels), as cull.occupancy does for the whole screen.
// 2. Thread s of the first CLUSTER_TILE_SLICES owns slice s: the tile's cluster there, and
//    (with the box test) the box of the tile's frustum between that cluster's pixel depths,
//    computed once into workgroup memory; the slices that may hold lights are listed.
// 3. The lights, CLUSTER_TILE_THREADS at a time: each thread takes one and, when its tile
//    rectangle holds the tile and it passes the tile's side planes (light_rect and tile_holds,
//    as the per-light passes), appends it to the batch's candidates. The threads then share the
//    (candidate, listed slice) pairs: a pair within the light's slices whose cluster keeps it
//    sets the light's bit in the slice's mask. Last, each slice's thread counts its mask (count
//    pass) or writes its lights in light order, bit by bit (fill pass), and clears it.
//
// The lists are exactly the per-light passes' (the same tests on the same floats) and already
// in light order, so neither cull.occupancy nor the order passes run, and each cluster's count
// is stored, not added. The count pass also stores the occupancy words cull.occupancy would.

// CLUSTER_TILE_SLICES (from the host) of the workgroup's CLUSTER_TILE_THREADS threads own a
// slice each.
const CLUSTER_TILE_THREADS: u32 = 256u;
const CLUSTER_TILE_WORDS: u32 = CLUSTER_TILE_THREADS / 32u;

// Each slice's pixel depths in this tile, as the occupancy buffer keeps them:
// (~ordered_bits(dmin), ordered_bits(dmax)), widened with atomicMax from zero (zero: no pixel).
var<workgroup> wg_slice_near: array<atomic<u32>, CLUSTER_TILE_SLICES>;
var<workgroup> wg_slice_far: array<atomic<u32>, CLUSTER_TILE_SLICES>;
// The listed slices (those holding pixels, or all without the pixels' test), and each one's
// depths and box (lo, hi).
var<workgroup> wg_slices: array<u32, CLUSTER_TILE_SLICES>;
var<workgroup> wg_slice_count: atomic<u32>;
var<workgroup> wg_slice_depth: array<vec2<f32>, CLUSTER_TILE_SLICES>;
var<workgroup> wg_slice_box: array<array<vec3<f32>, 2>, CLUSTER_TILE_SLICES>;
// A batch's candidates (in any order) with their slot and slices (slot | s0 << 8 | s1 << 16),
// and their count.
var<workgroup> wg_cand: array<CullLight, CLUSTER_TILE_THREADS>;
var<workgroup> wg_cand_info: array<u32, CLUSTER_TILE_THREADS>;
var<workgroup> wg_cand_count: atomic<u32>;
// Each slice's mask of the batch: bit k of word w for the light at slot 32 w + k.
var<workgroup> wg_slice_mask: array<atomic<u32>, CLUSTER_TILE_SLICES * CLUSTER_TILE_WORDS>;

fn widen_slice(s: u32, near: u32, far: u32) {
    if far != 0u {
        atomicMax(&wg_slice_near[s], near);
        atomicMax(&wg_slice_far[s], far);
    }
}

// Step 1: this thread's pixels of the tile, reduced per slice (a run of pixels in the same
// slice is widened into workgroup memory once).
fn slice_bounds(tile: vec2<u32>, li: u32) {
    let size = vec2<u32>(frame.viewport.xy);
    let origin = tile * cull.tile_size;
    let tiles = cull.tiles_x * cull.tiles_y;
    var cur = 0u;
    var near = 0u;
    var far = 0u;
    for (var i = li; i < cull.tile_size * cull.tile_size; i += CLUSTER_TILE_THREADS) {
        let p = origin + vec2<u32>(i % cull.tile_size, i / cull.tile_size);
        if all(p < size) {
            let z = textureLoad(depth_tex, p, 0);
            if z < 1.0 {
                let s = bin_of(p, z) / tiles;
                let d = ordered_bits(linear_depth(z));
                if s != cur {
                    widen_slice(cur, near, far);
                    cur = s;
                    near = 0u;
                    far = 0u;
                }
                near = max(near, ~d);
                far = max(far, d);
            }
        }
    }
    widen_slice(cur, near, far);
}

// Step 2, by thread s < CLUSTER_TILE_SLICES: slice s's cluster, listed if it may hold lights;
// with `fill`, the cluster's offset, returned; otherwise the occupancy words stored.
fn slice_setup(tile: vec2<u32>, s: u32, pixels: bool, fill: bool) -> u32 {
    if s >= cull.slices {
        return 0u;
    }
    let bin = s * cull.tiles_x * cull.tiles_y + tile.y * cull.tiles_x + tile.x;
    var listed = true;
    if pixels {
        let near = atomicLoad(&wg_slice_near[s]);
        let far = atomicLoad(&wg_slice_far[s]);
        listed = far != 0u;
        var t: TileDepth;
        t.dmin = from_ordered_bits(~near);
        t.dmax = from_ordered_bits(far);
        wg_slice_depth[s] = vec2<f32>(t.dmin, t.dmax);
        if listed && tile_boxes() {
            wg_slice_box[s] = tile_box(tile, t);
        }
        if !fill {
            // The occupancy buffer as cull.occupancy leaves it, for those who read it back
            // (every word stored: it is not cleared on this path).
            let bounds = select(vec2<u32>(0u), vec2<u32>(near, far), tile_boxes());
            atomicStore(&occupancy[bin], u32(listed));
            atomicStore(&occupancy[cull.bins + 2u * bin], bounds.x);
            atomicStore(&occupancy[cull.bins + 2u * bin + 1u], bounds.y);
        }
    }
    if listed {
        wg_slices[atomicAdd(&wg_slice_count, 1u)] = s;
    }
    for (var w = 0u; w < CLUSTER_TILE_WORDS; w++) {
        atomicStore(&wg_slice_mask[s * CLUSTER_TILE_WORDS + w], 0u);
    }
    if fill && listed {
        return bin_offsets[bin];
    }
    return 0u;
}

// Whether listed slice s's cluster keeps candidate c (with slices `info`).
fn cluster_keeps(c: u32, info: u32, s: u32) -> bool {
    if s < ((info >> 8u) & 0xffu) || s > (info >> 16u) {
        return false;
    }
    if !tile_boxes() {
        return true;
    }
    let l = wg_cand[c];
    var t: TileDepth;
    let d = wg_slice_depth[s];
    t.dmin = d.x;
    t.dmax = d.y;
    t.mask = 0u;
    t.covered = 1u;
    return depth_keeps(l, t) && sphere_meets_box(l.center, l.radius + l.slack, wg_slice_box[s]);
}

// The whole of a workgroup's tile (see the top of this file). Called in uniform control flow.
fn cluster_tile(tile: vec2<u32>, li: u32, fill: bool) {
    if li < CLUSTER_TILE_SLICES {
        atomicStore(&wg_slice_near[li], 0u);
        atomicStore(&wg_slice_far[li], 0u);
    }
    if li == 0u {
        atomicStore(&wg_slice_count, 0u);
        atomicStore(&wg_cand_count, 0u);
    }
    workgroupBarrier();
    let pixels = (cull.flags & (CULL_FLAG_SKIP_EMPTY | CULL_FLAG_TILE_BOX)) != 0u;
    if pixels {
        slice_bounds(tile, li);
    }
    workgroupBarrier();
    // Step 2.
    var at = 0u;
    if li < CLUSTER_TILE_SLICES {
        at = slice_setup(tile, li, pixels, fill);
    }
    workgroupBarrier();
    let slices = atomicLoad(&wg_slice_count);
    let own = li < cull.slices && li < CLUSTER_TILE_SLICES;
    // Step 3: the lights.
    let here = vec2<i32>(tile);
    var kept = 0u;
    for (var first = 0u; first < cull.light_count; first += CLUSTER_TILE_THREADS) {
        let i = first + li;
        if i < cull.light_count {
            let r = light_rect(i);
            if r.count != 0u && all(here >= r.rect.xy) && all(here <= r.rect.zw) && tile_holds(tile, r.l) {
                let c = atomicAdd(&wg_cand_count, 1u);
                wg_cand[c] = r.l;
                wg_cand_info[c] = li | (r.s0 << 8u) | (r.s1 << 16u);
            }
        }
        workgroupBarrier();
        let n = atomicLoad(&wg_cand_count);
        for (var p = li; p < n * slices; p += CLUSTER_TILE_THREADS) {
            let c = p % n;
            let s = wg_slices[p / n];
            let info = wg_cand_info[c];
            if cluster_keeps(c, info, s) {
                let slot = info & 0xffu;
                atomicOr(&wg_slice_mask[s * CLUSTER_TILE_WORDS + slot / 32u], 1u << (slot % 32u));
            }
        }
        workgroupBarrier();
        if own {
            for (var w = 0u; w < CLUSTER_TILE_WORDS; w++) {
                var m = atomicLoad(&wg_slice_mask[li * CLUSTER_TILE_WORDS + w]);
                if m == 0u {
                    continue;
                }
                atomicStore(&wg_slice_mask[li * CLUSTER_TILE_WORDS + w], 0u);
                if !fill {
                    kept += countOneBits(m);
                    continue;
                }
                while m != 0u {
                    if cull.capacity == 0u || kept < cull.capacity {
                        out_indices[at + kept] = first + 32u * w + firstTrailingBit(m);
                    }
                    m &= m - 1u;
                    kept += 1u;
                }
            }
        }
        if li == 0u {
            atomicStore(&wg_cand_count, 0u);
        }
        workgroupBarrier();
    }
    if !fill && own {
        let bin = li * cull.tiles_x * cull.tiles_y + tile.y * cull.tiles_x + tile.x;
        atomicStore(&bin_counts[bin], kept);
    }
}

@compute @workgroup_size(256)
fn cluster_tiles_count(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    cluster_tile(wg.xy, li, false);
}

@compute @workgroup_size(256)
fn cluster_tiles_fill(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    cluster_tile(wg.xy, li, true);
}
