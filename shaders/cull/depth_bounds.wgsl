// cull.depth_bounds: DEPTH_TILES tiles a workgroup (tiles DEPTH_TILES x + j of row y for
// workgroup (x, y)), 64 threads a tile: fewer, larger workgroups, as launching a workgroup
// costs more than a tile's work at small tiles. The nearest and farthest covered pixel (linear
// view depth) and the 2.5D geometry mask of every tile (Harada 2012, GPU Pro 4 section 5.6.1:
// 32 cells over [dmin, dmax]). Background pixels (depth 1.0, the clear value) are not covered
// and need no lights, so they do not widen the bounds.
//
// For gather's and 2.5D's coarse-to-fine passes the host adds rows of workgroups past the
// tiles' (wg.y >= tiles_y), which store each light's tile rectangle instead (light_tiles,
// as scatter and clusters use: its view-space box cut at the near plane, projected), packed as
// (x0 | y0 << 16, x1 | y1 << 16), an empty one as (1, 0) (x0 > x1): one pass, not two, as
// each pass has a fixed cost larger than this work.
@group(1) @binding(1) var depth_tex: texture_depth_2d;
@group(1) @binding(2) var<storage, read_write> tile_depth: array<TileDepth>;
@group(1) @binding(9) var<storage, read_write> light_rects: array<vec2<u32>>;

// Light `i`'s tile rectangle into light_rects.
fn store_light_rect(i: u32) {
    if i < cull.light_count {
        let r = light_tiles(cull_light(lights[i]));
        if r.x > r.z || r.y > r.w {
            light_rects[i] = vec2<u32>(1u, 0u);
        } else {
            light_rects[i] = vec2<u32>(u32(r.x) | (u32(r.y) << 16u), u32(r.z) | (u32(r.w) << 16u));
        }
    }
}

var<workgroup> wg_zmin: array<atomic<u32>, DEPTH_TILES>;
var<workgroup> wg_zmax: array<atomic<u32>, DEPTH_TILES>;
var<workgroup> wg_mask: array<atomic<u32>, DEPTH_TILES>;
var<workgroup> wg_covered: array<atomic<u32>, DEPTH_TILES>;

@compute @workgroup_size(64 * DEPTH_TILES)
fn depth_bounds(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) index: u32) {
    // Uniform (a workgroup's id), so the barriers below are reached by all threads or none.
    if wg.y >= cull.tiles_y {
        store_light_rect(((wg.y - cull.tiles_y) * groups.x + wg.x) * 64u * DEPTH_TILES + index);
        return;
    }
    let j = index / 64u;
    let li = index % 64u;
    let tile = vec2<u32>(wg.x * DEPTH_TILES + j, wg.y);
    if li == 0u {
        atomicStore(&wg_zmin[j], 0x7f800000u);
        atomicStore(&wg_zmax[j], 0u);
        atomicStore(&wg_mask[j], 0u);
        atomicStore(&wg_covered[j], 0u);
    }
    workgroupBarrier();
    let size = vec2<u32>(frame.viewport.xy);
    let origin = tile * cull.tile_size;
    // A tile past the last column (in the last workgroup of a row) has no pixels here.
    let n = select(0u, cull.tile_size * cull.tile_size, tile.x < cull.tiles_x);
    // Depth in [0, 1) is a non-negative float: its bits order like its value.
    for (var i = li; i < n; i += 64u) {
        let p = origin + vec2<u32>(i % cull.tile_size, i / cull.tile_size);
        if all(p < size) {
            let z = textureLoad(depth_tex, p, 0);
            if z < 1.0 {
                atomicMin(&wg_zmin[j], bitcast<u32>(z));
                atomicMax(&wg_zmax[j], bitcast<u32>(z));
                atomicAdd(&wg_covered[j], 1u);
            }
        }
    }
    workgroupBarrier();
    let covered = atomicLoad(&wg_covered[j]);
    var t: TileDepth;
    t.covered = covered;
    if covered > 0u {
        t.dmin = linear_depth(bitcast<f32>(atomicLoad(&wg_zmin[j])));
        t.dmax = linear_depth(bitcast<f32>(atomicLoad(&wg_zmax[j])));
        let scale = depth_cell_scale(t);
        for (var i = li; i < n; i += 64u) {
            let p = origin + vec2<u32>(i % cull.tile_size, i / cull.tile_size);
            if all(p < size) {
                let z = textureLoad(depth_tex, p, 0);
                if z < 1.0 {
                    atomicOr(&wg_mask[j], 1u << depth_cell(linear_depth(z), t.dmin, scale));
                }
            }
        }
    }
    workgroupBarrier();
    if li == 0u && tile.x < cull.tiles_x {
        t.mask = atomicLoad(&wg_mask[j]);
        tile_depth[tile.y * cull.tiles_x + tile.x] = t;
    }
}
