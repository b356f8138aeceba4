// cull.depth_bounds: one workgroup per tile. The nearest and farthest covered pixel (linear
// view depth) and the 2.5D geometry mask of every tile (Harada 2012, GPU Pro 4 section 5.6.1:
// 32 cells over [dmin, dmax]). Background pixels (depth 1.0, the clear value) are not covered
// and need no lights, so they do not widen the bounds.
@group(1) @binding(1) var depth_tex: texture_depth_2d;
@group(1) @binding(2) var<storage, read_write> tile_depth: array<TileDepth>;

var<workgroup> wg_zmin: atomic<u32>;
var<workgroup> wg_zmax: atomic<u32>;
var<workgroup> wg_mask: atomic<u32>;
var<workgroup> wg_covered: atomic<u32>;

@compute @workgroup_size(64)
fn depth_bounds(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let tile = wg.xy;
    p_index = li;
    if li == 0u {
        atomicStore(&wg_zmin, 0x7f800000u);
        atomicStore(&wg_zmax, 0u);
        atomicStore(&wg_mask, 0u);
        atomicStore(&wg_covered, 0u);
    }
    workgroupBarrier();
    let size = vec2<u32>(frame.viewport.xy);
    let origin = tile * cull.tile_size;
    let n = cull.tile_size * cull.tile_size;
    // Depth in [0, 1) is a non-negative float: its bits order like its value. Each thread
    // reduces its own pixels, then the workgroup's (reduce_bounds, in depth_reduce.wgsl or
    // depth_reduce_subgroup.wgsl).
    var zmin = 0x7f800000u;
    var zmax = 0u;
    var count = 0u;
    for (var i = li; i < n; i += 64u) {
        let p = origin + vec2<u32>(i % cull.tile_size, i / cull.tile_size);
        if all(p < size) {
            let z = textureLoad(depth_tex, p, 0);
            if z < 1.0 {
                zmin = min(zmin, bitcast<u32>(z));
                zmax = max(zmax, bitcast<u32>(z));
                count += 1u;
            }
        }
    }
    reduce_bounds(zmin, zmax, count);
    workgroupBarrier();
    let covered = atomicLoad(&wg_covered);
    var t: TileDepth;
    t.covered = covered;
    var mask = 0u;
    if covered > 0u {
        t.dmin = linear_depth(bitcast<f32>(atomicLoad(&wg_zmin)));
        t.dmax = linear_depth(bitcast<f32>(atomicLoad(&wg_zmax)));
        let scale = depth_cell_scale(t);
        for (var i = li; i < n; i += 64u) {
            let p = origin + vec2<u32>(i % cull.tile_size, i / cull.tile_size);
            if all(p < size) {
                let z = textureLoad(depth_tex, p, 0);
                if z < 1.0 {
                    mask |= 1u << depth_cell(linear_depth(z), t.dmin, scale);
                }
            }
        }
    }
    reduce_mask(mask);
    workgroupBarrier();
    if li == 0u {
        t.mask = atomicLoad(&wg_mask);
        tile_depth[tile.y * cull.tiles_x + tile.x] = t;
    }
}
