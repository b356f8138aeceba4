// The portable workgroup scan of cull.tiled_gather and its count and fill entry points (see
// tiled_gather.wgsl); gather_scan_subgroup.wgsl is the same with subgroup operations. Here a
// thread's slot is its local_invocation_index.
var<workgroup> wg_keep: array<u32, 64 * MASK_FILL_TILES>;

// (inclusive prefix of `value` over slots 64 (slot / 64)..=slot, total over those 64 slots):
// each 64 slots of the workgroup (one, or MASK_FILL_TILES in the masks' fill) are scanned on
// their own. A Hillis-Steele scan, 6 steps. Called in uniform control flow; workgroup memory
// is free again when it returns.
fn scan_keep(slot: u32, value: u32) -> vec2<u32> {
    return scan_keep_n(slot, value, 64u);
}

// As scan_keep, over each n slots (a power of two up to the workgroup's size).
fn scan_keep_n(slot: u32, value: u32, n: u32) -> vec2<u32> {
    let lane = slot % n;
    wg_keep[slot] = value;
    workgroupBarrier();
    for (var off = 1u; off < n; off <<= 1u) {
        var v = 0u;
        if lane >= off {
            v = wg_keep[slot - off];
        }
        workgroupBarrier();
        wg_keep[slot] += v;
        workgroupBarrier();
    }
    let r = vec2<u32>(wg_keep[slot], wg_keep[slot - lane + n - 1u]);
    workgroupBarrier();
    return r;
}

@compute @workgroup_size(64)
fn gather_count(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    gather_chunk(wg, li, CHUNK_COUNT);
}

@compute @workgroup_size(64)
fn gather_fill(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    gather_chunk(wg, li, CHUNK_FILL);
}

@compute @workgroup_size(64)
fn gather_count_masks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    gather_chunk(wg, li, CHUNK_MASK);
}

@compute @workgroup_size(64 * MASK_FILL_TILES)
fn gather_fill_masks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    masks_expand(wg.xy, li);
}

@compute @workgroup_size(LINE_GROUP_THREADS)
fn gather_lines_count(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    lines_tile(wg.xy, li, false);
}

@compute @workgroup_size(LINE_GROUP_THREADS)
fn gather_lines_fill(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    lines_tile(wg.xy, li, true);
}

@compute @workgroup_size(64)
fn gather_count_flat(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    gather_flat(wg.xy, li, false);
}

@compute @workgroup_size(64)
fn gather_fill_flat(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    gather_flat(wg.xy, li, true);
}

// Coarse-to-fine gather's lines (tiled_gather.wgsl): the bit of `slot` into line c of the set
// at `base` for each bit c of `spans`, through workgroup atomics. Called in uniform control flow.
fn mark_lines(slot: u32, spans: u32, base: u32) {
    let bit = 1u << (slot % 32u);
    let word = base + slot / 32u;
    var s = spans;
    while s != 0u {
        let c = firstTrailingBit(s);
        s &= s - 1u;
        atomicOr(&wg_lines[word + 2u * c], bit);
    }
}
