// cull.clustered.tiles_count / masks_fill: the clusters' lists a workgroup a tile, for runs of
// few lights (Culler::cluster_tiles_max_lights, CLUSTER_TILES_MAX_PAIRS and the mask budget) and
// at most CLUSTER_TILE_SLICES slices. With few lights, the per-light passes (clustered.wgsl)
// leave most of the GPU idle and pay for what surrounds them: an occupancy pass, a queue of
// wide lights and its indirect dispatches, global atomics on the clusters' counters (every
// light of a cluster adds to the same word), and order passes. Here a workgroup of the count
// pass takes one tile:
//
// 1. Each thread reduces some of the tile's pixels to the depth bounds of each slice they fall
//    in (nothing for slices without pixels), as cull.occupancy does for the whole screen.
// 2. Thread s of the first CLUSTER_TILE_SLICES owns slice s: the tile's cluster there, and
//    (with the box test) the box of the tile's frustum between that cluster's pixel depths,
//    computed once into workgroup memory; the slices that may hold lights are listed.
// 3. The lights, CLUSTER_TILE_THREADS at a time: each thread takes one and, when its tile
//    rectangle holds the tile and it passes the tile's side planes (light_rect's rectangle, or
//    cull.clustered.rects' where it ran, and the planes of tile_holds, built once), appends it
//    to the batch's candidates. The threads
//    then share the (candidate, listed slice) pairs: a pair within the light's slices whose
//    cluster keeps it sets the light's bit in the slice's mask. Last, each listed slice's
//    thread stores its mask's words, counts them and clears them.
//
// Then the scan, and masks_fill: a thread a cluster writes its range and, from its mask, its
// lights in light order (up to its count, which a capacity caps). The lists are exactly the
// per-light passes' (the same tests on the same floats), so neither cull.occupancy nor the
// order passes nor cull.finalize run, and each cluster's count is stored, not added. The count
// pass also stores the occupancy words cull.occupancy would.
//
// The masks: word w (lights 32 w .. 32 w + 31) of cluster `bin` at w * bins + bin, in the
// buffer at binding 9 (the per-light passes' wide-light queue, which this path does not use).
// Only the listed clusters' words are stored; the others' counts are zero, and the fill reads
// no word of theirs.

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
// The tile's lists' total (its clusters' counts summed).
var<workgroup> wg_tile_total: atomic<u32>;

fn widen_slice(s: u32, near: u32, far: u32) {
    if far != 0u {
        atomicMax(&wg_slice_near[s], near);
        atomicMax(&wg_slice_far[s], far);
    }
}

// A thread's run of pixels in one slice: widened into workgroup memory once, when the slice
// changes.
struct SliceRun {
    s: u32,
    near: u32,
    far: u32,
}

fn run_widen(run: ptr<function, SliceRun>, s: u32, d0: f32, d1: f32) {
    if s != (*run).s {
        widen_slice((*run).s, (*run).near, (*run).far);
        *run = SliceRun(s, 0u, 0u);
    }
    (*run).near = max((*run).near, ~ordered_bits(d0));
    (*run).far = max((*run).far, ordered_bits(d1));
}

// Pixel i of the tile at `origin`: its nearest and farthest covered sample (MSAA: of
// DEPTH_SAMPLES; one otherwise), or (1, 0) where it is past the tile or the viewport or
// uncovered.
fn tile_pixel_depths(origin: vec2<u32>, i: u32, size: vec2<u32>) -> vec2<f32> {
    let p = origin + vec2<u32>(i % cull.tile_size, i / cull.tile_size);
    if i < cull.tile_size * cull.tile_size && all(p < size) {
        let z = depth_span(p);
        return vec2<f32>(z.near, z.far);
    }
    return vec2<f32>(1.0, 0.0);
}

// A pixel's depths into the run: every slice from its nearest sample's to its farthest's, as
// cull.occupancy marks them (the slice as bin_of computes it, from the same linear depth).
fn reduce_pixel(run: ptr<function, SliceRun>, z: vec2<f32>) {
    if z.x >= 1.0 {
        return;
    }
    let d0 = linear_depth(z.x);
    let s0 = depth_slice(d0);
    // With one sample a pixel (DEPTH_SAMPLES is a constant) z.y is z.x.
    var s1 = s0;
    var d1 = d0;
    if DEPTH_SAMPLES > 1u {
        d1 = linear_depth(z.y);
        s1 = depth_slice(d1);
    }
    if DEPTH_SAMPLES == 1u || s0 == s1 {
        run_widen(run, s0, d0, d1);
        return;
    }
    for (var s = s0; s <= s1; s++) {
        let r = pixel_slice_range(s, s0, s1, d0, d1);
        run_widen(run, s, r.x, r.y);
    }
}

// Step 1: this thread's pixels of the tile, reduced per slice. Four pixels' depths are loaded
// before any is reduced, so that their loads overlap: a load a pixel waited on in turn, the
// count pass took 40 µs at 500 lights in the hall (64 px x 24), 34 with four (eight: the same;
// H100). Without step 3 it took 27.
fn slice_bounds(tile: vec2<u32>, li: u32) {
    let size = vec2<u32>(frame.viewport.xy);
    let origin = tile * cull.tile_size;
    let t = CLUSTER_TILE_THREADS;
    var run = SliceRun(0u, 0u, 0u);
    for (var i = li; i < cull.tile_size * cull.tile_size; i += 4u * t) {
        let za = tile_pixel_depths(origin, i, size);
        let zb = tile_pixel_depths(origin, i + t, size);
        let zc = tile_pixel_depths(origin, i + 2u * t, size);
        let zd = tile_pixel_depths(origin, i + 3u * t, size);
        reduce_pixel(&run, za);
        reduce_pixel(&run, zb);
        reduce_pixel(&run, zc);
        reduce_pixel(&run, zd);
    }
    widen_slice(run.s, run.near, run.far);
}

// Step 2, by thread s < CLUSTER_TILE_SLICES: slice s's cluster, listed if it may hold lights,
// and its occupancy words. Returns whether it is listed.
fn slice_setup(tile: vec2<u32>, s: u32, pixels: bool) -> bool {
    if s >= cull.slices {
        return false;
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
        // The occupancy buffer as cull.occupancy leaves it, for those who read it back (every
        // word stored: it is not cleared on this path).
        let bounds = select(vec2<u32>(0u), vec2<u32>(near, far), tile_boxes());
        atomicStore(&occupancy[bin], u32(listed));
        atomicStore(&occupancy[cull.bins + 2u * bin], bounds.x);
        atomicStore(&occupancy[cull.bins + 2u * bin + 1u], bounds.y);
    }
    if listed {
        wg_slices[atomicAdd(&wg_slice_count, 1u)] = s;
    }
    for (var w = 0u; w < CLUSTER_TILE_WORDS; w++) {
        atomicStore(&wg_slice_mask[s * CLUSTER_TILE_WORDS + w], 0u);
    }
    return listed;
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

// The count pass over a workgroup's tile (see the top of this file). Called in uniform control
// flow.
fn cluster_tile(tile: vec2<u32>, li: u32) {
    if li < CLUSTER_TILE_SLICES {
        atomicStore(&wg_slice_near[li], 0u);
        atomicStore(&wg_slice_far[li], 0u);
    }
    if li == 0u {
        atomicStore(&wg_slice_count, 0u);
        atomicStore(&wg_cand_count, 0u);
        atomicStore(&wg_tile_total, 0u);
        // The fill's cursor starts at zero (no clear: each clear is a transfer between passes).
        if all(tile == vec2<u32>(0u)) {
            atomicStore(&cull_stats[7], 0u);
        }
    }
    workgroupBarrier();
    let pixels = (cull.flags & (CULL_FLAG_SKIP_EMPTY | CULL_FLAG_TILE_BOX)) != 0u;
    if pixels {
        slice_bounds(tile, li);
    }
    workgroupBarrier();
    // Step 2.
    var listed = false;
    if li < CLUSTER_TILE_SLICES {
        listed = slice_setup(tile, li, pixels);
    }
    workgroupBarrier();
    let slices = atomicLoad(&wg_slice_count);
    let bin = li * cull.tiles_x * cull.tiles_y + tile.y * cull.tiles_x + tile.x;
    // Step 3: the lights.
    let planes = tile_side_planes(tile);
    var kept = 0u;
    for (var first = 0u; first < cull.light_count; first += CLUSTER_TILE_THREADS) {
        let i = first + li;
        if i < cull.light_count && !CLUSTER_TILE_RECTS {
            let r = light_rect(i);
            if r.count != 0u && all(vec2<i32>(tile) >= r.rect.xy) && all(vec2<i32>(tile) <= r.rect.zw) && !(outside_plane(planes[0], r.l) || outside_plane(planes[1], r.l) || outside_plane(planes[2], r.l) || outside_plane(planes[3], r.l)) {
                let c = atomicAdd(&wg_cand_count, 1u);
                wg_cand[c] = r.l;
                wg_cand_info[c] = li | (r.s0 << 8u) | (r.s1 << 16u);
            }
        }
        if i < cull.light_count && CLUSTER_TILE_RECTS {
            // The light's rectangle and slices from cull.clustered.rects.
            let lo = cluster_aux[4u * i];
            let hi = cluster_aux[4u * i + 1u];
            let t = tile;
            if cluster_aux[4u * i + 3u] != 0u && t.x >= (lo & 0xffffu) && t.y >= (lo >> 16u) && t.x <= (hi & 0xffffu) && t.y <= (hi >> 16u) {
                let l = cull_light(lights[i]);
                if !(outside_plane(planes[0], l) || outside_plane(planes[1], l) || outside_plane(planes[2], l) || outside_plane(planes[3], l)) {
                    let sl = cluster_aux[4u * i + 2u];
                    let c = atomicAdd(&wg_cand_count, 1u);
                    wg_cand[c] = l;
                    wg_cand_info[c] = li | ((sl & 0xffu) << 8u) | ((sl >> 16u) << 16u);
                }
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
        if listed {
            for (var w = 0u; w < CLUSTER_TILE_WORDS; w++) {
                let m = atomicExchange(&wg_slice_mask[li * CLUSTER_TILE_WORDS + w], 0u);
                atomicStore(&wide_lights[(first / 32u + w) * cull.bins + bin], m);
                kept += countOneBits(m);
            }
        }
        if li == 0u {
            atomicStore(&wg_cand_count, 0u);
        }
        workgroupBarrier();
    }
    if li < cull.slices && li < CLUSTER_TILE_SLICES {
        atomicStore(&bin_counts[bin], kept);
        atomicAdd(&wg_tile_total, kept);
    }
    // The lists' total, for the fill that takes its ranges from a cursor (no scan).
    workgroupBarrier();
    if li == 0u {
        atomicAdd(&cull_stats[3], atomicLoad(&wg_tile_total));
    }
}

// With CLUSTER_TILE_RECTS (where tiles x lights make it pay, CLUSTER_TILE_RECT_PAIRS), the count
// pass reads each light's rectangle and slices from cull.clustered.rects instead of computing
// them at every tile.
override CLUSTER_TILE_RECTS: bool = false;

// cull.clustered.rects: a thread a light, its tile rectangle and slices (light_rect), computed
// once for every tile of the count pass, at binding 11 (the wide lights' dispatch arguments on
// the other path): words 4 i .. 4 i + 3 are x0 | y0 << 16, x1 | y1 << 16, s0 | s1 << 16, and 1
// where the light reaches a tile (0: none).
@compute @workgroup_size(64)
fn cluster_light_rects(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * GROUPS_X * 64u + id.x;
    if i >= cull.light_count {
        return;
    }
    let r = light_rect(i);
    if r.count == 0u {
        cluster_aux[4u * i + 3u] = 0u;
        return;
    }
    cluster_aux[4u * i] = u32(r.rect.x) | (u32(r.rect.y) << 16u);
    cluster_aux[4u * i + 1u] = u32(r.rect.z) | (u32(r.rect.w) << 16u);
    cluster_aux[4u * i + 2u] = r.s0 | (r.s1 << 16u);
    cluster_aux[4u * i + 3u] = 1u;
}

@compute @workgroup_size(256)
fn cluster_tiles_count(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    cluster_tile(wg.xy, li);
}

// A thread a cluster: its range, and its lights from its mask in light order, up to its count
// (capped by a capacity: the first lights are kept).
// With CLUSTER_FILL_CURSOR (no capacity: the host then runs no scan), each cluster's range starts
// where a cursor (cull_stats[7]) stood when its workgroup took its clusters' total, and the
// count pass's total (cull_stats[3]) sizes the lists: the same lists, at other offsets, one pass
// where the scan takes three. Neither word is cleared: the count pass zeroes the cursor, and
// this pass the total, for the next run's count (the cursor's end is the total then).
override CLUSTER_FILL_CURSOR: bool = false;
var<workgroup> wg_fill_total: atomic<u32>;
var<workgroup> wg_fill_base: u32;

@compute @workgroup_size(64)
fn cluster_masks_fill(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let bin = id.y * GROUPS_X * 64u + id.x;
    let inside = bin < cull.bins;
    var n = 0u;
    if inside {
        n = atomicLoad(&bin_counts[bin]);
    }
    var at = 0u;
    if CLUSTER_FILL_CURSOR {
        if li == 0u {
            atomicStore(&wg_fill_total, 0u);
        }
        workgroupBarrier();
        let own = atomicAdd(&wg_fill_total, n);
        workgroupBarrier();
        if li == 0u {
            wg_fill_base = atomicAdd(&cull_stats[7], atomicLoad(&wg_fill_total));
        }
        at = workgroupUniformLoad(&wg_fill_base) + own;
    } else if inside {
        at = bin_offsets[bin];
    }
    if CLUSTER_FILL_CURSOR && bin == 0u {
        atomicStore(&cull_stats[3], 0u);
    }
    if !inside {
        return;
    }
    out_ranges[bin] = vec2<u32>(at, n);
    var kept = 0u;
    let words = (cull.light_count + 31u) / 32u;
    for (var w = 0u; w < words && kept < n; w++) {
        var m = atomicLoad(&wide_lights[w * cull.bins + bin]);
        while m != 0u && kept < n {
            out_indices[at + kept] = 32u * w + firstTrailingBit(m);
            m &= m - 1u;
            kept += 1u;
        }
    }
}
