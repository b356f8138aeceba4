// scan: exclusive prefix sum of u32, in place, portable (assumes no subgroup size).
// scan_blocks scans blocks of SCAN_BLOCK = 1024 elements (256 threads x 4) with a Hillis-Steele
// scan in workgroup memory and writes each block's total; the host scans the block totals the
// same way (recursively) and scan_add adds them back. Host side: manylights_cull::scan.
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
