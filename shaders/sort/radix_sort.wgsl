// sort.radix: a stable LSD radix sort of (u32 key, u32 value) pairs, RADIX_BITS bits a pass,
// portable (assumes no subgroup size). Host side: manylights_cull::radix_sort.
//
// Each pass: sort_count counts every block's digits into hist, laid out digit-major
// (hist[digit * blocks + block]), so that one exclusive scan of hist (the portable scan) gives
// each (digit, block) its first output slot; sort_scatter then ranks each key among the equal
// digits of its block, in order, and writes it there. Ranking packs a thread's 16 digit counters
// into 16-bit fields of two vec4<u32> (a block holds at most SORT_BLOCK = 1024 keys, so no field
// overflows) and scans them across the workgroup with a Hillis-Steele scan.
struct SortParams {
    n: u32,
    shift: u32,
    blocks: u32,
    // Digit mask of this pass: RADIX - 1, or fewer bits in a last pass that reaches past the
    // key bits asked for (so that exactly those bits are sorted).
    digit_mask: u32,
}

@group(0) @binding(0) var<uniform> sp: SortParams;
@group(0) @binding(1) var<storage, read_write> keys_in: array<u32>;
@group(0) @binding(2) var<storage, read_write> vals_in: array<u32>;
@group(0) @binding(3) var<storage, read_write> keys_out: array<u32>;
@group(0) @binding(4) var<storage, read_write> vals_out: array<u32>;
@group(0) @binding(5) var<storage, read_write> hist: array<u32>;

var<workgroup> wg_hist: array<atomic<u32>, RADIX>;
var<workgroup> sh_lo: array<vec4<u32>, SORT_THREADS>;
var<workgroup> sh_hi: array<vec4<u32>, SORT_THREADS>;

fn digit_of(key: u32) -> u32 {
    return (key >> sp.shift) & sp.digit_mask;
}

@compute @workgroup_size(SORT_THREADS)
fn sort_count(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let block = wg.y * GROUPS_X + wg.x;
    if li < RADIX {
        atomicStore(&wg_hist[li], 0u);
    }
    workgroupBarrier();
    for (var k = 0u; k < SORT_PER_THREAD; k++) {
        let idx = block * SORT_BLOCK + li * SORT_PER_THREAD + k;
        if idx < sp.n {
            atomicAdd(&wg_hist[digit_of(keys_in[idx])], 1u);
        }
    }
    workgroupBarrier();
    if li < RADIX && block < sp.blocks {
        hist[li * sp.blocks + block] = atomicLoad(&wg_hist[li]);
    }
}

// 16-bit field `d` of the packed counters (lo: digits 0..7, hi: digits 8..15).
fn field(lo: vec4<u32>, hi: vec4<u32>, d: u32) -> u32 {
    let v = select(lo, hi, d >= 8u);
    return (v[(d & 7u) >> 1u] >> ((d & 1u) * 16u)) & 0xffffu;
}

@compute @workgroup_size(SORT_THREADS)
fn sort_scatter(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let block = wg.y * GROUPS_X + wg.x;
    var keys: array<u32, SORT_PER_THREAD>;
    var vals: array<u32, SORT_PER_THREAD>;
    var rank: array<u32, SORT_PER_THREAD>;
    var lo = vec4<u32>(0u);
    var hi = vec4<u32>(0u);
    for (var k = 0u; k < SORT_PER_THREAD; k++) {
        let idx = block * SORT_BLOCK + li * SORT_PER_THREAD + k;
        if idx < sp.n {
            keys[k] = keys_in[idx];
            vals[k] = vals_in[idx];
            let d = digit_of(keys[k]);
            rank[k] = field(lo, hi, d);
            let one = 1u << ((d & 1u) * 16u);
            if d < 8u {
                lo[d >> 1u] += one;
            } else {
                hi[(d - 8u) >> 1u] += one;
            }
        }
    }
    sh_lo[li] = lo;
    sh_hi[li] = hi;
    workgroupBarrier();
    for (var offset = 1u; offset < SORT_THREADS; offset <<= 1u) {
        var tl = vec4<u32>(0u);
        var th = vec4<u32>(0u);
        if li >= offset {
            tl = sh_lo[li - offset];
            th = sh_hi[li - offset];
        }
        workgroupBarrier();
        sh_lo[li] += tl;
        sh_hi[li] += th;
        workgroupBarrier();
    }
    // Exclusive: counts of the threads before this one.
    let ex_lo = sh_lo[li] - lo;
    let ex_hi = sh_hi[li] - hi;
    for (var k = 0u; k < SORT_PER_THREAD; k++) {
        let idx = block * SORT_BLOCK + li * SORT_PER_THREAD + k;
        if idx < sp.n {
            let d = digit_of(keys[k]);
            let dest = hist[d * sp.blocks + block] + field(ex_lo, ex_hi, d) + rank[k];
            keys_out[dest] = keys[k];
            vals_out[dest] = vals[k];
        }
    }
}
