// The clusters' order passes (after cull.clustered.fill and fill_wide, clustered.wgsl): each
// cluster's list, filled by atomics in any order, sorted into light order.

// cull.clustered.order: sorts each cluster's list into light order after the atomic fill, so
// that shading sums a pixel's lights in the same order on every run (bit-identical images).
// One workgroup per cluster. Lists of up to ORDER_LOCAL lights are sorted in workgroup memory;
// longer ones in place in the list buffer (the same network, slower, and rare: a cluster holds
// that many lights only when thousands overlap it). The network is a bitonic sort over the list
// padded to a power of two with virtual +inf entries; in the form used here every
// compare-exchange puts the smaller value at the lower index, so a pair whose upper index is in
// the padding never swaps, and the padding never needs storing.
const ORDER_LOCAL: u32 = 2048u;
// 512 threads where the device allows (Pipelines::new), else 256: on the H100, culling at 1M
// lights in 32-pixel tiles 1.191 against 1.178 ms, and in the hall at 50,000 0.387 against
// 0.379 ms (1,024: no faster).
override ORDER_THREADS: u32 = 256u;
var<workgroup> wg_list: array<u32, ORDER_LOCAL>;
var<workgroup> wg_len: u32;

// Pair `t` of the bitonic step (`k`: the merge size, `d`: the distance; `d == k / 2` is the
// step that compares mirrored positions).
fn order_pair(t: u32, k: u32, d: u32) -> vec2<u32> {
    if d == k / 2u {
        let base = (t / d) * k;
        let pos = t % d;
        return vec2<u32>(base + pos, base + k - 1u - pos);
    }
    let i = (t / d) * 2u * d + t % d;
    return vec2<u32>(i, i + d);
}

// The length of cluster `bin`'s list, the same in every thread of the workgroup. Called in
// uniform control flow.
fn list_len(bin: u32, li: u32) -> u32 {
    if li == 0u {
        var n = 0u;
        if bin < cull.bins {
            n = atomicLoad(&bin_counts[bin]);
        }
        wg_len = n;
    }
    return workgroupUniformLoad(&wg_len);
}

// The network's size: the smallest power of two (at least 2) not below `n`.
fn padded(n: u32) -> u32 {
    var size = 2u;
    while size < n {
        size <<= 1u;
    }
    return size;
}

// cull.clustered.order_lists (after the fill passes, which were the last to read the wide
// lights' queue): a thread a cluster lists those whose lists need sorting in that buffer, the
// short ones (2 to ORDER_SHORT lights) from word 4 on and the long ones from its end back,
// counted in cull_stats[8] and [9] (cleared at the start of the run), with one atomic a
// workgroup and kind; cull.clustered.order_args turns the counts into the order passes'
// indirect dispatches, so that these take a workgroup only for a list to sort. (A workgroup for
// every cluster, most of them with nothing to sort, reserved the order pass's 8 KB and 256
// threads each.)
var<workgroup> wg_order: array<atomic<u32>, 2>;

// The word of listed cluster `k` of `kind` (0: short lists, from word 4 on; 1: long ones, from
// the buffer's end back).
fn order_slot(k: u32, kind: u32) -> u32 {
    return select(4u + k, arrayLength(&wide_lights) - 1u - k, kind == 1u);
}
var<workgroup> wg_order_base: array<u32, 2>;

@compute @workgroup_size(64)
fn cluster_order_lists(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if li < 2u {
        atomicStore(&wg_order[li], 0u);
    }
    workgroupBarrier();
    let bin = id.y * GROUPS_X * 64u + id.x;
    var n = 0u;
    if bin < cull.bins {
        n = atomicLoad(&bin_counts[bin]);
    }
    let kind = select(0u, 1u, n > ORDER_SHORT);
    var at = 0u;
    if n >= 2u {
        at = atomicAdd(&wg_order[kind], 1u);
    }
    workgroupBarrier();
    if li < 2u {
        let m = atomicLoad(&wg_order[li]);
        var base = 0u;
        if m != 0u {
            base = atomicAdd(&cull_stats[8u + li], m);
        }
        wg_order_base[li] = base;
    }
    workgroupBarrier();
    if n >= 2u {
        atomicStore(&wide_lights[order_slot(wg_order_base[kind] + at, kind)], bin);
    }
}

// The order passes' indirect dispatches: a workgroup a listed cluster, laid out as groups_2d
// does (GROUPS_X across); the short lists' at words 0-2 of binding 11, the long ones' at 4-6.
@compute @workgroup_size(1)
fn cluster_order_args() {
    for (var k = 0u; k < 2u; k++) {
        let groups = atomicLoad(&cull_stats[8u + k]);
        cluster_aux[4u * k] = min(groups, GROUPS_X);
        cluster_aux[4u * k + 1u] = (groups + GROUPS_X - 1u) / GROUPS_X;
        cluster_aux[4u * k + 2u] = 1u;
    }
}

// The cluster of the order passes' workgroup `wg`: listed cluster `k` of `kind` (0: short,
// 1: long), or cull.bins (nothing to sort) past the listed ones.
fn order_bin(wg: vec3<u32>, kind: u32) -> u32 {
    let k = wg.y * GROUPS_X + wg.x;
    if k >= atomicLoad(&cull_stats[8u + kind]) {
        return cull.bins;
    }
    return atomicLoad(&wide_lights[order_slot(k, kind)]);
}

@compute @workgroup_size(ORDER_THREADS)
fn cluster_order(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let bin = order_bin(wg, 1u);
    let n = list_len(bin, li);
    // Short lists are cluster_order_short's.
    if n <= ORDER_SHORT {
        return;
    }
    let base = bin_offsets[bin];
    let size = padded(n);
    let local = n <= ORDER_LOCAL;
    if local {
        for (var i = li; i < n; i += ORDER_THREADS) {
            wg_list[i] = out_indices[base + i];
        }
    }
    workgroupBarrier();
    for (var k = 2u; k <= size; k <<= 1u) {
        for (var d = k / 2u; d > 0u; d >>= 1u) {
            for (var t = li; t < size / 2u; t += ORDER_THREADS) {
                let p = order_pair(t, k, d);
                if p.y < n {
                    if local {
                        let a = wg_list[p.x];
                        let b = wg_list[p.y];
                        if a > b {
                            wg_list[p.x] = b;
                            wg_list[p.y] = a;
                        }
                    } else {
                        let a = out_indices[base + p.x];
                        let b = out_indices[base + p.y];
                        if a > b {
                            out_indices[base + p.x] = b;
                            out_indices[base + p.y] = a;
                        }
                    }
                }
            }
            // Only the in-place sort reads what other threads wrote to storage.
            if !local {
                storageBarrier();
            }
            workgroupBarrier();
        }
    }
    if local {
        for (var i = li; i < n; i += ORDER_THREADS) {
            out_indices[base + i] = wg_list[i];
        }
    }
}

// cull.clustered.order_short: the lists of 2 to ORDER_SHORT lights, with the same network in
// ORDER_SHORT words of workgroup memory and 128 threads, so that the many short lists do not pay
// cluster_order's 8 KB and 256 threads a workgroup (these bound how many workgroups run at
// once). In the hall at 50,000 lights (H100) the pass took 29 µs with 128 threads, 42 with 64
// and 70 with 32.
const ORDER_SHORT: u32 = 512u;
const ORDER_SHORT_THREADS: u32 = 128u;
var<workgroup> wg_short: array<u32, ORDER_SHORT>;

@compute @workgroup_size(ORDER_SHORT_THREADS)
fn cluster_order_short(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let bin = order_bin(wg, 0u);
    let n = list_len(bin, li);
    if n < 2u || n > ORDER_SHORT {
        return;
    }
    let base = bin_offsets[bin];
    if n >= ORDER_BITS_SHORT && (cull.flags & CULL_FLAG_ORDER_BITS) != 0u {
        bits_sort(base, n, li, ORDER_SHORT_THREADS);
        return;
    }
    let size = padded(n);
    for (var i = li; i < n; i += ORDER_SHORT_THREADS) {
        wg_short[i] = out_indices[base + i];
    }
    workgroupBarrier();
    for (var k = 2u; k <= size; k <<= 1u) {
        for (var d = k / 2u; d > 0u; d >>= 1u) {
            for (var t = li; t < size / 2u; t += ORDER_SHORT_THREADS) {
                let p = order_pair(t, k, d);
                if p.y < n {
                    let a = wg_short[p.x];
                    let b = wg_short[p.y];
                    if a > b {
                        wg_short[p.x] = b;
                        wg_short[p.y] = a;
                    }
                }
            }
            workgroupBarrier();
        }
    }
    for (var i = li; i < n; i += ORDER_SHORT_THREADS) {
        out_indices[base + i] = wg_short[i];
    }
}

// The rank sort through a bitmap of the light indices (CULL_FLAG_ORDER_BITS, for runs of at
// most CLUSTER_ORDER_BITS_LIGHTS lights: cull.clustered.order_bits, and
// cull.clustered.order_short's lists of ORDER_BITS_SHORT lights or more): a bit a light (8 KB
// at most), set by each entry of the list; the
// set bits counted a word at a time and prefix-summed across the threads; then each thread
// writes the lights of its words at their ranks. Four barriers whatever the length, against the
// bitonic network's 66 for 2,048 lights; the cost grows with the lights of the run (a word per
// 32) rather than with the list. Entries are distinct lights (a light enters a cluster's list
// once), so the bits are as many as the entries.
// On the H100 in the hall (20,000 and 50,000 lights), 64 and 128 were as fast (the short
// lists' pass 22-24 µs), 256 slower (24-29) and the network alone slower still (33-41).
const ORDER_BITS_SHORT: u32 = 64u;
var<workgroup> wg_bits: array<atomic<u32>, CLUSTER_ORDER_BITS_LIGHTS / 32u>;
// Each thread's set bits, then (the first threads / 16) each group of 16 threads' sum.
var<workgroup> wg_sums: array<u32, 512>;
var<workgroup> wg_groups: array<u32, 32>;

// Sorts the `n` entries at `base` with `threads` threads (at most 512, a multiple of 16), `li`
// this one. Called in uniform control flow.
fn bits_sort(base: u32, n: u32, li: u32, threads: u32) {
    let words = (cull.light_count + 31u) / 32u;
    for (var w = li; w < words; w += threads) {
        atomicStore(&wg_bits[w], 0u);
    }
    workgroupBarrier();
    for (var i = li; i < n; i += threads) {
        let l = out_indices[base + i];
        atomicOr(&wg_bits[l >> 5u], 1u << (l & 31u));
    }
    workgroupBarrier();
    // Each thread takes a run of words, so that its lights are consecutive in the list.
    let per = (words + threads - 1u) / threads;
    let first = min(li * per, words);
    let last = min(first + per, words);
    var s = 0u;
    for (var w = first; w < last; w++) {
        s += countOneBits(atomicLoad(&wg_bits[w]));
    }
    wg_sums[li] = s;
    workgroupBarrier();
    if li < threads / 16u {
        var g = 0u;
        for (var k = 0u; k < 16u; k++) {
            g += wg_sums[16u * li + k];
        }
        wg_groups[li] = g;
    }
    workgroupBarrier();
    var at = base;
    for (var k = 0u; k < li / 16u; k++) {
        at += wg_groups[k];
    }
    for (var k = li & ~15u; k < li; k++) {
        at += wg_sums[k];
    }
    for (var w = first; w < last; w++) {
        var m = atomicLoad(&wg_bits[w]);
        while m != 0u {
            out_indices[at] = 32u * w + firstTrailingBit(m);
            at++;
            m &= m - 1u;
        }
    }
}

// cull.clustered.order_bits: cull.clustered.order's lists by the bitmap's rank sort, run in its
// place with CULL_FLAG_ORDER_BITS.
@compute @workgroup_size(ORDER_THREADS)
fn cluster_order_bits(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let bin = order_bin(wg, 1u);
    let n = list_len(bin, li);
    if n <= ORDER_SHORT {
        return;
    }
    bits_sort(bin_offsets[bin], n, li, ORDER_THREADS);
}
