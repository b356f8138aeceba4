// sort.radix (onesweep path): a stable LSD radix sort of (u32 key, u32 value) pairs with 8-bit
// digits and one pass over the pairs per digit (Adinets and Merrill 2022, "Onesweep"), for
// adapters with subgroups of 8 to 32 invocations. Host side: manylights_cull::radix_sort.
//
// sort_init zeroes the look-back status, the digit histograms and the partition counters;
// sort_histogram counts every digit of every key, all passes at once, into hist; then one
// sort_onesweep dispatch per digit. A workgroup takes the next partition (OS_PART keys) from an
// atomic counter, ranks its keys by digit with subgroup ballots (each key's peers are the lanes
// whose 8 ballots agree with its digit's bits), publishes its per-digit counts and looks back
// over the partitions before it for their sums (decoupled look-back, Merrill and Garland 2016),
// then writes its keys and values out in digit order through workgroup memory.
//
// Status words pack (pass tag: 2 bits, flag: 2 bits, count: 28 bits); a word from an earlier
// pass reads as "not ready", so one zeroing serves every pass. All the look-back exchanges is in
// those atomic words: no other memory written by another workgroup is read. A partition that is
// not ready after OS_MAX_SPIN polls is counted from its keys by the waiting workgroup instead
// (decoupled fallback, Smith et al. 2024), so no workgroup waits on another's progress: the
// sort needs no forward-progress guarantee between workgroups, and every loop is bounded.
//
// Within a subgroup, ranks come from a running per-subgroup count per digit (16-bit fields in
// workgroup memory), added to by the lowest lane of each group of peers, one key step after
// another; the count's previous value reaches the peers by subgroupShuffle.
struct OnesweepParams {
    n: u32,
    pass_index: u32,
    shift: u32,
    digit_mask: u32,
    digit_bits: u32,
    passes: u32,
    key_bits: u32,
    // Polls of a predecessor's status before counting its keys instead; 0 counts at once.
    max_spin: u32,
    // Nonzero: count every predecessor's keys instead of reading its status (tests).
    fallback_only: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> op: OnesweepParams;
@group(0) @binding(1) var<storage, read_write> keys_in: array<u32>;
@group(0) @binding(2) var<storage, read_write> vals_in: array<u32>;
@group(0) @binding(3) var<storage, read_write> keys_out: array<u32>;
@group(0) @binding(4) var<storage, read_write> vals_out: array<u32>;
// OS_RADIX bins per pass, then (after sort_onesweep's own scan) read as counts.
@group(0) @binding(5) var<storage, read_write> hist: array<atomic<u32>>;
// OS_RADIX words per partition.
@group(0) @binding(6) var<storage, read_write> status: array<atomic<u32>>;
// One partition counter per pass.
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>>;

const FLAG_AGGREGATE: u32 = 1u;
const FLAG_INCLUSIVE: u32 = 2u;
const COUNT_MASK: u32 = 0x0fffffffu;

fn os_digit(key: u32) -> u32 {
    return (key >> op.shift) & op.digit_mask;
}

fn status_word(flag: u32, count: u32) -> u32 {
    return (op.pass_index << 30u) | (flag << 28u) | count;
}

// The flag of a status word of this pass; 0 (not ready) for a word of another pass.
fn status_flag(w: u32) -> u32 {
    return select(0u, (w >> 28u) & 3u, (w >> 30u) == op.pass_index);
}

@compute @workgroup_size(OS_THREADS)
fn sort_init(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    let stride = nw.x * OS_THREADS;
    for (var i = gid.x; i < arrayLength(&status); i += stride) {
        atomicStore(&status[i], 0u);
    }
    if gid.x < arrayLength(&hist) {
        atomicStore(&hist[gid.x], 0u);
    }
    if gid.x < arrayLength(&counters) {
        atomicStore(&counters[gid.x], 0u);
    }
}

var<workgroup> wg_hist: array<atomic<u32>, OS_HIST_BINS>;

// Every pass's digit counts at once: OS_HIST_KEYS keys a workgroup, counted in workgroup memory,
// then added to hist.
@compute @workgroup_size(OS_THREADS)
fn sort_histogram(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let block = wg.y * GROUPS_X + wg.x;
    for (var i = li; i < OS_HIST_BINS; i += OS_THREADS) {
        atomicStore(&wg_hist[i], 0u);
    }
    workgroupBarrier();
    let start = block * OS_HIST_KEYS;
    let end = min(start + OS_HIST_KEYS, op.n);
    for (var idx = start + li; idx < end; idx += OS_THREADS) {
        let key = keys_in[idx];
        for (var p = 0u; p < op.passes; p++) {
            let bits = min(8u, op.key_bits - 8u * p);
            let d = (key >> (8u * p)) & ((1u << bits) - 1u);
            atomicAdd(&wg_hist[p * OS_RADIX + d], 1u);
        }
    }
    workgroupBarrier();
    for (var i = li; i < op.passes * OS_RADIX; i += OS_THREADS) {
        let c = atomicLoad(&wg_hist[i]);
        if c != 0u {
            atomicAdd(&hist[i], c);
        }
    }
}

// Per-subgroup running digit counts (16-bit fields, OS_RADIX / 2 words a subgroup), then the
// partition's keys and values in digit order.
var<workgroup> sh: array<atomic<u32>, OS_SHARED_WORDS>;
var<workgroup> wg_part: u32;
var<workgroup> wg_count: array<u32, OS_RADIX>;
var<workgroup> wg_start: array<u32, OS_RADIX>;
// Output position of slot i of digit d: wg_base[d] + i (wrapping).
var<workgroup> wg_base: array<u32, OS_RADIX>;
var<workgroup> wg_sums: array<u32, OS_MAX_SUBGROUPS * 2u>;
var<workgroup> wg_fallback: array<atomic<u32>, OS_RADIX>;
// The latest partition a digit is stuck behind, plus one (0: none), and its uniform copy.
var<workgroup> wg_stuck: atomic<u32>;
var<workgroup> wg_after: u32;

fn field16(w: u32, d: u32) -> u32 {
    return (w >> ((d & 1u) * 16u)) & 0xffffu;
}

@compute @workgroup_size(OS_THREADS)
fn sort_onesweep(
    @builtin(local_invocation_index) li: u32,
    @builtin(subgroup_invocation_id) lane: u32,
    @builtin(subgroup_size) sg_size: u32,
    @builtin(subgroup_id) sg_id: u32,
    @builtin(num_subgroups) sg_count: u32,
) {
    // Slot of this invocation in subgroup order: its digit in the per-digit steps.
    let t = sg_id * sg_size + lane;
    if li == 0u {
        wg_part = atomicAdd(&counters[op.pass_index], 1u);
    }
    for (var i = li; i < sg_count * (OS_RADIX / 2u); i += OS_THREADS) {
        atomicStore(&sh[i], 0u);
    }
    let part = workgroupUniformLoad(&wg_part);
    let parts = (op.n + OS_PART - 1u) / OS_PART;
    if part >= parts {
        return;
    }
    let first = part * OS_PART;
    let valid = min(OS_PART, op.n - first);

    // Keys, subgroup-major: subgroup s holds keys [s * sg_size * OS_PER_THREAD, ...) of the
    // partition, lane-interleaved, so that (step, lane) order is index order. Values are loaded
    // with them (7% faster at 16M pairs on an H100 than loading them after the keys are out).
    let sg_first = first + sg_id * sg_size * OS_PER_THREAD;
    var keys: array<u32, OS_PER_THREAD>;
    var rank: array<u32, OS_PER_THREAD>;
    var vals: array<u32, OS_PER_THREAD>;
    for (var k = 0u; k < OS_PER_THREAD; k++) {
        let idx = sg_first + k * sg_size + lane;
        // Past the end: the largest digit, ranked after every real key of the partition.
        keys[k] = select(0xffffffffu, keys_in[min(idx, op.n - 1u)], idx < op.n);
        vals[k] = vals_in[min(idx, op.n - 1u)];
    }
    let lanes_below = (1u << lane) - 1u;
    let sg_lanes = select((1u << sg_size) - 1u, 0xffffffffu, sg_size == 32u);
    let sg_words = sg_id * (OS_RADIX / 2u);
    for (var k = 0u; k < OS_PER_THREAD; k++) {
        let d = os_digit(keys[k]);
        var peers = sg_lanes;
        for (var b = 0u; b < op.digit_bits; b++) {
            let set_bit = ((d >> b) & 1u) == 1u;
            let ballot = subgroupBallot(set_bit).x;
            peers &= select(~ballot, ballot, set_bit);
        }
        let below = countOneBits(peers & lanes_below);
        var before = 0u;
        if below == 0u {
            let shift = (d & 1u) * 16u;
            before = (atomicAdd(&sh[sg_words + d / 2u], countOneBits(peers) << shift) >> shift)
                & 0xffffu;
        }
        rank[k] = subgroupShuffle(before, countTrailingZeros(peers)) + below;
    }
    workgroupBarrier();

    // Per digit pair: exclusive sums over subgroups (in place) and the partition's counts.
    if li < OS_RADIX / 2u {
        var acc = 0u;
        for (var s = 0u; s < sg_count; s++) {
            let w = atomicLoad(&sh[s * (OS_RADIX / 2u) + li]);
            atomicStore(&sh[s * (OS_RADIX / 2u) + li], acc);
            acc += w;
        }
        wg_count[2u * li] = acc & 0xffffu;
        wg_count[2u * li + 1u] = acc >> 16u;
    }
    workgroupBarrier();

    // Exclusive scans over digits of this partition's counts and of the whole pass's counts.
    var count = 0u;
    var global_count = 0u;
    if t < OS_RADIX {
        count = wg_count[t];
        global_count = atomicLoad(&hist[op.pass_index * OS_RADIX + t]);
    }
    let ex = subgroupExclusiveAdd(count);
    let global_ex = subgroupExclusiveAdd(global_count);
    if lane == sg_size - 1u {
        wg_sums[sg_id] = ex + count;
        wg_sums[OS_MAX_SUBGROUPS + sg_id] = global_ex + global_count;
    }
    workgroupBarrier();
    if li == 0u {
        var a = 0u;
        var g = 0u;
        for (var s = 0u; s < sg_count; s++) {
            let x = wg_sums[s];
            let y = wg_sums[OS_MAX_SUBGROUPS + s];
            wg_sums[s] = a;
            wg_sums[OS_MAX_SUBGROUPS + s] = g;
            a += x;
            g += y;
        }
    }
    workgroupBarrier();
    let start = wg_sums[sg_id] + ex;
    let digit_offset = wg_sums[OS_MAX_SUBGROUPS + sg_id] + global_ex;
    if t < OS_RADIX {
        wg_start[t] = start;
    }
    workgroupBarrier();

    // Each key's place in the partition's digit order.
    for (var k = 0u; k < OS_PER_THREAD; k++) {
        let d = os_digit(keys[k]);
        rank[k] += wg_start[d] + field16(atomicLoad(&sh[sg_words + d / 2u]), d);
    }

    // Publish, then look back (one digit per invocation).
    var real = count;
    if t == op.digit_mask {
        real -= OS_PART - valid;
    }
    if t < OS_RADIX {
        atomicStore(
            &status[part * OS_RADIX + t],
            status_word(select(FLAG_AGGREGATE, FLAG_INCLUSIVE, part == 0u), real),
        );
    }
    // Each digit walks back on its own (no barriers) until it meets an inclusive count or a
    // predecessor still not ready after op.max_spin polls. Then the workgroup counts the keys
    // of the latest such predecessor, the digits stuck there take that count and step past it,
    // and the rest walk on; each round resolves one partition at least.
    var prefix = 0u;
    var done = t >= OS_RADIX || part == 0u;
    var q = part;
    if li == 0u {
        atomicStore(&wg_stuck, 0u);
    }
    workgroupBarrier();
    loop {
        var stuck = false;
        var spins = 0u;
        while !done {
            let w = atomicLoad(&status[(q - 1u) * OS_RADIX + t]);
            let flag = select(status_flag(w), 0u, op.fallback_only != 0u);
            if flag != 0u {
                prefix += w & COUNT_MASK;
                q -= 1u;
                spins = 0u;
                done = flag == FLAG_INCLUSIVE || q == 0u;
            } else {
                spins += 1u;
                if spins > op.max_spin || op.fallback_only != 0u {
                    stuck = true;
                    break;
                }
            }
        }
        if stuck {
            atomicMax(&wg_stuck, q);
        }
        workgroupBarrier();
        if li == 0u {
            wg_after = atomicLoad(&wg_stuck);
            atomicStore(&wg_stuck, 0u);
        }
        // Partition after the latest one not ready; 0: every digit is done.
        let after = workgroupUniformLoad(&wg_after);
        if after == 0u {
            break;
        }
        // Count partition after - 1 from its keys (it is whole: it is not the last).
        for (var i = li; i < OS_RADIX; i += OS_THREADS) {
            atomicStore(&wg_fallback[i], 0u);
        }
        workgroupBarrier();
        for (var k = 0u; k < OS_PER_THREAD; k++) {
            let key = keys_in[(after - 1u) * OS_PART + k * OS_THREADS + li];
            atomicAdd(&wg_fallback[os_digit(key)], 1u);
        }
        workgroupBarrier();
        if stuck && q == after {
            prefix += atomicLoad(&wg_fallback[t]);
            q -= 1u;
            done = q == 0u;
        }
    }
    if t < OS_RADIX {
        if part != 0u {
            atomicStore(&status[part * OS_RADIX + t], status_word(FLAG_INCLUSIVE, prefix + real));
        }
        wg_base[t] = digit_offset + prefix - start;
    }
    workgroupBarrier();

    // Keys through workgroup memory into digit order, then out.
    for (var k = 0u; k < OS_PER_THREAD; k++) {
        atomicStore(&sh[rank[k]], keys[k]);
    }
    workgroupBarrier();
    var dest: array<u32, OS_PER_THREAD>;
    for (var k = 0u; k < OS_PER_THREAD; k++) {
        let i = k * OS_THREADS + li;
        let key = atomicLoad(&sh[i]);
        dest[k] = wg_base[os_digit(key)] + i;
        if i < valid {
            keys_out[dest[k]] = key;
        }
    }
    workgroupBarrier();
    for (var k = 0u; k < OS_PER_THREAD; k++) {
        let idx = sg_first + k * sg_size + lane;
        if idx < op.n {
            atomicStore(&sh[rank[k]], vals[k]);
        }
    }
    workgroupBarrier();
    for (var k = 0u; k < OS_PER_THREAD; k++) {
        let i = k * OS_THREADS + li;
        if i < valid {
            vals_out[dest[k]] = atomicLoad(&sh[i]);
        }
    }
}
