// sort.radix: a stable LSD radix sort of (u32 key, u32 value) pairs, RADIX_BITS = 8 bits a
// pass, portable (assumes no subgroup size). Host side: manylights_cull::radix_sort.
//
// Each pass: sort_count counts every block's digits into hist, laid out digit-major
// (hist[digit * blocks + block]), so that one exclusive scan of hist (the portable scan) gives
// each (digit, block) its first output slot. sort_scatter then sorts its block by digit in
// workgroup memory and writes the block out in that order, so that consecutive threads write
// consecutive slots of each digit's run.
//
// The in-block sort is two stable counting sorts on the digit's nibbles (low, then high; the
// high one is skipped when this pass's digits fit in 4 bits). Each ranks 16 bins the way a
// 4-bit pass would: a thread's 16 counters are packed into the 16-bit fields of two vec4<u32>
// (a block holds SORT_BLOCK = 4096 keys, so no field overflows) and scanned across the
// workgroup with a Hillis-Steele scan. What is sorted is a packed slot, digit << 16 | the key's
// position in the block; the key and value are read again through that position when written.
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
// The block's packed slots, one padding word after every 32 (see `skew`).
var<workgroup> sh_slots: array<u32, SORT_BLOCK + SORT_BLOCK / 32u>;
// Per digit: its first output slot minus its first position in the sorted block.
var<workgroup> sh_off: array<u32, RADIX>;

fn digit_of(key: u32) -> u32 {
    return (key >> sp.shift) & sp.digit_mask;
}

// Workgroup-memory address of position e: one word of padding per 32, so that a thread reading
// its own 16 consecutive positions (stride 16 across a subgroup) meets no bank conflicts.
fn skew(e: u32) -> u32 {
    return e + (e >> 5u);
}

@compute @workgroup_size(SORT_THREADS)
fn sort_count(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let block = wg.y * GROUPS_X + wg.x;
    atomicStore(&wg_hist[li], 0u);
    workgroupBarrier();
    for (var k = 0u; k < SORT_PER_THREAD; k++) {
        let idx = block * SORT_BLOCK + k * SORT_THREADS + li;
        if idx < sp.n {
            atomicAdd(&wg_hist[digit_of(keys_in[idx])], 1u);
        }
    }
    workgroupBarrier();
    if li <= sp.digit_mask && block < sp.blocks {
        hist[li * sp.blocks + block] = atomicLoad(&wg_hist[li]);
    }
}

// 16-bit field `d` of the packed counters (lo: bins 0..7, hi: bins 8..15).
fn field(lo: vec4<u32>, hi: vec4<u32>, d: u32) -> u32 {
    let v = select(lo, hi, d >= 8u);
    return (v[(d & 7u) >> 1u] >> ((d & 1u) * 16u)) & 0xffffu;
}

// One stable counting sort of the block on the nibble at bit `at` of the packed slots: thread
// li holds positions li * SORT_PER_THREAD + k, in order, and writes each to its sorted place in
// sh_slots. Called in uniform control flow; ends with a barrier.
fn split(li: u32, p: ptr<function, array<u32, SORT_PER_THREAD>>, at: u32) {
    var rank: array<u32, SORT_PER_THREAD>;
    var lo = vec4<u32>(0u);
    var hi = vec4<u32>(0u);
    for (var k = 0u; k < SORT_PER_THREAD; k++) {
        let d = ((*p)[k] >> at) & 15u;
        rank[k] = field(lo, hi, d);
        let one = 1u << ((d & 1u) * 16u);
        if d < 8u {
            lo[d >> 1u] += one;
        } else {
            hi[(d - 8u) >> 1u] += one;
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
    // Exclusive: counts of the threads before this one; bin starts from the block's totals.
    let ex_lo = sh_lo[li] - lo;
    let ex_hi = sh_hi[li] - hi;
    let tot_lo = sh_lo[SORT_THREADS - 1u];
    let tot_hi = sh_hi[SORT_THREADS - 1u];
    var start: array<u32, 16>;
    var acc = 0u;
    for (var d = 0u; d < 16u; d++) {
        start[d] = acc;
        acc += field(tot_lo, tot_hi, d);
    }
    for (var k = 0u; k < SORT_PER_THREAD; k++) {
        let d = ((*p)[k] >> at) & 15u;
        sh_slots[skew(start[d] + field(ex_lo, ex_hi, d) + rank[k])] = (*p)[k];
    }
    workgroupBarrier();
}

@compute @workgroup_size(SORT_THREADS)
fn sort_scatter(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let block = wg.y * GROUPS_X + wg.x;
    let base = block * SORT_BLOCK;
    let valid = min(sp.n - min(sp.n, base), SORT_BLOCK);
    // Load coalesced; positions past the end get digit 255 and sort after every key (they
    // come last, and both counting sorts are stable), where nothing writes them.
    for (var k = 0u; k < SORT_PER_THREAD; k++) {
        let e = k * SORT_THREADS + li;
        var d = 255u;
        if e < valid {
            d = digit_of(keys_in[base + e]);
        }
        sh_slots[skew(e)] = (d << 16u) | e;
    }
    workgroupBarrier();
    var p: array<u32, SORT_PER_THREAD>;
    for (var k = 0u; k < SORT_PER_THREAD; k++) {
        p[k] = sh_slots[skew(li * SORT_PER_THREAD + k)];
    }
    workgroupBarrier();
    split(li, &p, 16u);
    if sp.digit_mask > 15u {
        for (var k = 0u; k < SORT_PER_THREAD; k++) {
            p[k] = sh_slots[skew(li * SORT_PER_THREAD + k)];
        }
        workgroupBarrier();
        split(li, &p, 20u);
    }
    // Each digit's first sorted position sets its offset; then write in sorted order.
    for (var k = 0u; k < SORT_PER_THREAD; k++) {
        let s = k * SORT_THREADS + li;
        p[k] = sh_slots[skew(s)];
        let d = p[k] >> 16u;
        if s < valid && (s == 0u || (sh_slots[skew(s - 1u)] >> 16u) != d) {
            sh_off[d] = hist[d * sp.blocks + block] - s;
        }
    }
    workgroupBarrier();
    for (var k = 0u; k < SORT_PER_THREAD; k++) {
        let s = k * SORT_THREADS + li;
        if s < valid {
            let e = p[k] & 0xffffu;
            let dest = sh_off[p[k] >> 16u] + s;
            keys_out[dest] = keys_in[base + e];
            vals_out[dest] = vals_in[base + e];
        }
    }
}
