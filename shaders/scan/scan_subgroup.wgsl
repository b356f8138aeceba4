// scan_blocks_subgroup: the same block scan as scan_blocks, with subgroup operations where the
// adapter has them (any subgroup size that divides SCAN_THREADS). Each thread takes the slot
// (subgroup_id * subgroup_size + lane), so lane order is element order whatever the layout of
// subgroups in the workgroup; subgroup totals are scanned by the first thread.
var<workgroup> sg_totals: array<u32, SCAN_THREADS>;

@compute @workgroup_size(SCAN_THREADS)
fn scan_blocks_subgroup(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
    @builtin(subgroup_invocation_id) lane: u32,
    @builtin(subgroup_size) sg_size: u32,
    @builtin(subgroup_id) sg_id: u32,
    @builtin(num_subgroups) sg_count: u32,
) {
    let block = wg.y * SCAN_MAX_GROUPS_X + wg.x;
    let slot = sg_id * sg_size + lane;
    let base = block * SCAN_BLOCK + slot * SCAN_PER_THREAD;
    var local: array<u32, SCAN_PER_THREAD>;
    var sum = 0u;
    for (var k = 0u; k < SCAN_PER_THREAD; k++) {
        let idx = base + k;
        var x = 0u;
        if idx < params.n {
            x = data[idx];
        }
        local[k] = sum;
        sum += x;
    }
    let inclusive = subgroupInclusiveAdd(sum);
    if lane == sg_size - 1u {
        sg_totals[sg_id] = inclusive;
    }
    workgroupBarrier();
    if li == 0u {
        var acc = 0u;
        for (var s = 0u; s < sg_count; s++) {
            let t = sg_totals[s];
            sg_totals[s] = acc;
            acc += t;
        }
        sg_totals[sg_count] = acc;
    }
    workgroupBarrier();
    let prefix = sg_totals[sg_id] + inclusive - sum;
    for (var k = 0u; k < SCAN_PER_THREAD; k++) {
        let idx = base + k;
        if idx < params.n {
            data[idx] = prefix + local[k];
        }
    }
    if li == 0u {
        block_sums[block] = sg_totals[sg_count];
    }
}
