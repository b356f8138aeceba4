// The tiles' depth data (Harada 2012, GPU Pro 4 section 5.6.1), shared by cull.depth_bounds
// (depth_bounds.wgsl) and gather's lines path, whose list passes compute their own tiles'
// (tile_lines.wgsl): the nearest and farthest covered pixel (linear view depth), the covered
// pixels, and the 2.5D geometry mask (32 cells over [dmin, dmax]). Background pixels (depth
// 1.0, the clear value) are not covered and need no lights, so they do not widen the bounds.
// The module declares depth_tex (binding 1) and tile_depth (binding 2).

var<workgroup> wg_tile_zmin: array<atomic<u32>, DEPTH_TILES>;
var<workgroup> wg_tile_zmax: array<atomic<u32>, DEPTH_TILES>;
var<workgroup> wg_tile_mask: array<atomic<u32>, DEPTH_TILES>;
var<workgroup> wg_tile_covered: array<atomic<u32>, DEPTH_TILES>;

// The depth data of workgroup wg's tiles, DEPTH_TILES tiles of row wg.y a workgroup, 64
// threads a tile (thread `index`'s tile is the index / 64-th): stored in tile_depth and
// returned to every thread of the tile; with `with_mask` false, the 2.5D mask is left 0 (one
// look at the pixels, not two). Called in uniform control flow.
fn tile_bounds(wg: vec3<u32>, index: u32, with_mask: bool) -> TileDepth {
    let j = index / 64u;
    let li = index % 64u;
    let tile = vec2<u32>(wg.x * DEPTH_TILES + j, wg.y);
    if li == 0u {
        atomicStore(&wg_tile_zmin[j], 0x7f800000u);
        atomicStore(&wg_tile_zmax[j], 0u);
        atomicStore(&wg_tile_mask[j], 0u);
        atomicStore(&wg_tile_covered[j], 0u);
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
                atomicMin(&wg_tile_zmin[j], bitcast<u32>(z));
                atomicMax(&wg_tile_zmax[j], bitcast<u32>(z));
                atomicAdd(&wg_tile_covered[j], 1u);
            }
        }
    }
    workgroupBarrier();
    let covered = atomicLoad(&wg_tile_covered[j]);
    var t: TileDepth;
    t.covered = covered;
    if covered > 0u {
        t.dmin = linear_depth(bitcast<f32>(atomicLoad(&wg_tile_zmin[j])));
        t.dmax = linear_depth(bitcast<f32>(atomicLoad(&wg_tile_zmax[j])));
    }
    if covered > 0u && with_mask {
        let scale = depth_cell_scale(t);
        for (var i = li; i < n; i += 64u) {
            let p = origin + vec2<u32>(i % cull.tile_size, i / cull.tile_size);
            if all(p < size) {
                let z = textureLoad(depth_tex, p, 0);
                if z < 1.0 {
                    atomicOr(&wg_tile_mask[j], 1u << depth_cell(linear_depth(z), t.dmin, scale));
                }
            }
        }
    }
    workgroupBarrier();
    t.mask = atomicLoad(&wg_tile_mask[j]);
    if li == 0u && tile.x < cull.tiles_x {
        tile_depth[tile.y * cull.tiles_x + tile.x] = t;
    }
    return t;
}
