// A tile's depth data (TileDepth) from the depth buffer, shared by cull.depth_bounds and the
// one-pass lists of gather and 2.5D (gather_lists.wgsl): the nearest and farthest covered
// pixel (linear view depth) and the 2.5D geometry mask (Harada 2012, GPU Pro 4 section 5.6.1:
// 32 cells over [dmin, dmax]). Background pixels (depth 1.0, the clear value) are not covered
// and need no lights, so they do not widen the bounds.
@group(1) @binding(1) var depth_tex: texture_depth_2d;

// Per tile slot of a workgroup (at most BOUNDS_TILES tiles a workgroup).
var<workgroup> wb_zmin: array<atomic<u32>, BOUNDS_TILES>;
var<workgroup> wb_zmax: array<atomic<u32>, BOUNDS_TILES>;
var<workgroup> wb_mask: array<atomic<u32>, BOUNDS_TILES>;
var<workgroup> wb_covered: array<atomic<u32>, BOUNDS_TILES>;

// The depth data of `tile`, in tile slot `j` of the workgroup, computed by the `threads`
// threads of that slot (`li` in 0..threads); every one of them returns it. A tile outside the
// image has no pixels (covered 0). Called in uniform control flow (three barriers).
fn tile_depth_of(tile: vec2<u32>, j: u32, li: u32, threads: u32) -> TileDepth {
    if li == 0u {
        atomicStore(&wb_zmin[j], 0x7f800000u);
        atomicStore(&wb_zmax[j], 0u);
        atomicStore(&wb_mask[j], 0u);
        atomicStore(&wb_covered[j], 0u);
    }
    workgroupBarrier();
    let size = vec2<u32>(frame.viewport.xy);
    let origin = tile * cull.tile_size;
    let n = select(0u, cull.tile_size * cull.tile_size, tile.x < cull.tiles_x && tile.y < cull.tiles_y);
    // Depth in [0, 1) is a non-negative float: its bits order like its value. Each thread
    // reduces its own pixels first: one atomic of each kind a thread, not one a pixel.
    var zmin = 0x7f800000u;
    var zmax = 0u;
    var covered = 0u;
    for (var i = li; i < n; i += threads) {
        let p = origin + vec2<u32>(i % cull.tile_size, i / cull.tile_size);
        if all(p < size) {
            let z = textureLoad(depth_tex, p, 0);
            if z < 1.0 {
                zmin = min(zmin, bitcast<u32>(z));
                zmax = max(zmax, bitcast<u32>(z));
                covered += 1u;
            }
        }
    }
    if covered != 0u {
        atomicMin(&wb_zmin[j], zmin);
        atomicMax(&wb_zmax[j], zmax);
        atomicAdd(&wb_covered[j], covered);
    }
    workgroupBarrier();
    var t: TileDepth;
    t.covered = atomicLoad(&wb_covered[j]);
    if t.covered > 0u {
        t.dmin = linear_depth(bitcast<f32>(atomicLoad(&wb_zmin[j])));
        t.dmax = linear_depth(bitcast<f32>(atomicLoad(&wb_zmax[j])));
        let scale = depth_cell_scale(t);
        var mask = 0u;
        for (var i = li; i < n; i += threads) {
            let p = origin + vec2<u32>(i % cull.tile_size, i / cull.tile_size);
            if all(p < size) {
                let z = textureLoad(depth_tex, p, 0);
                if z < 1.0 {
                    mask |= 1u << depth_cell(linear_depth(z), t.dmin, scale);
                }
            }
        }
        if mask != 0u {
            atomicOr(&wb_mask[j], mask);
        }
    }
    workgroupBarrier();
    t.mask = atomicLoad(&wb_mask[j]);
    return t;
}
