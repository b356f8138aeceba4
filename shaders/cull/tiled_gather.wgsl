// cull.tiled_gather (Harada, McKee, Yang 2012, section 4.1) and, with CULL_FLAG_DEPTH_MASK,
// cull.depth_mask (2.5D culling, Harada 2012): lights tested against each tile's frustum
// between the tile's depth bounds (and the 2.5D masks). Entry points, in gather_scan.wgsl or,
// with subgroup operations, gather_scan_subgroup.wgsl (which also define the workgroup scan
// `scan_keep`): gather_count / gather_fill (count and fill passes, coarse-to-fine) and
// gather_count_flat / gather_fill_flat (the single level); here gather_finalize. A thread's
// `slot` (0..63) orders its light within a batch.
//
// Coarse-to-fine (cull.coarse = 8): workgroup (x, y, z) takes coarse tile (x, y), 8 x 8 tiles,
// one tile a thread, and chunk z of the lights (cull.chunk lights in light order). For each 64
// lights of the chunk, each thread transforms one and tests it against the coarse tile (its
// frustum between the depth bounds of its covered tiles); the survivors go to workgroup memory,
// in light order (a workgroup scan of the flags); then each thread tests them against its own
// tile. So a light is transformed once per coarse tile, not once per tile, and a thread writes
// its tile's survivors in light order without scans: the count pass stores each (tile, chunk)'s
// count, their exclusive scan gives each chunk's place in its tile's list, and
// gather_finalize makes a tile's range from its first chunk's offset to the next tile's. A
// coarse frustum contains each of its tiles' frusta (its outer planes are theirs, the same
// floats), so coarse culling drops only plane-test false positives of the tile (cpu.rs mirrors
// it).
//
// The single level (cull.coarse = 0): the paper's one workgroup per tile over every light; the
// fill keeps each list in light order: in every batch of 64 lights, a light's slot is the
// number of kept lights before it in the batch (a workgroup scan of the batch's flags) plus
// those of earlier batches. Lists, and so the order in which shading sums a pixel's lights, are
// the same on every run: images are bit-identical across runs.

var<workgroup> wg_planes: array<vec4<f32>, 4>;
var<workgroup> wg_covered: u32;
var<workgroup> wg_cmin: atomic<u32>;
var<workgroup> wg_cmax: atomic<u32>;
var<workgroup> wg_ccov: atomic<u32>;
// A batch's survivors of the coarse test and their light indices.
var<workgroup> wg_surv: array<CullLight, 64>;
var<workgroup> wg_surv_index: array<u32, 64>;

// One batch of up to 64 candidate lights, light `i` at this thread (`valid` false past the
// end). The count pass adds the survivors to `counted`, this thread's own count (one atomic
// add per thread at the end, not one per light); the fill pass places them in light order.
// Returns (lights placed in the tile's list after the batch, counted). Called in uniform
// control flow.
fn gather_batch(bin: u32, slot: u32, i: u32, valid: bool, planes: array<vec4<f32>, 4>, t: TileDepth, fill: bool, acc: vec2<u32>) -> vec2<u32> {
    var keep = false;
    if valid {
        keep = tile_keeps(cull_light(lights[i]), planes, t);
    }
    if !fill {
        return vec2<u32>(acc.x, acc.y + u32(keep));
    }
    let scan = scan_keep(slot, u32(keep));
    let at = acc.x + scan.x - u32(keep);
    if keep && (cull.capacity == 0u || at < cull.capacity) {
        out_indices[bin_offsets[bin] + at] = i;
    }
    return vec2<u32>(acc.x + scan.y, acc.y);
}

// The tile's planes (in workgroup memory) and depth data; false for an empty tile. Uniform, so
// the barriers after it are reached by all threads or none.
fn tile_setup(tile: vec2<u32>, slot: u32) -> bool {
    let t = tile_depth[tile.y * cull.tiles_x + tile.x];
    if slot == 0u {
        wg_planes = tile_side_planes(tile);
        wg_covered = t.covered;
    }
    return workgroupUniformLoad(&wg_covered) != 0u;
}

fn count_done(bin: u32, fill: bool, acc: vec2<u32>) {
    if !fill && acc.y != 0u {
        atomicAdd(&bin_counts[bin], acc.y);
    }
}

// The single level: every light, 64 at a time.
fn gather_flat(tile: vec2<u32>, slot: u32, fill: bool) {
    if !tile_setup(tile, slot) {
        return;
    }
    let bin = tile.y * cull.tiles_x + tile.x;
    let t = tile_depth[bin];
    let planes = wg_planes;
    var acc = vec2<u32>(0u);
    for (var first = 0u; first < cull.light_count; first += 64u) {
        let i = first + slot;
        acc = gather_batch(bin, slot, i, i < cull.light_count, planes, t, fill, acc);
    }
    count_done(bin, fill, acc);
}

// A float's bits mapped so that unsigned order is the float order (negative depths of an
// orthographic camera included), and back.
fn ordered_bits(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn from_ordered_bits(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u & 0x7fffffffu, (u & 0x80000000u) != 0u));
}

// Coarse-to-fine over coarse tile wg.xy and light chunk wg.z (see the top of this file); this
// thread's tile is the slot-th of the coarse tile, row by row.
fn gather_chunk(wg: vec3<u32>, slot: u32, fill: bool) {
    if slot == 0u {
        atomicStore(&wg_cmin, 0xffffffffu);
        atomicStore(&wg_cmax, 0u);
        atomicStore(&wg_ccov, 0u);
    }
    workgroupBarrier();
    let tile = wg.xy * 8u + vec2<u32>(slot % 8u, slot / 8u);
    let inside = tile.x < cull.tiles_x && tile.y < cull.tiles_y;
    let bin = tile.y * cull.tiles_x + tile.x;
    var t: TileDepth;
    var planes: array<vec4<f32>, 4>;
    if inside {
        t = tile_depth[bin];
        if t.covered != 0u {
            atomicMin(&wg_cmin, ordered_bits(t.dmin));
            atomicMax(&wg_cmax, ordered_bits(t.dmax));
            atomicAdd(&wg_ccov, t.covered);
            planes = tile_side_planes(tile);
        }
    }
    workgroupBarrier();
    if slot == 0u {
        wg_covered = atomicLoad(&wg_ccov);
    }
    // Uniform, so the barriers below are reached by all threads or none.
    if workgroupUniformLoad(&wg_covered) == 0u {
        return;
    }
    var c: TileDepth;
    c.covered = atomicLoad(&wg_ccov);
    c.dmin = from_ordered_bits(atomicLoad(&wg_cmin));
    c.dmax = from_ordered_bits(atomicLoad(&wg_cmax));
    c.mask = 0xffffffffu;
    let coarse_planes = square_side_planes(wg.xy, 8u * cull.tile_size);
    let has_pixels = inside && t.covered != 0u;
    let chunks = (cull.light_count + cull.chunk - 1u) / cull.chunk;
    let entry = bin * chunks + wg.z;
    var at = 0u;
    if fill && has_pixels {
        at = bin_offsets[entry];
    }
    var kept = 0u;
    let first = wg.z * cull.chunk;
    let end = min(first + cull.chunk, cull.light_count);
    for (var b = first; b < end; b += 64u) {
        let i = b + slot;
        var keep = false;
        var l: CullLight;
        if i < end {
            l = cull_light(lights[i]);
            keep = tile_keeps(l, coarse_planes, c);
        }
        let scan = scan_keep(slot, u32(keep));
        if keep {
            wg_surv[scan.x - 1u] = l;
            wg_surv_index[scan.x - 1u] = i;
        }
        workgroupBarrier();
        if has_pixels {
            for (var k = 0u; k < scan.y; k++) {
                if tile_keeps(wg_surv[k], planes, t) {
                    if fill {
                        out_indices[at + kept] = wg_surv_index[k];
                    }
                    kept += 1u;
                }
            }
        }
        workgroupBarrier();
    }
    if !fill && has_pixels {
        atomicStore(&bin_counts[entry], kept);
    }
}

// cull.finalize for the coarse-to-fine lists: a tile's range runs from its first chunk's
// offset to the next tile's.
@compute @workgroup_size(64)
fn gather_finalize(@builtin(global_invocation_id) id: vec3<u32>) {
    let b = id.y * GROUPS_X * 64u + id.x;
    if b < cull.bins {
        let chunks = (cull.light_count + cull.chunk - 1u) / cull.chunk;
        let o = bin_offsets[b * chunks];
        out_ranges[b] = vec2<u32>(o, bin_offsets[(b + 1u) * chunks] - o);
    }
}
