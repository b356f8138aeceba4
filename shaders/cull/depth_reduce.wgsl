// cull.depth_bounds' workgroup reductions, portable: each thread's values straight into the
// workgroup atomics.

// This thread's index in the workgroup (what the subgroup variant elects a lane by).
var<private> p_index: u32;
fn reduce_bounds(zmin: u32, zmax: u32, count: u32) {
    if count != 0u {
        atomicMin(&wg_zmin, zmin);
        atomicMax(&wg_zmax, zmax);
        atomicAdd(&wg_covered, count);
    }
}

fn reduce_mask(mask: u32) {
    if mask != 0u {
        atomicOr(&wg_mask, mask);
    }
}
