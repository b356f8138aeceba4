// cull.occlusion: after any strategy's lists of a list a bin (every strategy but z-binning),
// drops from each bin's list the lights an occluder hides from every point of the bin's cell,
// in place and in order (manylights_cull::blocks::occlusion). A bin's cell is its tile's
// frustum, widened by a pixel on each side, between the tile's depth bounds (tiled strategies)
// or, for clusters, its pixels' depth bounds where the box test stored them (CULL_FLAG_TILE_BOX,
// the occupancy words; an unoccupied cluster's list is left as it is) or else its slice's
// boundaries, each widened by 1e-4 of its depth: the convex hull of
// its eight corners holds every surface point its pixels shade. A workgroup a bin takes its
// list 64 entries at a time, each thread a light against the occluders that can hide anything
// from the cell (occluder_hides), then writes the kept ones at their rank among the kept;
// cull_stats[10] counts the dropped. The occluders that can: those whose plane has every corner
// of the cell beyond it on one side by the smallest spare any light's test gives it (a thread
// an occluder, once a bin, into workgroup memory): occluder_hides asks that of every corner
// with a spare at least as large, so no occluder left out hides a light.

@group(1) @binding(2) var<storage, read> tile_depth: array<TileDepth>;
@group(1) @binding(8) var<storage, read> occupancy: array<u32>;
@group(1) @binding(6) var<storage, read_write> out_ranges: array<vec2<u32>>;
@group(1) @binding(7) var<storage, read_write> out_indices: array<u32>;
@group(1) @binding(10) var<storage, read_write> cull_stats: array<atomic<u32>>;
@group(1) @binding(12) var<storage, read> occluders: array<Occluder>;
// x: the occluders.
@group(1) @binding(13) var<uniform> occlusion: vec4<u32>;

var<workgroup> wg_cell: array<vec3<f32>, 8>;
var<workgroup> wg_range: vec2<u32>;
var<workgroup> wg_scan: array<u32, 64>;
// The occluders that can hide a light from the cell (cell_beyond), and how many.
var<workgroup> wg_occluders: array<Occluder, 64>;
var<workgroup> wg_useful: atomic<u32>;
var<workgroup> wg_useful_count: u32;

// The world-space corners of bin `bin`'s cell into wg_cell, or false where it has no covered
// pixel (its list is then left as it is).
fn occlusion_cell(bin: u32) -> bool {
    let tiles = cull.tiles_x * cull.tiles_y;
    let t = bin % tiles;
    let s = bin / tiles;
    var d: vec2<f32>;
    if cull.slices <= 1u {
        let td = tile_depth[t];
        if td.covered == 0u {
            return false;
        }
        d = vec2<f32>(td.dmin, td.dmax);
    } else if (cull.flags & CULL_FLAG_TILE_BOX) != 0u {
        if occupancy[bin] == 0u {
            return false;
        }
        d = vec2<f32>(from_ordered_bits(~occupancy[cull.bins + 2u * bin]), from_ordered_bits(occupancy[cull.bins + 2u * bin + 1u]));
    } else {
        d = vec2<f32>(cull.near, cull.far);
        if s > 0u {
            d.x = slice_edge(s);
        }
        if s + 1u < cull.slices {
            d.y = slice_edge(s + 1u);
        }
    }
    d *= vec2<f32>(1.0 - 1e-4, 1.0 + 1e-4);
    let r = tile_ndc(vec2<u32>(t % cull.tiles_x, t / cull.tiles_x));
    let pad = 2.0 * frame.viewport.zw;
    let x = vec2<f32>(r.x - pad.x, r.z + pad.x);
    let y = vec2<f32>(r.y - pad.y, r.w + pad.y);
    for (var c = 0u; c < 8u; c++) {
        let v = view_point(vec2<f32>(x[c & 1u], y[(c >> 1u) & 1u]), -d[c >> 2u]);
        wg_cell[c] = (frame.world_from_view * vec4<f32>(v, 1.0)).xyz;
    }
    return true;
}

// The workgroup's cell, and the largest magnitude of its corners' coordinates (at least 1).
struct CellCorners {
    corners: array<vec3<f32>, 8>,
    far: f32,
}

fn cell_corners() -> CellCorners {
    var cell: array<vec3<f32>, 8>;
    var far = 1.0;
    for (var c = 0u; c < 8u; c++) {
        cell[c] = wg_cell[c];
        let a = abs(cell[c]);
        far = max(far, max(a.x, max(a.y, a.z)));
    }
    return CellCorners(cell, far);
}

// Whether an occluder hides light `l` from every point of the workgroup's cell.
fn occlusion_hidden(l: u32, useful: u32) -> bool {
    let p = lights[l].position;
    let cell = cell_corners();
    let a = abs(p);
    let margin = 1e-4 * max(cell.far, max(a.x, max(a.y, a.z)));
    for (var k = 0u; k < useful; k++) {
        if occluder_hides(wg_occluders[k], p, cell.corners, margin) {
            return true;
        }
    }
    return false;
}

@compute @workgroup_size(64)
fn occlusion_filter(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) i: u32) {
    let bin = wid.y * GROUPS_X + wid.x;
    if i == 0u {
        var range = vec2<u32>(0u);
        if bin < cull.bins {
            range = out_ranges[bin];
            if range.y != 0u && !occlusion_cell(bin) {
                range.y = 0u;
            }
        }
        wg_range = range;
    }
    let range = workgroupUniformLoad(&wg_range);
    if range.y == 0u {
        return;
    }
    // The occluders that can hide a light from the cell: at the smallest margin any light's
    // test takes (1e-4 of the cell's largest coordinate), occluder_hides's corner test.
    if i < occlusion.x {
        let cell = cell_corners();
        let o = occluders[i];
        if cell_beyond(o, cell.corners, 1e-4 * cell.far) {
            wg_occluders[atomicAdd(&wg_useful, 1u)] = o;
        }
    }
    workgroupBarrier();
    if i == 0u {
        wg_useful_count = atomicLoad(&wg_useful);
    }
    let useful = workgroupUniformLoad(&wg_useful_count);
    var kept_total = 0u;
    for (var base = 0u; base < range.y; base += 64u) {
        let k = base + i;
        var light = 0u;
        var keep = 0u;
        if k < range.y {
            light = out_indices[range.x + k];
            keep = select(1u, 0u, occlusion_hidden(light, useful));
        }
        // Inclusive scan of the kept flags (Hillis and Steele).
        wg_scan[i] = keep;
        workgroupBarrier();
        for (var step = 1u; step < 64u; step <<= 1u) {
            var v = wg_scan[i];
            if i >= step {
                v += wg_scan[i - step];
            }
            workgroupBarrier();
            wg_scan[i] = v;
            workgroupBarrier();
        }
        if keep != 0u {
            out_indices[range.x + kept_total + wg_scan[i] - 1u] = light;
        }
        kept_total += wg_scan[63];
        workgroupBarrier();
    }
    if i == 0u {
        out_ranges[bin] = vec2<u32>(range.x, kept_total);
        if kept_total < range.y {
            atomicAdd(&cull_stats[10], range.y - kept_total);
        }
    }
}
