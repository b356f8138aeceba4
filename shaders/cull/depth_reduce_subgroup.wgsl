// cull.depth_bounds' workgroup reductions with subgroup operations: each subgroup reduces its
// threads' values, and one lane of it updates the workgroup atomics (one atomic per subgroup,
// not per thread). Called in uniform control flow.

var<private> p_index: u32;

// Whether this thread is its subgroup's first active lane (in uniform control flow: lane 0).
fn first_lane() -> bool {
    return subgroupBroadcastFirst(p_index) == p_index;
}
fn reduce_bounds(zmin: u32, zmax: u32, count: u32) {
    let first = first_lane();
    let lo = subgroupMin(zmin);
    let hi = subgroupMax(zmax);
    let total = subgroupAdd(count);
    if first && total != 0u {
        atomicMin(&wg_zmin, lo);
        atomicMax(&wg_zmax, hi);
        atomicAdd(&wg_covered, total);
    }
}

fn reduce_mask(mask: u32) {
    let first = first_lane();
    let all_cells = subgroupOr(mask);
    if first && all_cells != 0u {
        atomicOr(&wg_mask, all_cells);
    }
}
