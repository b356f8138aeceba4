// shade.deferred: the lighting pass of the deferred backend, one thread per pixel. Reads the
// G-buffer, reconstructs the surface point, reads the pixel's list through lookup.wgsl and
// writes HDR radiance (alpha 1 where covered, 0 for background, as the reference does).
@group(2) @binding(0) var gb_normal_depth: texture_2d<f32>;
@group(2) @binding(1) var gb_material: texture_2d<u32>;
@group(2) @binding(2) var out_color: texture_storage_2d<rgba32float, write>;
// The stored world position (deferred_stored_position; a 1 x 1 placeholder otherwise).
@group(2) @binding(3) var gb_position: texture_2d<f32>;

// An entry point for each form of lists (list_shading.wgsl): `zbin` is a constant of each.
@compute @workgroup_size(8, 8)
fn deferred_shade(@builtin(global_invocation_id) id: vec3<u32>) {
    shading_pixel = id.xy;
    shade_pixel(id.xy, false, false);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_stored(@builtin(global_invocation_id) id: vec3<u32>) {
    shading_pixel = id.xy;
    shade_pixel(id.xy, true, false);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_tiles(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    shading_pixel = id.xy;
    shade_tile_group(id.xy, wg.xy, li, false);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_stored_tiles(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    shading_pixel = id.xy;
    shade_tile_group(id.xy, wg.xy, li, true);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_zbin(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    shading_pixel = id.xy;
    shade_zbin_group(id.xy, wg.xy, li, false);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_stored_zbin(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    shading_pixel = id.xy;
    shade_zbin_group(id.xy, wg.xy, li, true);
}

// A covered pixel's surface point (rebuilt from the view depth, or stored), normal, view
// direction and material.
struct Surface {
    p: vec3<f32>,
    n: vec3<f32>,
    v: vec3<f32>,
    m: Material,
}

fn surface(pixel: vec2<u32>, stored: bool) -> Surface {
    let g = textureLoad(gb_normal_depth, pixel, 0);
    let m = materials[textureLoad(gb_material, pixel, 0).x];
    let ndc = vec2<f32>((f32(pixel.x) + 0.5) * frame.viewport.z * 2.0 - 1.0, 1.0 - (f32(pixel.y) + 0.5) * frame.viewport.w * 2.0);
    var p = (frame.world_from_view * vec4<f32>(view_point(ndc, g.w), 1.0)).xyz;
    if stored {
        p = textureLoad(gb_position, pixel, 0).xyz;
    }
    return Surface(p, g.xyz, view_dir(p), m);
}

fn shade_pixel(pixel: vec2<u32>, stored: bool, zbin: bool) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(pixel >= size) {
        return;
    }
    let z = textureLoad(depth_tex, pixel, 0);
    if z >= 1.0 {
        textureStore(out_color, pixel, vec4<f32>(0.0));
        return;
    }
    let s = surface(pixel, stored);
    var c: vec3<f32>;
    if zbin {
        c = shade_zbin(zbin_cell(pixel, z), s.p, s.n, s.v, s.m);
    } else {
        c = shade_list(light_list(pixel, z), s.p, s.n, s.v, s.m);
    }
    textureStore(out_color, pixel, vec4<f32>(c, 1.0));
}

var<workgroup> wg_range: array<atomic<u32>, 2>;
var<workgroup> wg_range_plain: vec2<u32>;

// Z-binning's lights, a workgroup at a time. Where a workgroup's 8 x 8 pixels lie in one tile
// (tiles of a multiple of 8 pixels), they share the tile's mask and differ only in their depth
// bins' ranges: the workgroup walks the mask's bits within the union of its pixels' ranges
// together, each light loaded once for all of them, and each pixel shades the lights of its own
// range. (A loop a pixel over its own range, shade_zbin, makes neighbouring threads load
// different lights at once.) Other tile sizes take the loop a pixel.
fn shade_zbin_group(pixel: vec2<u32>, group: vec2<u32>, li: u32, stored: bool) {
    if cull.tile_size % 8u != 0u {
        shade_pixel(pixel, stored, true);
        return;
    }
    if li == 0u {
        atomicStore(&wg_range[0], 0u);
        atomicStore(&wg_range[1], 0u);
    }
    workgroupBarrier();
    let inside = all(pixel < vec2<u32>(frame.viewport.xy));
    var z = 1.0;
    if inside {
        z = textureLoad(depth_tex, pixel, 0);
    }
    let covered = inside && z < 1.0;
    var cell = ZBinCell(0u, 1u, 0u);
    if covered {
        cell = zbin_cell(pixel, z);
        if cell.first < cell.end {
            atomicMax(&wg_range[0], ~cell.first);
            atomicMax(&wg_range[1], cell.end);
        }
    }
    workgroupBarrier();
    if li == 0u {
        wg_range_plain = vec2<u32>(~atomicLoad(&wg_range[0]), atomicLoad(&wg_range[1]));
    }
    let range = workgroupUniformLoad(&wg_range_plain);
    var c = vec3<f32>(0.0);
    var s: Surface;
    if covered {
        s = surface(pixel, stored);
        c = emitted(s.m);
    }
    if range.x < range.y {
        let tile = group * 8u / cull.tile_size;
        let group_cell = ZBinCell(cull.light_count + (tile.y * cull.tiles_x + tile.x) * zbin_words(), range.x, range.y);
        let infinite = (frame.flags & FRAME_FLAG_INFINITE_RANGE) != 0u;
        for (var w = range.x / 32u; w <= (range.y - 1u) / 32u; w++) {
            var bits = zbin_bits(group_cell, w);
            while bits != 0u {
                let k = w * 32u + firstTrailingBit(bits);
                bits &= bits - 1u;
                let i = light_indices[k];
                if k < cell.first || k >= cell.end {
                    continue;
                }
                let to_light = lights[i].position - s.p;
                let d = length(to_light);
                if !infinite && d >= lights[i].radius {
                    continue;
                }
                c += shade_listed(lights[i], to_light, d, s.n, s.v, s.m);
            }
        }
    }
    if inside {
        textureStore(out_color, pixel, select(vec4<f32>(0.0), vec4<f32>(lights_checked(c), 1.0), covered));
    }
}

// The lights a workgroup holds in workgroup memory at a time (shade_tile_group): 32 lights of
// 64 bytes, 2 KB a workgroup. On an H100 culling and lighting took 7-11% longer with 64 (4 KB),
// 2-3% with 48, up to 1% with 24, 1-2% with 16 and 6% with 8 (docs/bench/HISTORY.md, "The
// lighting pass against its floor").
const TILE_GROUP_LIGHTS: u32 = 32u;
var<workgroup> wg_list: vec2<u32>;
var<workgroup> wg_lights: array<Light, TILE_GROUP_LIGHTS>;

// A list a tile, in tiles of a multiple of 8 pixels (ListForm::Tiles: the tiled strategies, and
// clusters of one slice): a workgroup's 8 x 8 pixels lie in one tile and read one list, so its
// lights go through workgroup memory TILE_GROUP_LIGHTS at a time, each loaded once by one
// thread for all 64 pixels, in the list's order (the same sums as shade_list).
fn shade_tile_group(pixel: vec2<u32>, group: vec2<u32>, li: u32, stored: bool) {
    let inside = all(pixel < vec2<u32>(frame.viewport.xy));
    var z = 1.0;
    if inside {
        z = textureLoad(depth_tex, pixel, 0);
    }
    let covered = inside && z < 1.0;
    if li == 0u {
        let tile = group * 8u / cull.tile_size;
        wg_list = bin_ranges[tile.y * cull.tiles_x + tile.x];
    }
    let list = workgroupUniformLoad(&wg_list);
    var s: Surface;
    if covered {
        s = surface(pixel, stored);
    }
    let infinite = (frame.flags & FRAME_FLAG_INFINITE_RANGE) != 0u;
    var c = vec3<f32>(0.0);
    if covered {
        c = emitted(s.m);
    }
    for (var base = 0u; base < list.y; base += TILE_GROUP_LIGHTS) {
        let n = min(TILE_GROUP_LIGHTS, list.y - base);
        if li < n {
            wg_lights[li] = lights[light_indices[list.x + base + li]];
        }
        workgroupBarrier();
        if covered {
            for (var k = 0u; k < n; k++) {
                let to_light = wg_lights[k].position - s.p;
                let d = length(to_light);
                if !infinite && d >= wg_lights[k].radius {
                    continue;
                }
                c += shade_listed(wg_lights[k], to_light, d, s.n, s.v, s.m);
            }
        }
        workgroupBarrier();
    }
    if inside {
        textureStore(out_color, pixel, select(vec4<f32>(0.0), vec4<f32>(lights_checked(c), 1.0), covered));
    }
}
