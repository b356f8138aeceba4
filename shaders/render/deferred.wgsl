// shade.deferred: the lighting pass of the deferred backend, one thread per pixel. Reads the
// G-buffer, reconstructs the surface point, reads the pixel's list through lookup.wgsl and
// writes HDR radiance (alpha 1 where covered, 0 for background, as the reference does).
@group(2) @binding(0) var gb_normal_depth: texture_2d<f32>;
@group(2) @binding(1) var gb_material: texture_2d<u32>;
@group(2) @binding(2) var out_color: texture_storage_2d<rgba32float, write>;
// The stored world position (deferred_stored_position; a 1 x 1 placeholder otherwise).
@group(2) @binding(3) var gb_position: texture_2d<f32>;

// The view-space point on the ray through NDC (x, y) at view-space z: with rows of
// clip_from_view, x_c = P00 x + P02 z + P03 and w_c = P32 z + P33, so x = (ndc_x w_c - P02 z -
// P03) / P00 (and y alike). Exact for perspective and orthographic cameras.
fn view_point(ndc: vec2<f32>, z: f32) -> vec3<f32> {
    let m = frame.clip_from_view;
    let w = m[2][3] * z + m[3][3];
    return vec3<f32>((ndc.x * w - m[2][0] * z - m[3][0]) / m[0][0], (ndc.y * w - m[2][1] * z - m[3][1]) / m[1][1], z);
}

// An entry point for each form of lists (list_shading.wgsl): `zbin` is a constant of each.
@compute @workgroup_size(8, 8)
fn deferred_shade(@builtin(global_invocation_id) id: vec3<u32>) {
    shade_pixel(id.xy, false, false);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_stored(@builtin(global_invocation_id) id: vec3<u32>) {
    shade_pixel(id.xy, true, false);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_zbin(@builtin(global_invocation_id) id: vec3<u32>) {
    shade_pixel(id.xy, false, true);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_stored_zbin(@builtin(global_invocation_id) id: vec3<u32>) {
    shade_pixel(id.xy, true, true);
}

fn shade_pixel(pixel: vec2<u32>, stored: bool, zbin: bool) {
    let id = vec3<u32>(pixel, 0u);
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let z = textureLoad(depth_tex, id.xy, 0);
    if z >= 1.0 {
        textureStore(out_color, id.xy, vec4<f32>(0.0));
        return;
    }
    let g = textureLoad(gb_normal_depth, id.xy, 0);
    let m = materials[textureLoad(gb_material, id.xy, 0).x];
    let ndc = vec2<f32>((f32(id.x) + 0.5) * frame.viewport.z * 2.0 - 1.0, 1.0 - (f32(id.y) + 0.5) * frame.viewport.w * 2.0);
    var p = (frame.world_from_view * vec4<f32>(view_point(ndc, g.w), 1.0)).xyz;
    if stored {
        p = textureLoad(gb_position, id.xy, 0).xyz;
    }
    let v = view_dir(p);
    var c: vec3<f32>;
    if zbin {
        c = shade_zbin(zbin_cell(id.xy, z), p, g.xyz, v, m);
    } else {
        c = shade_list(light_list(id.xy, z), p, g.xyz, v, m);
    }
    textureStore(out_color, id.xy, vec4<f32>(c, 1.0));
}
