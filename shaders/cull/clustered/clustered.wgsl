// cull.clustered (Olsson, Billeter, Assarsson, HPG 2012): the view frustum split into tiles in
// x/y and depth slices (linear or exponential). One thread per light: the light's conservative
// screen rectangle gives candidate tiles, its depth extent the candidate slices; each candidate
// tile is tested with the tile's side planes (sphere, and cone for spots), and every slice of
// the light's range is emitted (with CULL_FLAG_SKIP_EMPTY, only clusters holding geometry).

// Lights come in three sizes. Most cover a few tiles: one thread a light does them
// (cull.clustered.count / fill), and a light covering more than CLUSTER_NARROW tiles is queued
// instead (count pass) or skipped (fill pass). A light near the camera covers the whole screen
// (at 1080p, 510 tiles x 24 slices); alone, one thread would emit its 12,000 entries in series
// while the rest of the GPU idles, so the queued lights get several threads each
// (cull.clustered.count_wide / fill_wide, dispatched indirectly from the queue's lengths):
// CLUSTER_MEDIUM_LANES for a medium light (at most CLUSTER_MEDIUM tiles), CLUSTER_LANES for a
// wide one. Lane k takes the entry's tiles k, k + lanes, ... when it has at least as many tiles
// as lanes or the tiles' masks of occupied slices are there (CULL_FLAG_SLICE_MASKS), and
// otherwise its (tile, slice) pairs k, k + lanes, ... So neither the many small lights pay for
// lanes they do not use nor a wide light serialises. (At 1M lights in 32-pixel tiles, H100:
// 1.56 ms with 32 lanes for every queued light, 1.22 with the medium lights' 8.)
//
// The queue (wide_lights): word 0 the wide lights, word 1 the bands reserved, word 2 the medium
// lights; entry q at words 4 + 4q: the light (WIDE_NONE: an unused band), its rectangle
// (x0 | y0 << 16, x1 | y1 << 16) and its slices (s0 | s1 << 16), so that the lanes need not
// recompute them. Entries 0 .. light_count hold the wide lights from the front and the medium
// ones from the back (a light is one or the other); a workgroup of the count pass reserves its
// entries with one atomic for each kind, not one per light: a quarter of a million lights may be
// queued.
//
// Bands: a wide light whose rectangle has more than CLUSTER_LANES x cull.chunk tiles (the tiles
// a lane should take) is split into bands of its rows, up to one a row, each an entry of its
// own with CLUSTER_LANES lanes. Its lanes would otherwise walk a whole-screen light's thousands
// of tiles while the rest of the GPU idles. The first band is the light's entry; the others are
// taken from the band pool, entries light_count .. (the buffer's end), with one atomic a
// workgroup on word 1; a light whose bands do not fit there keeps one entry for its whole
// rectangle (and marks the pool's entries it reserved WIDE_NONE). The same (tile, slice) tests
// either way. The wide passes' threads: the wide entries' lanes (the lights' first bands, then
// the pool's), then the medium lights'.
@group(1) @binding(9) var<storage, read_write> wide_lights: array<atomic<u32>>;
// Binding 11: the wide passes' dispatch arguments in cull.clustered.wide_args (an indirect
// buffer cannot also be bound for storage in the dispatch that reads it); with
// CULL_FLAG_CLUSTER_BOXES, the clusters' boxes in the passes after cull.clustered.boxes; on the
// tile path, the lights' rectangles (cluster_tiles.wgsl).
@group(1) @binding(11) var<storage, read_write> cluster_aux: array<u32>;

const CLUSTER_NARROW: u32 = 4u;
// Medium lights (more than CLUSTER_NARROW tiles, at most CLUSTER_MEDIUM) get
// CLUSTER_MEDIUM_LANES lanes each, wider ones CLUSTER_LANES.
const CLUSTER_MEDIUM: u32 = 32u;
const CLUSTER_MEDIUM_LANES: u32 = 8u;

struct LightRect {
    l: CullLight,
    s0: u32,
    s1: u32,
    rect: vec4<i32>,
    // Tiles of the rectangle (0: the light reaches none).
    count: u32,
}

fn light_rect(i: u32) -> LightRect {
    var r: LightRect;
    r.l = cull_light(lights[i]);
    r.count = 0u;
    let dlo = -r.l.center.z - r.l.radius - r.l.slack;
    let dhi = -r.l.center.z + r.l.radius + r.l.slack;
    // Only the far side can reject: cull.near is where slicing starts, which for exponential
    // slicing of an orthographic camera lies beyond the camera's own near plane (nearer depths
    // fall in slice 0). (light_tiles rejects lights wholly nearer than the near plane.)
    if dlo > cull.far {
        return r;
    }
    r.s0 = depth_slice(dlo);
    r.s1 = depth_slice(dhi);
    r.rect = light_tiles(r.l);
    if r.rect.x > r.rect.z || r.rect.y > r.rect.w {
        return r;
    }
    r.count = u32(r.rect.z - r.rect.x + 1) * u32(r.rect.w - r.rect.y + 1);
    return r;
}

// Whether the light may reach the tile: its four side planes.
fn tile_holds(tile: vec2<u32>, l: CullLight) -> bool {
    let planes = tile_side_planes(tile);
    return !(outside_plane(planes[0], l) || outside_plane(planes[1], l) || outside_plane(planes[2], l) || outside_plane(planes[3], l));
}

// With the box test (CULL_FLAG_TILE_BOX), whether the light may reach a pixel of cluster `bin`
// of tile `tile`: the depths of its pixels (none: no), then the box of the tile's frustum
// between them (tile_box), so a cluster is tested as its pixels bound it, not as its slice.
fn cluster_box_keeps(l: CullLight, tile: vec2<u32>, bin: u32) -> bool {
    if (cull.flags & CULL_FLAG_CLUSTER_BOXES) != 0u {
        return stored_box_keeps(l, bin);
    }
    let at = cull.bins + 2u * bin;
    let far = atomicLoad(&occupancy[at + 1u]);
    if far == 0u {
        return false;
    }
    var t = cluster_depth(atomicLoad(&occupancy[at]), far);
    t.mask = cells_of(bin);
    return depth_keeps(l, t) && sphere_meets_box(l.center, l.radius + l.slack, tile_box(tile, t));
}

// The first occupancy word of the clusters' 2.5D cells (after the flags, the depth bounds and
// the tiles' slice masks): cluster `bin`'s at cells_at() + bin.
fn cells_at() -> u32 {
    return 3u * cull.bins + 2u * cull.tiles_x * cull.tiles_y;
}

// Whether the pipeline tests the clusters' cells (their runs set CULL_FLAG_DEPTH_MASK): a
// constant, so that the pipelines without them test no flag at every (light, cluster).
override CLUSTER_CELLS: bool = false;

// Cluster `bin`'s 2.5D cells in a CLUSTER_CELLS pipeline (cull.clustered.cells: a bit for each of
// the 32 cells of its pixels' depth range that holds a pixel), which depth_keeps tests the
// light's cells against; 0 (unused) otherwise.
fn cells_of(bin: u32) -> u32 {
    if CLUSTER_CELLS {
        return atomicLoad(&occupancy[cells_at() + bin]);
    }
    return 0u;
}

// A cluster's pixels' depth bounds from its occupancy words (nearest as ~ordered bits,
// farthest as ordered bits), as the box test takes them.
fn cluster_depth(near: u32, far: u32) -> TileDepth {
    var t: TileDepth;
    t.dmin = from_ordered_bits(~near);
    t.dmax = from_ordered_bits(far);
    t.mask = 0u;
    t.covered = 1u;
    return t;
}

// The words of cluster `bin`'s box in cluster_aux (CULL_FLAG_CLUSTER_BOXES): the box's low
// corner and the cluster's nearest depth as the occupancy stores it, then its high corner and
// the farthest depth (0: no pixel).
const CLUSTER_BOX_WORDS: u32 = 8u;

// cluster_box_keeps from the box cull.clustered.boxes stored: the same floats, computed once a
// cluster, not once for each light that reaches its tile.
fn stored_box_keeps(l: CullLight, bin: u32) -> bool {
    let at = CLUSTER_BOX_WORDS * bin;
    let far = cluster_aux[at + 7u];
    if far == 0u {
        return false;
    }
    var t = cluster_depth(cluster_aux[at + 3u], far);
    t.mask = cells_of(bin);
    let lo = vec3<f32>(bitcast<f32>(cluster_aux[at]), bitcast<f32>(cluster_aux[at + 1u]), bitcast<f32>(cluster_aux[at + 2u]));
    let hi = vec3<f32>(bitcast<f32>(cluster_aux[at + 4u]), bitcast<f32>(cluster_aux[at + 5u]), bitcast<f32>(cluster_aux[at + 6u]));
    return depth_keeps(l, t) && sphere_meets_box(l.center, l.radius + l.slack, array<vec3<f32>, 2>(lo, hi));
}

// cull.clustered.boxes (with CULL_FLAG_CLUSTER_BOXES, after cull.occupancy): a thread a cluster
// stores its box (tile_box between its pixels' depths) for the count and fill passes, and with
// CULL_FLAG_SLICE_MASKS sets its slice's bit in its tile's mask of occupied slices.
@compute @workgroup_size(64)
fn cluster_boxes(@builtin(global_invocation_id) id: vec3<u32>) {
    let bin = id.y * GROUPS_X * 64u + id.x;
    if bin >= cull.bins {
        return;
    }
    let at = cull.bins + 2u * bin;
    let near = atomicLoad(&occupancy[at]);
    let far = atomicLoad(&occupancy[at + 1u]);
    var b = array<vec3<f32>, 2>(vec3<f32>(0.0), vec3<f32>(0.0));
    if far != 0u {
        let tiles = cull.tiles_x * cull.tiles_y;
        let t = bin % tiles;
        if (cull.flags & CULL_FLAG_SLICE_MASKS) != 0u {
            let s = bin / tiles;
            atomicOr(&occupancy[3u * cull.bins + 2u * t + s / 32u], 1u << (s % 32u));
        }
        b = tile_box(vec2<u32>(t % cull.tiles_x, t / cull.tiles_x), cluster_depth(near, far));
    }
    let o = CLUSTER_BOX_WORDS * bin;
    cluster_aux[o] = bitcast<u32>(b[0].x);
    cluster_aux[o + 1u] = bitcast<u32>(b[0].y);
    cluster_aux[o + 2u] = bitcast<u32>(b[0].z);
    cluster_aux[o + 3u] = near;
    cluster_aux[o + 4u] = bitcast<u32>(b[1].x);
    cluster_aux[o + 5u] = bitcast<u32>(b[1].y);
    cluster_aux[o + 6u] = bitcast<u32>(b[1].z);
    cluster_aux[o + 7u] = far;
}

// Held pairs (CLUSTER_PAIRS: the count passes of a run whose lists were sized up front, as
// back-to-back runs are): the count passes' tests are the fill passes' again, so there each
// thread keeps the (cluster, light) pairs it counts, PAIR_SLOTS of them in registers, and writes
// them to the pair region of cluster_aux (after the clusters' boxes, two words a pair) at an
// offset its workgroup takes with one atomic on cull_stats[PAIRS_WORD]; a thread that counted
// more walks its lights' clusters again, writing each pair (EMIT_PAIRS). The region holds the
// lists' total, so every pair fits; cull.clustered.scatter then puts each into its list in
// place of the fill passes.
override CLUSTER_PAIRS: bool = false;
const PAIR_SLOTS: u32 = 8u;
const PAIRS_WORD: u32 = 11u;
// What emit_cluster does with a pair: count it (holding it with CLUSTER_PAIRS), put it in its
// list, or write it to the pair region at pair_next.
const EMIT_COUNT: u32 = 0u;
const EMIT_FILL: u32 = 1u;
const EMIT_PAIRS: u32 = 2u;
var<private> held_bins: array<u32, PAIR_SLOTS>;
var<private> held_count: u32;
var<private> held_light: u32;
var<private> pair_next: u32;
var<workgroup> wg_pairs: atomic<u32>;
var<workgroup> wg_pairs_base: u32;

// The first word of the pair region in cluster_aux, and the pairs it holds.
fn pairs_at() -> u32 {
    return CLUSTER_BOX_WORDS * cull.bins;
}

fn pair_capacity() -> u32 {
    return (arrayLength(&cluster_aux) - pairs_at()) / 2u;
}

fn write_pair(k: u32, bin: u32, light: u32) {
    if k < pair_capacity() {
        cluster_aux[pairs_at() + 2u * k] = bin;
        cluster_aux[pairs_at() + 2u * k + 1u] = light;
    }
}

fn emit_cluster(bin: u32, light: u32, mode: u32) {
    if mode == EMIT_PAIRS {
        write_pair(pair_next, bin, light);
        pair_next += 1u;
        return;
    }
    emit(bin, light, mode == EMIT_FILL);
    if CLUSTER_PAIRS && mode == EMIT_COUNT {
        if held_count < PAIR_SLOTS {
            held_bins[held_count] = bin;
        }
        held_count += 1u;
        held_light = light;
    }
}

// After a count pass's thread has emitted its pairs (uniform control flow): takes their place in
// the pair region and writes those held; true where it counted more than it held, and must walk
// its clusters again with EMIT_PAIRS (from pair_next).
fn hold_pairs(li: u32) -> bool {
    var at = 0u;
    if held_count != 0u {
        at = atomicAdd(&wg_pairs, held_count);
    }
    workgroupBarrier();
    if li == 0u {
        let n = atomicLoad(&wg_pairs);
        var base = 0u;
        if n != 0u {
            base = atomicAdd(&cull_stats[PAIRS_WORD], n);
        }
        wg_pairs_base = base;
    }
    pair_next = workgroupUniformLoad(&wg_pairs_base) + at;
    if held_count > PAIR_SLOTS {
        return true;
    }
    for (var k = 0u; k < held_count; k++) {
        write_pair(pair_next + k, held_bins[k], held_light);
    }
    return false;
}

fn emit_slices(i: u32, l: CullLight, tile: vec2<u32>, s0: u32, s1: u32, mode: u32) {
    let tiles = cull.tiles_x * cull.tiles_y;
    if (cull.flags & CULL_FLAG_SLICE_MASKS) != 0u {
        // Only the slices of s0..=s1 that hold pixels, from the tile's mask (s1 < 64).
        let t = tile.y * cull.tiles_x + tile.x;
        let at = 3u * cull.bins + 2u * t;
        for (var w = s0 / 32u; w <= s1 / 32u; w++) {
            let lo = select(0u, s0 % 32u, w == s0 / 32u);
            let hi = select(31u, s1 % 32u, w == s1 / 32u);
            var bits = atomicLoad(&occupancy[at + w]) & bit_range(lo, hi);
            while bits != 0u {
                let s = w * 32u + firstTrailingBit(bits);
                bits &= bits - 1u;
                let bin = s * tiles + t;
                if cluster_box_keeps(l, tile, bin) {
                    emit_cluster(bin, i, mode);
                }
            }
        }
        return;
    }
    for (var s = s0; s <= s1; s++) {
        let bin = s * tiles + tile.y * cull.tiles_x + tile.x;
        if tile_boxes() {
            if cluster_box_keeps(l, tile, bin) {
                emit_cluster(bin, i, mode);
            }
        } else if (cull.flags & CULL_FLAG_SKIP_EMPTY) == 0u || atomicLoad(&occupancy[bin]) != 0u {
            emit_cluster(bin, i, mode);
        }
    }
}

var<workgroup> wg_wide: atomic<u32>;
var<workgroup> wg_base: u32;
var<workgroup> wg_extra: atomic<u32>;
var<workgroup> wg_extra_base: u32;
var<workgroup> wg_medium: atomic<u32>;
var<workgroup> wg_medium_base: u32;

// One thread a narrow light: its tiles, each with every slice of the light's range.
fn assign_narrow(i: u32, r: LightRect, mode: u32) {
    let width = u32(r.rect.z - r.rect.x + 1);
    for (var k = 0u; k < r.count; k++) {
        let tile = vec2<u32>(u32(r.rect.x) + k % width, u32(r.rect.y) + k / width);
        if tile_holds(tile, r.l) {
            emit_slices(i, r.l, tile, r.s0, r.s1, mode);
        }
    }
}

const WIDE_NONE: u32 = 0xffffffffu;

// The entries of the band pool (after the light_count entries of the lights' first bands).
fn band_pool() -> u32 {
    return arrayLength(&wide_lights) / 4u - 1u - cull.light_count;
}

// The bands of a wide light: one a row at most, each of at least CLUSTER_LANES x cull.chunk
// tiles (one band with cull.chunk 0).
fn light_bands(r: LightRect) -> u32 {
    if cull.chunk == 0u {
        return 1u;
    }
    let rows = u32(r.rect.w - r.rect.y + 1);
    return clamp((r.count + CLUSTER_LANES * cull.chunk - 1u) / (CLUSTER_LANES * cull.chunk), 1u, rows);
}

// The queue's entry of band `b` of `bands` of light `i` at entry `e`.
fn store_band(e: u32, i: u32, r: LightRect, b: u32, bands: u32) {
    let rows = u32(r.rect.w - r.rect.y + 1);
    let y0 = u32(r.rect.y) + b * rows / bands;
    let y1 = u32(r.rect.y) + (b + 1u) * rows / bands - 1u;
    let w = 4u + 4u * e;
    atomicStore(&wide_lights[w], i);
    atomicStore(&wide_lights[w + 1u], u32(r.rect.x) | (y0 << 16u));
    atomicStore(&wide_lights[w + 2u], u32(r.rect.z) | (y1 << 16u));
    atomicStore(&wide_lights[w + 3u], r.s0 | (r.s1 << 16u));
}

// The queue's entries: the lights' first bands, then the pool's bands in use.
fn queue_entries() -> u32 {
    return atomicLoad(&wide_lights[0]) + min(atomicLoad(&wide_lights[1]), band_pool());
}

// CLUSTER_LANES threads a queued entry (a wide light or a band of its rows), then
// CLUSTER_MEDIUM_LANES a medium light, over its (tile, slice) pairs.
fn assign_wide(id: vec3<u32>, mode: u32) {
    let t = id.y * GROUPS_X * 64u + id.x;
    let wide = queue_entries();
    var q = t / CLUSTER_LANES;
    var lanes = CLUSTER_LANES;
    var lane = t % CLUSTER_LANES;
    if q < wide {
        let first = atomicLoad(&wide_lights[0]);
        if q >= first {
            q = cull.light_count + (q - first);
        }
    } else {
        let m = t - wide * CLUSTER_LANES;
        if m / CLUSTER_MEDIUM_LANES >= atomicLoad(&wide_lights[2]) {
            return;
        }
        q = cull.light_count - 1u - m / CLUSTER_MEDIUM_LANES;
        lanes = CLUSTER_MEDIUM_LANES;
        lane = m % CLUSTER_MEDIUM_LANES;
    }
    let e = 4u + 4u * q;
    let i = atomicLoad(&wide_lights[e]);
    if i == WIDE_NONE {
        return;
    }
    let lo = atomicLoad(&wide_lights[e + 1u]);
    let hi = atomicLoad(&wide_lights[e + 2u]);
    let sl = atomicLoad(&wide_lights[e + 3u]);
    let l = cull_light(lights[i]);
    let x0 = lo & 0xffffu;
    let y0 = lo >> 16u;
    let width = (hi & 0xffffu) - x0 + 1u;
    let s0 = sl & 0xffffu;
    let slices = (sl >> 16u) - s0 + 1u;
    let tiles = width * ((hi >> 16u) - y0 + 1u);
    if tiles >= lanes || (cull.flags & CULL_FLAG_SLICE_MASKS) != 0u {
        // Enough tiles for every lane, or the tiles' masks of occupied slices: a lane tests
        // each of its tiles once, for all slices (with the masks, only the occupied ones).
        for (var k = lane; k < tiles; k += lanes) {
            let tile = vec2<u32>(x0 + k % width, y0 + k / width);
            if tile_holds(tile, l) {
                emit_slices(i, l, tile, s0, s0 + slices - 1u, mode);
            }
        }
        return;
    }
    // Fewer tiles than lanes: the lanes share the (tile, slice) pairs (a tile is tested once
    // per slice, by the lane that has the pair).
    let pairs = tiles * slices;
    for (var k = lane; k < pairs; k += lanes) {
        let tk = k / slices;
        let tile = vec2<u32>(x0 + tk % width, y0 + tk / width);
        if tile_holds(tile, l) {
            let s = s0 + k % slices;
            emit_slices(i, l, tile, s, s, mode);
        }
    }
}

// One thread a light: narrow lights done here, wide ones queued.
@compute @workgroup_size(64)
fn clustered_count(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if li == 0u {
        atomicStore(&wg_wide, 0u);
        atomicStore(&wg_extra, 0u);
        atomicStore(&wg_medium, 0u);
    }
    workgroupBarrier();
    let i = id.y * GROUPS_X * 64u + id.x;
    var r: LightRect;
    var wide = false;
    var medium = false;
    if i < cull.light_count {
        r = light_rect(i);
        medium = r.count > CLUSTER_NARROW && r.count <= CLUSTER_MEDIUM;
        wide = r.count > CLUSTER_MEDIUM;
        if r.count <= CLUSTER_NARROW {
            assign_narrow(i, r, EMIT_COUNT);
        }
    }
    var at = 0u;
    var bands = 1u;
    var extra = 0u;
    if medium {
        at = atomicAdd(&wg_medium, 1u);
    }
    if wide {
        at = atomicAdd(&wg_wide, 1u);
        bands = light_bands(r);
        if bands > 1u {
            extra = atomicAdd(&wg_extra, bands - 1u);
        }
    }
    workgroupBarrier();
    if li == 0u {
        let n = atomicLoad(&wg_wide);
        var base = 0u;
        if n != 0u {
            base = atomicAdd(&wide_lights[0], n);
        }
        wg_base = base;
        let x = atomicLoad(&wg_extra);
        var extra_base = 0u;
        if x != 0u {
            extra_base = atomicAdd(&wide_lights[1], x);
        }
        wg_extra_base = extra_base;
        let m = atomicLoad(&wg_medium);
        var medium_base = 0u;
        if m != 0u {
            medium_base = atomicAdd(&wide_lights[2], m);
        }
        wg_medium_base = medium_base;
    }
    let base = workgroupUniformLoad(&wg_base);
    let extra_base = workgroupUniformLoad(&wg_extra_base);
    let medium_base = workgroupUniformLoad(&wg_medium_base);
    if medium {
        store_band(cull.light_count - 1u - (medium_base + at), i, r, 0u, 1u);
    }
    if wide {
        // Bands 1 .. bands - 1 in the pool, where they all fit; else the whole rectangle in
        // one entry, and the pool's entries reserved (those within it) unused.
        let pool = band_pool();
        let start = extra_base + extra;
        if bands > 1u && start + bands - 1u > pool {
            for (var k = start; k < min(start + bands - 1u, pool); k++) {
                atomicStore(&wide_lights[4u + 4u * (cull.light_count + k)], WIDE_NONE);
            }
            bands = 1u;
        }
        store_band(base + at, i, r, 0u, bands);
        for (var b = 1u; b < bands; b++) {
            store_band(cull.light_count + start + b - 1u, i, r, b, bands);
        }
    }
    if CLUSTER_PAIRS && hold_pairs(li) {
        assign_narrow(i, r, EMIT_PAIRS);
    }
}

// The narrow lights again; the wide ones are the queue's.
@compute @workgroup_size(64)
fn clustered_fill(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * GROUPS_X * 64u + id.x;
    if i < cull.light_count {
        let r = light_rect(i);
        if r.count <= CLUSTER_NARROW {
            assign_narrow(i, r, EMIT_FILL);
        }
    }
}

@compute @workgroup_size(64)
fn clustered_count_wide(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    assign_wide(id, EMIT_COUNT);
    if CLUSTER_PAIRS && hold_pairs(li) {
        assign_wide(id, EMIT_PAIRS);
    }
}

@compute @workgroup_size(64)
fn clustered_fill_wide(@builtin(global_invocation_id) id: vec3<u32>) {
    assign_wide(id, EMIT_FILL);
}

// cull.clustered.scatter (a run whose lists were sized up front, in place of the fill passes):
// a thread a pair that the count passes held (CLUSTER_PAIRS), into its cluster's list as the
// fill passes would put it.
@compute @workgroup_size(64)
fn clustered_scatter(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.y * GROUPS_X * 64u + id.x;
    if k < min(atomicLoad(&cull_stats[PAIRS_WORD]), pair_capacity()) {
        let at = pairs_at() + 2u * k;
        emit(cluster_aux[at], cluster_aux[at + 1u], true);
    }
}

// The indirect dispatch of the wide passes: CLUSTER_LANES threads for each queued entry, in
// workgroups of 64 laid out as groups_2d does (GROUPS_X across).
@compute @workgroup_size(1)
fn clustered_wide_args() {
    let threads = queue_entries() * CLUSTER_LANES + atomicLoad(&wide_lights[2]) * CLUSTER_MEDIUM_LANES;
    let groups = (threads + 63u) / 64u;
    cluster_aux[0] = min(groups, GROUPS_X);
    cluster_aux[1] = (groups + GROUPS_X - 1u) / GROUPS_X;
    cluster_aux[2] = 1u;
}

// Marks the clusters that hold covered pixels, one thread per pixel.

// A workgroup's pixels: the least and greatest bin, and (with the box test) the nearest and
// farthest depth as the occupancy stores them.
var<workgroup> wg_occ: array<atomic<u32>, 4>;

// A pixel's nearest and farthest covered sample (MSAA: of DEPTH_SAMPLES; one otherwise), their
// bins and linear depths: its clusters are every one from the nearest sample's to the
// farthest's (pixel_slice_range says why). b0 past the last bin where nothing is covered.
struct PixelDepths {
    covered: bool,
    b0: u32,
    b1: u32,
    d0: f32,
    d1: f32,
}

fn pixel_depths(p: vec2<u32>) -> PixelDepths {
    let inside = all(p < vec2<u32>(frame.viewport.xy));
    var z0 = 1.0;
    var z1 = 0.0;
    if inside {
        let z = depth_span(p);
        z0 = z.near;
        z1 = z.far;
    }
    let b0 = bin_of(p, z0);
    let d0 = linear_depth(z0);
    // With one sample a pixel (DEPTH_SAMPLES is a constant) z1 is z0: not computed again.
    var b1 = b0;
    var d1 = d0;
    if DEPTH_SAMPLES > 1u {
        b1 = bin_of(p, z1);
        d1 = linear_depth(z1);
    }
    return PixelDepths(z0 < 1.0, b0, b1, d0, d1);
}

// Where a workgroup's 8 x 8 pixels fall in one cluster (most of them: a cluster is a tile of
// several such blocks, and neighbouring pixels mostly share a slice), its first thread writes
// the cluster's flag and bounds once; elsewhere each pixel writes its own. (Every pixel of a
// cluster widening the same two words serialises on them.)
@compute @workgroup_size(8, 8)
fn cluster_occupancy(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if li == 0u {
        atomicStore(&wg_occ[0], 0xffffffffu);
        atomicStore(&wg_occ[1], 0u);
        atomicStore(&wg_occ[2], 0u);
        atomicStore(&wg_occ[3], 0u);
    }
    workgroupBarrier();
    let px = pixel_depths(id.xy);
    let covered = px.covered;
    let b0 = px.b0;
    let b1 = px.b1;
    let d0 = px.d0;
    let d1 = px.d1;
    if covered {
        atomicMin(&wg_occ[0], b0);
        atomicMax(&wg_occ[1], b1);
        atomicMax(&wg_occ[2], ~ordered_bits(d0));
        atomicMax(&wg_occ[3], ordered_bits(d1));
    }
    workgroupBarrier();
    let first = atomicLoad(&wg_occ[0]);
    if first == atomicLoad(&wg_occ[1]) {
        // One cluster (or, first past the last bin, no covered pixel).
        if li == 0u && first < cull.bins {
            atomicStore(&occupancy[first], 1u);
            if tile_boxes() {
                atomicMax(&occupancy[cull.bins + 2u * first], atomicLoad(&wg_occ[2]));
                atomicMax(&occupancy[cull.bins + 2u * first + 1u], atomicLoad(&wg_occ[3]));
            }
        }
    } else if covered && (DEPTH_SAMPLES == 1u || b0 == b1) {
        atomicStore(&occupancy[b0], 1u);
        if tile_boxes() {
            atomicMax(&occupancy[cull.bins + 2u * b0], ~ordered_bits(d0));
            atomicMax(&occupancy[cull.bins + 2u * b0 + 1u], ordered_bits(d1));
        }
    } else if covered {
        let tiles = cull.tiles_x * cull.tiles_y;
        for (var bin = b0; bin <= b1; bin += tiles) {
            atomicStore(&occupancy[bin], 1u);
            if tile_boxes() {
                let r = pixel_slice_range(bin / tiles, b0 / tiles, b1 / tiles, d0, d1);
                atomicMax(&occupancy[cull.bins + 2u * bin], ~ordered_bits(r.x));
                atomicMax(&occupancy[cull.bins + 2u * bin + 1u], ordered_bits(r.y));
            }
        }
    }
}

// cull.clustered.cells (with CULL_FLAG_DEPTH_MASK, after cull.occupancy): each covered pixel
// sets, in each of its clusters, the bits of the 2.5D cells its depths there fall in (its part
// of the pixel's depths, pixel_slice_range; depth_cell over the cluster's pixels' depth bounds
// from cull.occupancy). A light's cells (light_depth_mask, over the same bounds) that hold a
// pixel's depth hold its cell: floor is monotone. Where the workgroup's pixels fall in one
// cluster, they gather their bits in workgroup memory and the first thread stores them once.
var<workgroup> wg_cells: atomic<u32>;

@compute @workgroup_size(8, 8)
fn cluster_cells(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if li == 0u {
        atomicStore(&wg_occ[0], 0xffffffffu);
        atomicStore(&wg_occ[1], 0u);
        atomicStore(&wg_cells, 0u);
    }
    workgroupBarrier();
    let px = pixel_depths(id.xy);
    if px.covered {
        atomicMin(&wg_occ[0], px.b0);
        atomicMax(&wg_occ[1], px.b1);
    }
    workgroupBarrier();
    let first = atomicLoad(&wg_occ[0]);
    let one = first == atomicLoad(&wg_occ[1]);
    if px.covered {
        let tiles = cull.tiles_x * cull.tiles_y;
        for (var bin = px.b0; bin <= px.b1; bin += tiles) {
            let r = pixel_slice_range(bin / tiles, px.b0 / tiles, px.b1 / tiles, px.d0, px.d1);
            let at = cull.bins + 2u * bin;
            let t = cluster_depth(atomicLoad(&occupancy[at]), atomicLoad(&occupancy[at + 1u]));
            let scale = depth_cell_scale(t);
            let bits = bit_range(depth_cell(r.x, t.dmin, scale), depth_cell(r.y, t.dmin, scale));
            if one {
                atomicOr(&wg_cells, bits);
            } else {
                atomicOr(&occupancy[cells_at() + bin], bits);
            }
        }
    }
    workgroupBarrier();
    if one && li == 0u && first < cull.bins {
        atomicOr(&occupancy[cells_at() + first], atomicLoad(&wg_cells));
    }
}
