// The clusters' order passes (after cull.clustered.fill and fill_wide, clustered.wgsl): each
// cluster's list, filled by atomics in any order, sorted into light order.

// Each list is sorted so that shading sums a pixel's lights in the same order on every run
// (bit-identical images), by one workgroup, in one of three ways:
// - the bitmap's rank sort (order_rank.wgsl, bits_sort) with CULL_FLAG_ORDER_BITS: lists of
//   more than ORDER_SHORT lights in cull.clustered.order_bits;
// - the bucket rank sort (order_rank.wgsl, bucket_sort), unless the list's lights crowd a
//   bucket: lists of ORDER_BUCKET_MIN to ORDER_SHORT lights in cull.clustered.order_short, in
//   workgroup memory, and, without the bitmap, longer ones of up to ORDER_WIDE_ENTRIES
//   lights a thread in cull.clustered.order, in place in the list buffer;
// - a bitonic network (below): the rest, in workgroup memory in cull.clustered.order_short, in
//   place in the list buffer in cull.clustered.order (slower, and rare: a list the buckets do
//   not take there is a crowded one or one of over 4,096 lights).
// The network sorts the list padded to a power of two with virtual +inf entries; in the form
// used here every compare-exchange puts the smaller value at the lower index, so a pair whose
// upper index is in the padding never swaps, and the padding never needs storing.
// Threads of the long lists' passes: 512 where the device allows (Pipelines::new), else 256: on
// the H100, culling at 1M lights in 32-pixel tiles 1.191 against 1.178 ms, and in the hall at
// 50,000 0.387 against 0.379 ms (1,024: no faster), by the network.
override ORDER_THREADS: u32 = 256u;
var<workgroup> wg_list: array<u32, ORDER_SHORT>;
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

// The list of the order passes' workgroup `wg` of `kind`: its length, the same in every thread
// (0: none), and its offset. Called in uniform control flow.
fn order_list(wg: vec3<u32>, kind: u32, li: u32) -> vec2<u32> {
    let bin = order_bin(wg, kind);
    let n = list_len(bin, li);
    var base = 0u;
    if n != 0u {
        base = bin_offsets[bin];
    }
    return vec2<u32>(n, base);
}

// Sorts the `n` entries at `base` by the network with `threads` threads: in wg_list (`local`:
// at most ORDER_SHORT, loaded there, after a barrier), then written back; or in place in the
// list buffer. Called in uniform control flow.
fn network(base: u32, n: u32, li: u32, threads: u32, local: bool) {
    let size = padded(n);
    for (var k = 2u; k <= size; k <<= 1u) {
        for (var d = k / 2u; d > 0u; d >>= 1u) {
            for (var t = li; t < size / 2u; t += threads) {
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
        for (var i = li; i < n; i += threads) {
            out_indices[base + i] = wg_list[i];
        }
    }
}

// Sorts the `n` (at least 2, at most ORDER_SHORT) entries at `base` in wg_list: by 256
// buckets from ORDER_BUCKET_MIN entries on, else (or where the lights crowd a bucket) by the
// network.
fn sort_local(base: u32, n: u32, li: u32, threads: u32) {
    var sorted = false;
    if n >= ORDER_BUCKET_MIN {
        sorted = bucket_sort_local(base, n, li, threads);
    } else {
        for (var i = li; i < n; i += threads) {
            wg_list[i] = out_indices[base + i];
        }
        workgroupBarrier();
    }
    if !sorted {
        network(base, n, li, threads, true);
    }
}

// cull.clustered.order: the lists of more than ORDER_SHORT lights, without CULL_FLAG_ORDER_BITS.
@compute @workgroup_size(ORDER_THREADS)
fn cluster_order(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let list = order_list(wg, 1u, li);
    let n = list.x;
    let base = list.y;
    if n <= ORDER_SHORT {
        return;
    }
    // A bucket for every 4 entries up to 2,048, 8 beyond (256 or 512 buckets: the short lists'
    // pass reserves the buckets too, and is bound by its workgroup memory).
    var sorted = false;
    if n <= ORDER_WIDE_ENTRIES * ORDER_THREADS {
        let bucket_bits = clamp(32u - countLeadingZeros(n - 1u), 10u, 11u) - 2u;
        sorted = bucket_sort_wide(base, n, li, ORDER_THREADS, bucket_bits);
    }
    if !sorted {
        network(base, n, li, ORDER_THREADS, false);
    }
}

// cull.clustered.order_bits: the same lists, with CULL_FLAG_ORDER_BITS, by the bitmap.
@compute @workgroup_size(ORDER_THREADS)
fn cluster_order_bits(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let list = order_list(wg, 1u, li);
    if list.x <= ORDER_SHORT {
        return;
    }
    bits_sort(list.y, list.x, li, ORDER_THREADS);
}

// cull.clustered.order_short: the lists of 2 to ORDER_SHORT lights, with 128 threads, so that
// the many short lists do not pay the long lists' 512 threads a workgroup (in the hall at 50,000
// lights on the H100, by the network, the pass took 29 µs with 128 threads, 42 with 64 and 70
// with 32).
const ORDER_SHORT: u32 = 512u;
const ORDER_SHORT_THREADS: u32 = 128u;

@compute @workgroup_size(ORDER_SHORT_THREADS)
fn cluster_order_short(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let list = order_list(wg, 0u, li);
    if list.x < 2u || list.x > ORDER_SHORT {
        return;
    }
    sort_local(list.y, list.x, li, ORDER_SHORT_THREADS);
}
