// scan: exclusive prefix sum of u32, in place, portable (assumes no subgroup size).
// scan_blocks scans blocks of SCAN_BLOCK = 1024 elements (256 threads x 4) with a Hillis-Steele
// scan in workgroup memory and writes each block's total; the host scans the block totals the
// same way (recursively) and scan_add adds them back; where n is small, scan_single does it all
// in one pass (scan_single, below). Host side: manylights_cull::scan.
struct ScanParams {
    n: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> block_sums: array<u32>;

var<workgroup> sh: array<u32, SCAN_THREADS>;

@compute @workgroup_size(SCAN_THREADS)
fn scan_blocks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let block = wg.y * SCAN_MAX_GROUPS_X + wg.x;
    let base = block * SCAN_BLOCK + li * SCAN_PER_THREAD;
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
    sh[li] = sum;
    workgroupBarrier();
    for (var offset = 1u; offset < SCAN_THREADS; offset <<= 1u) {
        var t = 0u;
        if li >= offset {
            t = sh[li - offset];
        }
        workgroupBarrier();
        sh[li] += t;
        workgroupBarrier();
    }
    let prefix = sh[li] - sum;
    for (var k = 0u; k < SCAN_PER_THREAD; k++) {
        let idx = base + k;
        if idx < params.n {
            data[idx] = prefix + local[k];
        }
    }
    if li == SCAN_THREADS - 1u {
        block_sums[block] = sh[li];
    }
}

@compute @workgroup_size(SCAN_THREADS)
fn scan_add(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let block = wg.y * SCAN_MAX_GROUPS_X + wg.x;
    let add = block_sums[block];
    for (var k = 0u; k < SCAN_PER_THREAD; k++) {
        let idx = block * SCAN_BLOCK + li * SCAN_PER_THREAD + k;
        if idx < params.n {
            data[idx] += add;
        }
    }
}

// scan_single: the whole scan in one workgroup and one pass, where n is at most SCAN_THREADS x
// SCAN_SINGLE_PER_THREAD (the host's SCAN_SINGLE_MAX): each thread loads a
// run of up to SCAN_SINGLE_PER_THREAD consecutive elements at once (all loads in flight
// together), the threads' sums are scanned as scan_blocks scans them, and each thread writes
// its run's prefixes. One pass where the block scan takes three (the blocks, their totals, the
// add back), each after the gap between dependent passes.
// The run of thread li: [li * per, li * per + per) of n, per = ceil(n / SCAN_THREADS).
fn single_run(li: u32) -> vec2<u32> {
    let per = (params.n + SCAN_THREADS - 1u) / SCAN_THREADS;
    let begin = min(li * per, params.n);
    return vec2<u32>(begin, min(begin + per, params.n));
}

@compute @workgroup_size(SCAN_THREADS)
fn scan_single(@builtin(local_invocation_index) li: u32) {
    let run = single_run(li);
    var vals: array<u32, SCAN_SINGLE_PER_THREAD>;
    var sum = 0u;
    for (var k = 0u; k < SCAN_SINGLE_PER_THREAD; k++) {
        var x = 0u;
        if run.x + k < run.y {
            x = data[run.x + k];
        }
        vals[k] = x;
        sum += x;
    }
    sh[li] = sum;
    workgroupBarrier();
    for (var offset = 1u; offset < SCAN_THREADS; offset <<= 1u) {
        var t = 0u;
        if li >= offset {
            t = sh[li - offset];
        }
        workgroupBarrier();
        sh[li] += t;
        workgroupBarrier();
    }
    var acc = sh[li] - sum;
    for (var k = 0u; k < SCAN_SINGLE_PER_THREAD; k++) {
        if run.x + k < run.y {
            data[run.x + k] = acc;
        }
        acc += vals[k];
    }
}
