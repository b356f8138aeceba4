// cull.clustered (Olsson, Billeter, Assarsson, HPG 2012): the view frustum split into tiles in
// x/y and depth slices (linear or exponential). One thread per light: the light's conservative
// screen rectangle gives candidate tiles, its depth extent the candidate slices; each candidate
// tile is tested with the tile's side planes (sphere, and cone for spots), and every slice of
// the light's range is emitted (with CULL_FLAG_SKIP_EMPTY, only clusters holding geometry).

// Light `i`'s tiles are shared by the CLUSTER_LANES threads of its lane group: lane k takes
// the tiles k, k + CLUSTER_LANES, ... of its rectangle. A light near the camera covers the whole
// screen (at 1080p, 510 tiles x 24 slices); one thread alone would emit its 12,000 entries in
// series while the rest of the GPU idles. Each lane recomputes the rectangle (a few hundred
// flops), so the lanes need no barrier.
fn assign(i: u32, lane: u32, fill: bool) {
    if i >= cull.light_count {
        return;
    }
    let l = cull_light(lights[i]);
    let dlo = -l.center.z - l.radius - l.slack;
    let dhi = -l.center.z + l.radius + l.slack;
    // Only the far side can reject: cull.near is where slicing starts, which for exponential
    // slicing of an orthographic camera lies beyond the camera's own near plane (nearer depths
    // fall in slice 0).
    if dlo > cull.far {
        return;
    }
    let s0 = depth_slice(dlo);
    let s1 = depth_slice(dhi);
    let rect = light_tiles(l);
    if rect.x > rect.z || rect.y > rect.w {
        return;
    }
    let width = u32(rect.z - rect.x + 1);
    let count = width * u32(rect.w - rect.y + 1);
    let tiles = cull.tiles_x * cull.tiles_y;
    for (var k = lane; k < count; k += CLUSTER_LANES) {
        let tile = vec2<u32>(u32(rect.x) + k % width, u32(rect.y) + k / width);
        let planes = tile_side_planes(tile);
        var inside = true;
        for (var p = 0u; p < 4u; p++) {
            if outside_plane(planes[p], l) {
                inside = false;
            }
        }
        if !inside {
            continue;
        }
        for (var s = s0; s <= s1; s++) {
            let bin = s * tiles + tile.y * cull.tiles_x + tile.x;
            if (cull.flags & CULL_FLAG_SKIP_EMPTY) == 0u || occupancy[bin] != 0u {
                emit(bin, i, fill);
            }
        }
    }
}

fn lane_work(id: vec3<u32>) -> vec2<u32> {
    let t = id.y * GROUPS_X * 64u + id.x;
    return vec2<u32>(t / CLUSTER_LANES, t % CLUSTER_LANES);
}

@compute @workgroup_size(64)
fn clustered_count(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = lane_work(id);
    assign(w.x, w.y, false);
}

@compute @workgroup_size(64)
fn clustered_fill(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = lane_work(id);
    assign(w.x, w.y, true);
}

// Marks the clusters that hold covered pixels, one thread per pixel.
@group(1) @binding(1) var depth_tex: texture_depth_2d;

@compute @workgroup_size(8, 8)
fn cluster_occupancy(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if any(p >= vec2<u32>(frame.viewport.xy)) {
        return;
    }
    let z = textureLoad(depth_tex, p, 0);
    if z < 1.0 {
        occupancy[bin_of(p, z)] = 1u;
    }
}
