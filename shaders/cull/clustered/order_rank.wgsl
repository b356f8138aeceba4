// The clusters' order passes' rank sorts (the passes: order.wgsl).

// Both sorts take distinct lights (a light enters a cluster's list once) and write each at its
// rank, the lights before it in light order.

// Each thread's value, then, in the first threads / 16, each group of 16 threads' sum.
var<workgroup> wg_sums: array<u32, 512>;
var<workgroup> wg_groups: array<u32, 32>;

// The sum of `s` over the threads before this one (`li`) of `threads` (at most 512, a multiple
// of 16): two barriers. Called in uniform control flow.
fn wg_prefix(s: u32, li: u32, threads: u32) -> u32 {
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
    var at = 0u;
    for (var k = 0u; k < li / 16u; k++) {
        at += wg_groups[k];
    }
    for (var k = li & ~15u; k < li; k++) {
        at += wg_sums[k];
    }
    return at;
}

// The bitmap's rank sort (CULL_FLAG_ORDER_BITS: at most CLUSTER_ORDER_BITS_LIGHTS lights): a
// bit a light (8 KB at most), set by each entry of the list; the set bits counted a word at a
// time and prefix-summed across the threads; then each thread writes the lights of its words at
// their ranks. Four barriers whatever the length, against the network's 66 for 2,048 lights;
// the work grows with the lights of the run (a word per 32) rather than with the list, and no
// order of the light indices slows it. In the hall at 50,000 lights (H100) the long lists' pass
// took 23 µs, against 28 by buckets and 67 by the network.
var<workgroup> wg_bits: array<atomic<u32>, CLUSTER_ORDER_BITS_LIGHTS / 32u>;

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
    var at = base + wg_prefix(s, li, threads);
    for (var w = first; w < last; w++) {
        var m = atomicLoad(&wg_bits[w]);
        while m != 0u {
            out_indices[at] = 32u * w + firstTrailingBit(m);
            at++;
            m &= m - 1u;
        }
    }
}

// The bucket rank sort: each entry counted into one of ORDER_BUCKETS buckets by the high bits
// of its light index (of the run's light count); the buckets' offsets prefix-summed; the
// entries scattered into wg_list by bucket; and each written at its bucket's offset plus the
// entries of its bucket below it. Seven barriers; the work grows with the list's length times
// its entries a bucket, a few where the list's lights spread over the indices. Where a bucket
// holds more than ORDER_BUCKET_MAX (a list of lights with neighbouring indices) it returns
// false, with the list loaded into wg_list for the network. For lists of at most 4 entries a
// thread and ORDER_LOCAL. At 1M lights in 32-pixel tiles (H100) the short lists' pass took 54 µs,
// against 116 by the network.
const ORDER_BUCKETS: u32 = 256u;
const ORDER_BUCKET_MIN: u32 = 16u;
const ORDER_BUCKET_MAX: u32 = 64u;
var<workgroup> wg_buckets: array<atomic<u32>, ORDER_BUCKETS>;
var<workgroup> wg_crowded: atomic<u32>;
var<workgroup> wg_crowded_all: u32;

fn bucket_sort(base: u32, n: u32, li: u32, threads: u32) -> bool {
    let bits = 32u - countLeadingZeros(max(cull.light_count, 2u) - 1u);
    let shift = select(0u, bits - 8u, bits > 8u);
    for (var b = li; b < ORDER_BUCKETS; b += threads) {
        atomicStore(&wg_buckets[b], 0u);
    }
    if li == 0u {
        atomicStore(&wg_crowded, 0u);
    }
    workgroupBarrier();
    var e: array<u32, 4>;
    var slot: array<u32, 4>;
    for (var k = 0u; k < 4u; k++) {
        let i = li + k * threads;
        if i < n {
            e[k] = out_indices[base + i];
            slot[k] = atomicAdd(&wg_buckets[e[k] >> shift], 1u);
        }
    }
    workgroupBarrier();
    // Each thread's run of buckets (2 at most: ORDER_BUCKETS / 128), their offsets from the
    // prefix of the runs' sums.
    let per = (ORDER_BUCKETS + threads - 1u) / threads;
    let first = min(li * per, ORDER_BUCKETS);
    let last = min(first + per, ORDER_BUCKETS);
    var c: array<u32, 2>;
    var s = 0u;
    for (var b = first; b < last; b++) {
        c[b - first] = atomicLoad(&wg_buckets[b]);
        s += c[b - first];
        if c[b - first] > ORDER_BUCKET_MAX {
            atomicStore(&wg_crowded, 1u);
        }
    }
    var at = wg_prefix(s, li, threads);
    if li == 0u {
        wg_crowded_all = atomicLoad(&wg_crowded);
    }
    if workgroupUniformLoad(&wg_crowded_all) != 0u {
        for (var k = 0u; k < 4u; k++) {
            if li + k * threads < n {
                wg_list[li + k * threads] = e[k];
            }
        }
        workgroupBarrier();
        return false;
    }
    for (var b = first; b < last; b++) {
        atomicStore(&wg_buckets[b], at);
        at += c[b - first];
    }
    workgroupBarrier();
    for (var k = 0u; k < 4u; k++) {
        if li + k * threads < n {
            wg_list[atomicLoad(&wg_buckets[e[k] >> shift]) + slot[k]] = e[k];
        }
    }
    workgroupBarrier();
    for (var k = 0u; k < 4u; k++) {
        if li + k * threads < n {
            let b = e[k] >> shift;
            let o = atomicLoad(&wg_buckets[b]);
            var end = n;
            if b + 1u < ORDER_BUCKETS {
                end = atomicLoad(&wg_buckets[b + 1u]);
            }
            var r = o;
            for (var j = o; j < end; j++) {
                r += select(0u, 1u, wg_list[j] < e[k]);
            }
            out_indices[base + r] = e[k];
        }
    }
    return true;
}
