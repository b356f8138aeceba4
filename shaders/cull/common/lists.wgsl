// Buffers of the light lists, shared by the count, fill and finalize passes of every strategy.
// Sizing is exact: a count pass counts each bin's lights, an exclusive scan turns the counts
// into offsets (bin_offsets[bins] is the total), the host sizes light_indices from that total,
// and a fill pass writes each light at bin_offsets[bin] + a per-bin cursor.
@group(1) @binding(2) var<storage, read_write> tile_depth: array<TileDepth>;
@group(1) @binding(3) var<storage, read_write> bin_counts: array<atomic<u32>>;
@group(1) @binding(4) var<storage, read_write> bin_offsets: array<u32>;
@group(1) @binding(5) var<storage, read_write> bin_cursors: array<atomic<u32>>;
@group(1) @binding(6) var<storage, read_write> out_ranges: array<vec2<u32>>;
@group(1) @binding(7) var<storage, read_write> out_indices: array<u32>;

// Statistics: [0] = lights dropped by a deliberate capacity; [1], [2] = tiled scatter's pair
// total, low word and carries; [4] = the list total with tile masks, [5] = the cursor from
// which their fill places each tile's list; [6] = the blocks tiled scatter queued for its
// masks' count pass (depth_bounds.wgsl); [3], [7] = the clusters' tile path's total and
// cursor (cluster_tiles.wgsl); [8], [9] = the clusters' lists to sort, short and long
// (cull.clustered.order_lists).
@group(1) @binding(10) var<storage, read_write> cull_stats: array<atomic<u32>>;

// The lights a workgroup kept into tile masks (zeroed by its first thread at the start).
var<workgroup> wg_kept: atomic<u32>;

// Adds this thread's `kept` lights to the tile masks' list total, cull_stats[4] (gather's and
// tiled scatter's masked count passes): summed in the workgroup first, then one atomic add a
// workgroup. Called in uniform control flow.
fn add_kept_total(slot: u32, kept: u32) {
    if kept != 0u {
        atomicAdd(&wg_kept, kept);
    }
    workgroupBarrier();
    if slot == 0u {
        let k = atomicLoad(&wg_kept);
        if k != 0u {
            atomicAdd(&cull_stats[4], k);
        }
    }
}

// Appends light `light` to bin `bin` (count pass: counts; fill pass: writes, up to the
// capacity when one is set).
fn emit(bin: u32, light: u32, fill: bool) {
    if fill {
        let k = atomicAdd(&bin_cursors[bin], 1u);
        if cull.capacity == 0u || k < cull.capacity {
            out_indices[bin_offsets[bin] + k] = light;
        }
    } else {
        atomicAdd(&bin_counts[bin], 1u);
    }
}

// cull.cap: with a capacity, clamps each bin's count to it and counts what is dropped (which
// lights are dropped depends on the fill order). Runs between the count pass and the scan.
@compute @workgroup_size(64)
fn cap_counts(@builtin(global_invocation_id) id: vec3<u32>) {
    let b = id.y * GROUPS_X * 64u + id.x;
    if b < cull.bins && cull.capacity != 0u {
        let c = atomicLoad(&bin_counts[b]);
        if c > cull.capacity {
            atomicAdd(&cull_stats[0], c - cull.capacity);
            atomicStore(&bin_counts[b], cull.capacity);
        }
    }
}

// cull.finalize: bin_ranges[bin] = (offset, count), one thread per bin.
@compute @workgroup_size(64)
fn finalize(@builtin(global_invocation_id) id: vec3<u32>) {
    let b = id.y * GROUPS_X * 64u + id.x;
    if b < cull.bins {
        out_ranges[b] = vec2<u32>(bin_offsets[b], atomicLoad(&bin_counts[b]));
    }
}

// Clusters that hold covered pixels (CULL_FLAG_SKIP_EMPTY or CULL_FLAG_TILE_BOX), written by
// cluster_occupancy: occupancy[bin] is 1 for a cluster holding a covered pixel, and after the
// bins' flags, at bins + 2 bin, the nearest and farthest linear depth of its pixels as
// (~ordered_bits(dmin), ordered_bits(dmax)), both widened with atomicMax from zero (zero: no
// pixel).
@group(1) @binding(8) var<storage, read_write> occupancy: array<atomic<u32>>;
