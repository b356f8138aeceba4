// cull.tiled_scatter (Harada, McKee, Yang 2012, section 4.2): one thread per light finds the
// tiles it overlaps (its conservative screen rectangle, then the same per-tile test as tiled
// gather) and writes (tile, light) pairs; sort.radix orders them by tile (stably, so each
// tile's lights stay in light order); scatter_ranges finds each tile's start and end.
// Group 1 here: bin_counts/bin_offsets are per light (pair counts and their scan), bin_cursors
// holds each tile's end, out_indices the pairs' lights, pair_keys their tiles.
@group(1) @binding(9) var<storage, read_write> pair_keys: array<u32>;
// The tile masks (tile_masks.wgsl), as atomics: lights set their bits concurrently.
@group(1) @binding(11) var<storage, read_write> tile_masks: array<atomic<u32>>;
// The blocks queued for scatter_masks.
var<workgroup> wg_mask_blocks: u32;
var<workgroup> wg_mask_light: CullLight;

// Visits the tiles that keep light t / SCATTER_LANES, the lane t % SCATTER_LANES taking every
// SCATTER_LANES-th tile of its rectangle, so that a light covering the screen is shared by many
// threads. Each (light, lane) has its own count and its own segment of the pairs (bin_counts
// and bin_offsets hold lights x SCATTER_LANES entries); the stable sort by tile then leaves each
// tile's lights in light order, whatever the lanes.
fn scatter_light(t: u32, write: bool) {
    let i = t / SCATTER_LANES;
    let lane = t % SCATTER_LANES;
    if i >= cull.light_count {
        return;
    }
    let l = cull_light(lights[i]);
    let rect = light_tiles(l);
    if rect.x > rect.z || rect.y > rect.w {
        return;
    }
    let width = u32(rect.z - rect.x + 1);
    let count = width * u32(rect.w - rect.y + 1);
    var n = 0u;
    var base = 0u;
    if write {
        base = bin_offsets[t];
    }
    for (var k = lane; k < count; k += SCATTER_LANES) {
        let tile = vec2<u32>(u32(rect.x) + k % width, u32(rect.y) + k / width);
        let bin = tile.y * cull.tiles_x + tile.x;
        if tile_keeps_at(l, tile, tile_side_planes(tile), tile_depth[bin]) {
            if write {
                pair_keys[base + n] = bin;
                out_indices[base + n] = i;
            }
            n += 1u;
        }
    }
    if !write {
        atomicStore(&bin_counts[t], n);
        // The pairs' 64-bit total: cull_stats[1] wraps, and the thread whose add wraps it
        // carries into cull_stats[2].
        if n > 0u {
            let old = atomicAdd(&cull_stats[1], n);
            if old + n < old {
                atomicAdd(&cull_stats[2], 1u);
            }
        }
    }
}

@compute @workgroup_size(64)
fn scatter_count(@builtin(global_invocation_id) id: vec3<u32>) {
    scatter_light(id.y * GROUPS_X * 64u + id.x, false);
}

@compute @workgroup_size(64)
fn scatter_pairs(@builtin(global_invocation_id) id: vec3<u32>) {
    scatter_light(id.y * GROUPS_X * 64u + id.x, true);
}

// After the sort: each tile's first pair (into out_ranges.x) and end (into bin_cursors).
@compute @workgroup_size(64)
fn scatter_ranges(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * GROUPS_X * 64u + id.x;
    let pairs = bin_offsets[cull.light_count * SCATTER_LANES];
    if i >= pairs {
        return;
    }
    let k = pair_keys[i];
    if i == 0u || pair_keys[i - 1u] != k {
        out_ranges[k].x = i;
    }
    if i + 1u == pairs || pair_keys[i + 1u] != k {
        atomicStore(&bin_cursors[k], i + 1u);
    }
}

// (start, end) to (offset, count); empty tiles stay (0, 0).
@compute @workgroup_size(64)
fn scatter_finalize(@builtin(global_invocation_id) id: vec3<u32>) {
    let b = id.y * GROUPS_X * 64u + id.x;
    if b < cull.bins {
        let end = atomicLoad(&bin_cursors[b]);
        let start = out_ranges[b].x;
        var count = select(0u, end - start, end > 0u);
        // A deliberate capacity keeps each tile's lowest-indexed lights and counts the rest.
        if cull.capacity != 0u && count > cull.capacity {
            atomicAdd(&cull_stats[0], count - cull.capacity);
            count = cull.capacity;
        }
        out_ranges[b] = vec2<u32>(select(0u, start, count > 0u), count);
    }
}

// The count pass with tile masks (tile_masks.wgsl; the fill is the masks' fill of the gather
// modules): the blocks cull.depth_bounds queued (block_queue, here in out_indices), a block of
// SCATTER_MASK_THREADS tiles of a light's rectangle at a time, a tile a thread, each workgroup
// taking every n-th block for n workgroups: a large light's tiles are shared by many
// workgroups, and no workgroup walks one light's thousands of tiles alone. The rectangles are
// in pair_keys (two words a light).
@compute @workgroup_size(SCATTER_MASK_THREADS)
fn scatter_masks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) slot: u32) {
    if slot == 0u {
        atomicStore(&wg_kept, 0u);
        wg_mask_blocks = atomicLoad(&cull_stats[6]);
    }
    let blocks = workgroupUniformLoad(&wg_mask_blocks);
    let words = mask_words();
    var kept = 0u;
    for (var q = wg.x; q < blocks; q += groups.x) {
        let i = out_indices[2u * q];
        let k = out_indices[2u * q + 1u] * SCATTER_MASK_THREADS + slot;
        // The light in view space, once a block.
        if slot == 0u {
            wg_mask_light = cull_light(lights[i]);
        }
        workgroupBarrier();
        let l = wg_mask_light;
        workgroupBarrier();
        let packed = vec2<u32>(pair_keys[2u * i], pair_keys[2u * i + 1u]);
        let rect = vec4<u32>(packed.x & 0xffffu, packed.x >> 16u, packed.y & 0xffffu, packed.y >> 16u);
        let width = rect.z - rect.x + 1u;
        if k < width * (rect.w - rect.y + 1u) {
            let tile = vec2<u32>(rect.x + k % width, rect.y + k / width);
            let bin = tile.y * cull.tiles_x + tile.x;
            if tile_keeps_at(l, tile, tile_side_planes(tile), tile_depth[bin]) {
                atomicOr(&tile_masks[bin * words + i / 32u], 1u << (i % 32u));
                kept += 1u;
            }
        }
    }
    add_kept_total(slot, kept);
}
