// cull.tiled_gather (Harada, McKee, Yang 2012, section 4.1) and, with CULL_FLAG_DEPTH_MASK,
// cull.depth_mask (2.5D culling, Harada 2012): one workgroup per tile tests every light
// against the tile frustum between the tile's depth bounds (and the 2.5D masks), 64 lights at
// a time. Entry points: gather_count (count pass) and gather_fill (fill pass).
var<workgroup> wg_planes: array<vec4<f32>, 4>;

fn gather(tile: vec2<u32>, li: u32, fill: bool) {
    if li == 0u {
        wg_planes = tile_side_planes(tile);
    }
    workgroupBarrier();
    let bin = tile.y * cull.tiles_x + tile.x;
    let t = tile_depth[bin];
    if t.covered == 0u {
        return;
    }
    let planes = wg_planes;
    for (var i = li; i < cull.light_count; i += 64u) {
        if tile_keeps(cull_light(lights[i]), planes, t) {
            emit(bin, i, fill);
        }
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
