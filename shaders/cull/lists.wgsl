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
@group(0) @binding(1) var<storage, read> lights: array<Light>;

// Appends light `light` to bin `bin` (count pass: counts; fill pass: writes).
fn emit(bin: u32, light: u32, fill: bool) {
    if fill {
        let slot = bin_offsets[bin] + atomicAdd(&bin_cursors[bin], 1u);
        out_indices[slot] = light;
    } else {
        atomicAdd(&bin_counts[bin], 1u);
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

// Clusters that hold covered pixels (CULL_FLAG_SKIP_EMPTY), written by cluster_occupancy.
@group(1) @binding(8) var<storage, read_write> occupancy: array<u32>;
