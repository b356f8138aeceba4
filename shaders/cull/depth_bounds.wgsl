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
    // Depth in [0, 1) is a non-negative float: its bits order like its value.
    for (var i = li; i < n; i += 64u) {
        let p = origin + vec2<u32>(i % cull.tile_size, i / cull.tile_size);
        if all(p < size) {
            let z = textureLoad(depth_tex, p, 0);
            if z < 1.0 {
                atomicMin(&wg_zmin, bitcast<u32>(z));
                atomicMax(&wg_zmax, bitcast<u32>(z));
                atomicAdd(&wg_covered, 1u);
            }
        }
    }
    workgroupBarrier();
    let covered = atomicLoad(&wg_covered);
    var t: TileDepth;
    t.covered = covered;
    if covered > 0u {
        t.dmin = linear_depth(bitcast<f32>(atomicLoad(&wg_zmin)));
        t.dmax = linear_depth(bitcast<f32>(atomicLoad(&wg_zmax)));
        let scale = depth_cell_scale(t);
        for (var i = li; i < n; i += 64u) {
            let p = origin + vec2<u32>(i % cull.tile_size, i / cull.tile_size);
            if all(p < size) {
                let z = textureLoad(depth_tex, p, 0);
                if z < 1.0 {
                    atomicOr(&wg_mask, 1u << depth_cell(linear_depth(z), t.dmin, scale));
                }
            }
        }
    }
    workgroupBarrier();
    if li == 0u {
        t.mask = atomicLoad(&wg_mask);
        tile_depth[tile.y * cull.tiles_x + tile.x] = t;
    }
}
