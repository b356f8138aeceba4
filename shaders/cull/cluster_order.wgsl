// cull.clustered.order: sorts each cluster's list into light order after the atomic fill, so
// that shading sums a pixel's lights in the same order on every run (bit-identical images).
// One workgroup per cluster. Lists of up to ORDER_LOCAL lights (order_local_*.wgsl: 8,191 where
// the device has 32 KB of workgroup memory, else 2,048) are sorted in workgroup memory;
// longer ones in place in the list buffer (the same network, slower, and rare: a cluster holds
// that many lights only when thousands overlap it). The network is a bitonic sort over the list
// padded to a power of two with virtual +inf entries; in the form used here every
// compare-exchange puts the smaller value at the lower index, so a pair whose upper index is in
// the padding never swaps, and the padding never needs storing.
const ORDER_THREADS: u32 = 256u;
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

@compute @workgroup_size(256)
fn cluster_order(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let bin = wg.y * GROUPS_X + wg.x;
    if li == 0u {
        var n = 0u;
        if bin < cull.bins {
            n = atomicLoad(&bin_counts[bin]);
        }
        wg_len = n;
    }
    let n = workgroupUniformLoad(&wg_len);
    if n < 2u {
        return;
    }
    let base = bin_offsets[bin];
    var size = 2u;
    while size < n {
        size <<= 1u;
    }
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
            storageBarrier();
            workgroupBarrier();
        }
    }
    if local {
        for (var i = li; i < n; i += ORDER_THREADS) {
            out_indices[base + i] = wg_list[i];
        }
    }
}
