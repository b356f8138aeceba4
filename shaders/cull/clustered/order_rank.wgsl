// The clusters' order passes' rank sorts (the passes: order.wgsl).

// Both sorts take distinct lights (a light enters a cluster's list once) and write each at its
// rank, the lights before it in light order.

// Sums of 16 words of wg_buckets (buckets_before).
var<workgroup> wg_groups: array<u32, 32>;

// The sum of wg_buckets' first `at` words of `words` (a multiple of 16, at most 512), in every
// thread: the words' groups of 16 summed first (wg_groups), then one barrier. Called in uniform
// control flow, after a barrier past the words' last store. The passes keep no word a thread
// for it: the short lists' pass is bound by its workgroup memory.
fn buckets_before(at: u32, li: u32, words: u32) -> u32 {
    if li < words / 16u {
        var g = 0u;
        for (var k = 0u; k < 16u; k++) {
            g += atomicLoad(&wg_buckets[16u * li + k]);
        }
        wg_groups[li] = g;
    }
    workgroupBarrier();
    var sum = 0u;
    for (var k = 0u; k < at / 16u; k++) {
        sum += wg_groups[k];
    }
    for (var b = at & ~15u; b < at; b++) {
        sum += atomicLoad(&wg_buckets[b]);
    }
    return sum;
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
    // The threads' sums in wg_buckets (this pass sorts by no bucket).
    atomicStore(&wg_buckets[li], s);
    workgroupBarrier();
    var at = base + buckets_before(li, li, threads);
    for (var w = first; w < last; w++) {
        var m = atomicLoad(&wg_bits[w]);
        while m != 0u {
            out_indices[at] = 32u * w + firstTrailingBit(m);
            at++;
            m &= m - 1u;
        }
    }
}

// The bucket rank sort: each entry counted into one of 2^`bucket_bits` buckets by the high
// bits of its light index (of the run's light count); the buckets' offsets prefix-summed; the
// entries scattered by bucket, into wg_list (bucket_sort_local) or in place in the list buffer
// (bucket_sort_wide); and each written at its bucket's offset plus the entries of its bucket
// below it. Seven barriers; the work grows with the list's length times its entries a bucket,
// a few where the list's lights spread over the indices. Where a bucket holds more than
// ORDER_BUCKET_MAX (a list of lights with neighbouring indices) each returns false, the list
// as it was (bucket_sort_local: loaded into wg_list), for the network. The entries of a
// thread are held in registers, 4 (local) or ORDER_WIDE_ENTRIES (wide): on the H100 16 a
// thread for both made the short lists' pass at 1M lights in 32-pixel tiles 45 -> 78 µs, and
// the long lists' 8 against 16 a thread took 43 against 51 µs. The short lists' pass is bound
// by its workgroup memory: wg_buckets of 2,048, 1,024 and 512 words took 53, 40 and 35 µs
// there (140, 95 and 77 in 16-pixel tiles), and 32 (67) without a word a thread for the
// prefix (buckets_before).
const ORDER_BUCKET_MIN: u32 = 16u;
const ORDER_BUCKET_MAX: u32 = 64u;
const ORDER_WIDE_ENTRIES: u32 = 8u;
// The buckets' counts, then offsets; in the bitmap's sort, its threads' sums (at most 512).
var<workgroup> wg_buckets: array<atomic<u32>, 512>;
var<workgroup> wg_crowded: atomic<u32>;
var<workgroup> wg_crowded_all: u32;

// The shift of a light index to its bucket of 2^`bucket_bits`.
fn bucket_shift(bucket_bits: u32) -> u32 {
    let bits = 32u - countLeadingZeros(max(cull.light_count, 2u) - 1u);
    return select(0u, bits - bucket_bits, bits > bucket_bits);
}

// Zeroes the buckets' counts and the crowded flag, then a barrier.
fn buckets_clear(li: u32, threads: u32, buckets: u32) {
    for (var b = li; b < buckets; b += threads) {
        atomicStore(&wg_buckets[b], 0u);
    }
    if li == 0u {
        atomicStore(&wg_crowded, 0u);
    }
    workgroupBarrier();
}

// After the count (and a barrier): true, the same in every thread, where a bucket holds more
// than ORDER_BUCKET_MAX entries; else each bucket's count replaced by its offset, then a
// barrier. Each thread takes a run of buckets (at most 2: `buckets` at most 2 a thread), and
// their offsets from the counts in place (buckets_before).
fn buckets_place(li: u32, threads: u32, buckets: u32) -> bool {
    let per = (buckets + threads - 1u) / threads;
    let first = min(li * per, buckets);
    let last = min(first + per, buckets);
    for (var b = first; b < last; b++) {
        if atomicLoad(&wg_buckets[b]) > ORDER_BUCKET_MAX {
            atomicStore(&wg_crowded, 1u);
        }
    }
    var at = buckets_before(first, li, buckets);
    var offsets: array<u32, 2>;
    for (var b = first; b < last; b++) {
        offsets[b - first] = at;
        at += atomicLoad(&wg_buckets[b]);
    }
    if li == 0u {
        wg_crowded_all = atomicLoad(&wg_crowded);
    }
    // (Also keeps every count read above from the offsets written below.)
    if workgroupUniformLoad(&wg_crowded_all) != 0u {
        return true;
    }
    for (var b = first; b < last; b++) {
        atomicStore(&wg_buckets[b], offsets[b - first]);
    }
    workgroupBarrier();
    return false;
}

// The rank of light `e`, of bucket `b`, in its list of `n`: its bucket's offset plus the
// entries of its bucket below it, scattered into wg_list (`local`) or at `base`.
fn bucket_rank(e: u32, b: u32, buckets: u32, n: u32, base: u32, local: bool) -> u32 {
    let o = atomicLoad(&wg_buckets[b]);
    var end = n;
    if b + 1u < buckets {
        end = atomicLoad(&wg_buckets[b + 1u]);
    }
    var r = o;
    for (var j = o; j < end; j++) {
        var x: u32;
        if local {
            x = wg_list[j];
        } else {
            x = out_indices[base + j];
        }
        r += select(0u, 1u, x < e);
    }
    return r;
}

// The short lists' bucket sort: at most ORDER_SHORT entries and 4 a thread, 256 buckets, in
// wg_list. (Its count and bucket_sort_wide's differ only in their register arrays' sizes,
// which WGSL cannot take as a parameter; the short lists' pass was slower holding 8 or 16.)
fn bucket_sort_local(base: u32, n: u32, li: u32, threads: u32) -> bool {
    let buckets = 256u;
    let shift = bucket_shift(8u);
    buckets_clear(li, threads, buckets);
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
    if buckets_place(li, threads, buckets) {
        for (var k = 0u; k < 4u; k++) {
            if li + k * threads < n {
                wg_list[li + k * threads] = e[k];
            }
        }
        workgroupBarrier();
        return false;
    }
    for (var k = 0u; k < 4u; k++) {
        if li + k * threads < n {
            wg_list[atomicLoad(&wg_buckets[e[k] >> shift]) + slot[k]] = e[k];
        }
    }
    workgroupBarrier();
    for (var k = 0u; k < 4u; k++) {
        if li + k * threads < n {
            out_indices[base + bucket_rank(e[k], e[k] >> shift, buckets, n, base, true)] = e[k];
        }
    }
    return true;
}

// The long lists' bucket sort: at most ORDER_WIDE_ENTRIES entries a thread, 2^`bucket_bits`
// buckets (at most 512), in place in the list buffer: every thread ranks its entries among
// the scattered ones before any is written at its rank.
fn bucket_sort_wide(base: u32, n: u32, li: u32, threads: u32, bucket_bits: u32) -> bool {
    let buckets = 1u << bucket_bits;
    let shift = bucket_shift(bucket_bits);
    buckets_clear(li, threads, buckets);
    var e: array<u32, ORDER_WIDE_ENTRIES>;
    var slot: array<u32, ORDER_WIDE_ENTRIES>;
    for (var k = 0u; k < ORDER_WIDE_ENTRIES; k++) {
        let i = li + k * threads;
        if i < n {
            e[k] = out_indices[base + i];
            slot[k] = atomicAdd(&wg_buckets[e[k] >> shift], 1u);
        }
    }
    workgroupBarrier();
    if buckets_place(li, threads, buckets) {
        return false;
    }
    for (var k = 0u; k < ORDER_WIDE_ENTRIES; k++) {
        if li + k * threads < n {
            out_indices[base + atomicLoad(&wg_buckets[e[k] >> shift]) + slot[k]] = e[k];
        }
    }
    storageBarrier();
    workgroupBarrier();
    for (var k = 0u; k < ORDER_WIDE_ENTRIES; k++) {
        if li + k * threads < n {
            slot[k] = bucket_rank(e[k], e[k] >> shift, buckets, n, base, false);
        }
    }
    storageBarrier();
    workgroupBarrier();
    for (var k = 0u; k < ORDER_WIDE_ENTRIES; k++) {
        if li + k * threads < n {
            out_indices[base + slot[k]] = e[k];
        }
    }
    return true;
}
