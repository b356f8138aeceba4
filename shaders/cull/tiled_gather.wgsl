// cull.tiled_gather (Harada, McKee, Yang 2012, section 4.1) and, with CULL_FLAG_DEPTH_MASK,
// cull.depth_mask (2.5D culling, Harada 2012): one workgroup per tile tests every light
// against the tile frustum between the tile's depth bounds (and the 2.5D masks), 64 lights at
// a time. Entry points: gather_count (count pass) and gather_fill (fill pass).
//
// The fill keeps each list in light order: in every batch of 64 lights, a light's slot is the
// number of kept lights before it in the batch (a workgroup scan of the batch's flags) plus
// those of earlier batches. Lists, and so the order in which shading sums a pixel's lights, are the same
// on every run: images are bit-identical across runs.
var<workgroup> wg_planes: array<vec4<f32>, 4>;
var<workgroup> wg_covered: u32;
var<workgroup> wg_keep: array<u32, 64>;

fn gather(tile: vec2<u32>, li: u32, fill: bool) {
    let bin = tile.y * cull.tiles_x + tile.x;
    let t = tile_depth[bin];
    if li == 0u {
        wg_planes = tile_side_planes(tile);
        wg_covered = t.covered;
    }
    // Uniform across the workgroup, so the barriers below are reached by all or none.
    if workgroupUniformLoad(&wg_covered) == 0u {
        return;
    }
    let planes = wg_planes;
    var placed = 0u;
    for (var first = 0u; first < cull.light_count; first += 64u) {
        let i = first + li;
        var keep = false;
        if i < cull.light_count {
            keep = tile_keeps(cull_light(lights[i]), planes, t);
        }
        if !fill {
            if keep {
                atomicAdd(&bin_counts[bin], 1u);
            }
            continue;
        }
        // Inclusive Hillis-Steele scan of the batch's flags (6 steps for 64 threads).
        wg_keep[li] = u32(keep);
        workgroupBarrier();
        for (var off = 1u; off < 64u; off <<= 1u) {
            var v = 0u;
            if li >= off {
                v = wg_keep[li - off];
            }
            workgroupBarrier();
            wg_keep[li] += v;
            workgroupBarrier();
        }
        let total = wg_keep[63];
        let slot = placed + wg_keep[li] - u32(keep);
        if keep && (cull.capacity == 0u || slot < cull.capacity) {
            out_indices[bin_offsets[bin] + slot] = i;
        }
        placed += total;
        workgroupBarrier();
    }
}

@compute @workgroup_size(64)
fn gather_count(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    gather(wg.xy, li, false);
}

@compute @workgroup_size(64)
fn gather_fill(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    gather(wg.xy, li, true);
}
