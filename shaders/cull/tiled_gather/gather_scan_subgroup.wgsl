// The workgroup scan of cull.tiled_gather with subgroup operations, and its count and fill
// entry points (see tiled_gather.wgsl and the portable gather_scan.wgsl). A thread's slot is
// subgroup_id * subgroup_size + lane, so that lane order is slot order whatever the layout of
// subgroups in the workgroup (any subgroup size that divides 64).
var<workgroup> sg_sums: array<u32, 64 * MASK_FILL_TILES>;
var<private> g_lane: u32;
var<private> g_sg_size: u32;
var<private> g_sg_id: u32;
var<private> g_sg_count: u32;

fn subgroup_slot(lane: u32, size: u32, id: u32, count: u32) -> u32 {
    g_lane = lane;
    g_sg_size = size;
    g_sg_id = id;
    g_sg_count = count;
    return id * size + lane;
}

// (inclusive prefix of `value` over slots 64 (slot / 64)..=slot, total over those 64 slots):
// each 64 slots of the workgroup (one, or MASK_FILL_TILES in the masks' fill) are scanned on
// their own. An inclusive add within each subgroup, the totals of the segment's subgroups
// across them; two barriers. Called in uniform control flow; workgroup memory is free again
// when it returns.
fn scan_keep(slot: u32, value: u32) -> vec2<u32> {
    return scan_keep_n(slot, value, 64u);
}

// As scan_keep, over each n slots (a power of two up to the workgroup's size, and no smaller
// than a subgroup: gather_subgroups_fit on the host).
fn scan_keep_n(slot: u32, value: u32, n: u32) -> vec2<u32> {
    let inclusive = subgroupInclusiveAdd(value);
    if g_lane == g_sg_size - 1u {
        sg_sums[g_sg_id] = inclusive;
    }
    workgroupBarrier();
    var before = 0u;
    var total = 0u;
    // The subgroups of this slot's n (subgroup sizes divide n).
    let per = n / g_sg_size;
    let seg = g_sg_id / per * per;
    for (var s = seg; s < seg + per; s++) {
        let v = sg_sums[s];
        if s < g_sg_id {
            before += v;
        }
        total += v;
    }
    workgroupBarrier();
    return vec2<u32>(before + inclusive, total);
}

// Coarse-to-fine gather's lines (tiled_gather.wgsl): the bit of `slot` into line c of the set
// at `base` for each bit c of `spans`. A ballot per line that some lane of the subgroup spans,
// written by the subgroup's first lane: no workgroup atomics contend when large lights span
// many lines. Called in uniform control flow.
fn mark_lines(slot: u32, spans: u32, base: u32) {
    var used = subgroupOr(spans);
    while used != 0u {
        let c = firstTrailingBit(used);
        used &= used - 1u;
        let b = subgroupBallot(((spans >> c) & 1u) != 0u);
        if g_lane == 0u {
            let word = base + 2u * c;
            if g_sg_size == 64u {
                atomicStore(&wg_lines[word], b.x);
                atomicStore(&wg_lines[word + 1u], b.y);
            } else {
                let first = g_sg_id * g_sg_size;
                atomicOr(&wg_lines[word + first / 32u], b.x << (first % 32u));
            }
        }
    }
}

@compute @workgroup_size(64)
fn gather_count(@builtin(workgroup_id) wg: vec3<u32>, @builtin(subgroup_invocation_id) lane: u32, @builtin(subgroup_size) size: u32, @builtin(subgroup_id) id: u32, @builtin(num_subgroups) count: u32) {
    gather_chunk(wg, subgroup_slot(lane, size, id, count), CHUNK_COUNT);
}

@compute @workgroup_size(64)
fn gather_fill(@builtin(workgroup_id) wg: vec3<u32>, @builtin(subgroup_invocation_id) lane: u32, @builtin(subgroup_size) size: u32, @builtin(subgroup_id) id: u32, @builtin(num_subgroups) count: u32) {
    gather_chunk(wg, subgroup_slot(lane, size, id, count), CHUNK_FILL);
}

@compute @workgroup_size(64)
fn gather_count_masks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(subgroup_invocation_id) lane: u32, @builtin(subgroup_size) size: u32, @builtin(subgroup_id) id: u32, @builtin(num_subgroups) count: u32) {
    gather_chunk(wg, subgroup_slot(lane, size, id, count), CHUNK_MASK);
}

@compute @workgroup_size(64 * MASK_FILL_TILES)
fn gather_fill_masks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(subgroup_invocation_id) lane: u32, @builtin(subgroup_size) size: u32, @builtin(subgroup_id) id: u32, @builtin(num_subgroups) count: u32) {
    masks_expand(wg.xy, subgroup_slot(lane, size, id, count));
}

@compute @workgroup_size(LINE_GROUP_THREADS)
fn gather_lines_count(@builtin(workgroup_id) wg: vec3<u32>, @builtin(subgroup_invocation_id) lane: u32, @builtin(subgroup_size) size: u32, @builtin(subgroup_id) id: u32, @builtin(num_subgroups) count: u32) {
    lines_tile(wg.xy, subgroup_slot(lane, size, id, count), false);
}

@compute @workgroup_size(LINE_GROUP_THREADS)
fn gather_lines_fill(@builtin(workgroup_id) wg: vec3<u32>, @builtin(subgroup_invocation_id) lane: u32, @builtin(subgroup_size) size: u32, @builtin(subgroup_id) id: u32, @builtin(num_subgroups) count: u32) {
    lines_tile(wg.xy, subgroup_slot(lane, size, id, count), true);
}

@compute @workgroup_size(64)
fn gather_count_flat(@builtin(workgroup_id) wg: vec3<u32>, @builtin(subgroup_invocation_id) lane: u32, @builtin(subgroup_size) size: u32, @builtin(subgroup_id) id: u32, @builtin(num_subgroups) count: u32) {
    gather_flat(wg.xy, subgroup_slot(lane, size, id, count), false);
}

@compute @workgroup_size(64)
fn gather_fill_flat(@builtin(workgroup_id) wg: vec3<u32>, @builtin(subgroup_invocation_id) lane: u32, @builtin(subgroup_size) size: u32, @builtin(subgroup_id) id: u32, @builtin(num_subgroups) count: u32) {
    gather_flat(wg.xy, subgroup_slot(lane, size, id, count), true);
}
