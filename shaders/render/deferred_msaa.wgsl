// shade.deferred with MSAA (Lauritzen 2010, "Deferred rendering for current and future rendering
// pipelines"): over a multisampled G-buffer, one thread a pixel lights the pixel once where one
// fragment covers all its samples (their G-buffer samples are equal: the G-buffer pass writes a
// fragment's values to every sample it covers), and each covered sample apart where they differ
// (an edge), averaging the samples into the pixel (alpha: the covered fraction, as the resolve
// of the references gives). Once a pixel: at the pixel centre, at the view depth the G-buffer
// holds (a fully covered fragment's centroid is the centre), looked up at that depth, which lies
// between its samples' (the culling bounds cover every sample, and clusters every slice between
// a pixel's samples). At an edge: each sample at its own depth and standard position, looked up
// at its depth, exactly the points the exact oracle checks.
// With GLASS, shade.forward_transparent has drawn the transparent surfaces first into a layer
// of their own (each sample: their contribution in rgb, their transmittance in alpha), and each
// sample's colour is composited under it before the average, as the reference blends the glass
// over each sample.
// With VISIBILITY (surface.wgsl), the same from the triangle ids (shade_triangles_msaa). The
// MSAA reference (shade.reference_samples) lights every pixel this way. With GBUFFER_IDS (a
// device with primitive_index: gbuffer_ids.wgsl), the G-buffer holds each sample's triangle id
// in the material's place, and a pixel is lit as the reference lights it, once where one fragment
// covers every sample (its surface the G-buffer's, the material its triangle's) and elsewhere
// each sample on its triangle (shade_gbuffer_ids_msaa): an edge sample's normal is the one the
// reference interpolates there, not its fragment's at the centroid.
@group(2) @binding(0) var gb_normal_depth: texture_multisampled_2d<f32>;
@group(2) @binding(1) var gb_material: texture_multisampled_2d<u32>;
@group(2) @binding(3) var glass: texture_multisampled_2d<f32>;

override GLASS: bool = false;
override GBUFFER_IDS: bool = false;

// Sample k's colour c (alpha: 1 where covered, 0 for background) under the glass layer.
fn under_glass(pixel: vec2<u32>, k: u32, c: vec4<f32>) -> vec4<f32> {
    let g = textureLoad(glass, pixel, k);
    return vec4<f32>(g.rgb + g.a * c.rgb, 1.0 - g.a + g.a * c.a);
}

// The mean of the samples' colours each under the glass, where each has the colour c.
fn all_under_glass(pixel: vec2<u32>, c: vec4<f32>) -> vec4<f32> {
    var sum = vec4<f32>(0.0);
    for (var k = 0u; k < DEPTH_SAMPLES; k++) {
        sum += under_glass(pixel, k, c);
    }
    return sum / f32(DEPTH_SAMPLES);
}

// An entry point for each form of lists, as deferred.wgsl has.
@compute @workgroup_size(8, 8)
fn deferred_shade_msaa(@builtin(global_invocation_id) id: vec3<u32>) {
    shading_pixel = id.xy;
    shade_pixel_msaa(id.xy, false);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_msaa_zbin(@builtin(global_invocation_id) id: vec3<u32>) {
    shading_pixel = id.xy;
    shade_pixel_msaa(id.xy, true);
}

// The NDC depth of view-space z (rows of clip_from_view; exact for both projections).
fn ndc_depth(view_z: f32) -> f32 {
    let m = frame.clip_from_view;
    return (m[2][2] * view_z + m[3][2]) / (m[2][3] * view_z + m[3][3]);
}

// The lights of the pixel's list at NDC depth z, shaded at s.
fn shade_point(pixel: vec2<u32>, z: f32, s: Surface, zbin: bool) -> vec3<f32> {
    if zbin {
        return shade_zbin(zbin_cell(pixel, z), s.p, s.n, s.v, s.m);
    }
    return shade_list(light_list(pixel, z), s.p, s.n, s.v, s.m);
}

// A G-buffer sample's surface: at p, with the sample's normal and material (with GBUFFER_IDS,
// its triangle's: the first vertex's, as visibility_surface takes it).
fn gbuffer_surface(p: vec3<f32>, pixel: vec2<u32>, k: u32) -> Surface {
    let v = view_dir(p);
    var m = textureLoad(gb_material, pixel, k).x;
    if GBUFFER_IDS {
        m = vis_material(vis_indices[3u * (m - 1u)]);
    }
    return Surface(p, textureLoad(gb_normal_depth, pixel, k).xyz, v, materials[m]);
}

// The NDC depth of world point p.
fn world_ndc_depth(p: vec3<f32>) -> f32 {
    return ndc_depth((frame.view_from_world * vec4<f32>(p, 1.0)).z);
}

// A pixel one fragment covers, lit once at its centre from G-buffer sample 0 at view depth
// `view_z` (under the glass with GLASS).
fn gbuffer_centre(pixel: vec2<u32>, view_z: f32, zbin: bool) -> vec4<f32> {
    let q = view_point(screen_ndc(vec2<f32>(pixel) + 0.5), view_z);
    let p = (frame.world_from_view * vec4<f32>(q, 1.0)).xyz;
    let c = vec4<f32>(shade_point(pixel, ndc_depth(view_z), gbuffer_surface(p, pixel, 0u), zbin), 1.0);
    if GLASS {
        return all_under_glass(pixel, c);
    }
    return c;
}

fn shade_pixel_msaa(pixel: vec2<u32>, zbin: bool) {
    if any(pixel >= vec2<u32>(frame.viewport.xy)) {
        return;
    }
    if VISIBILITY {
        shade_triangles_msaa(pixel, zbin);
        return;
    }
    if GBUFFER_IDS {
        shade_gbuffer_ids_msaa(pixel, zbin);
        return;
    }
    let g0 = textureLoad(gb_normal_depth, pixel, 0);
    let m0 = textureLoad(gb_material, pixel, 0).x;
    var covered = 0u;
    var edge = false;
    for (var k = 0u; k < DEPTH_SAMPLES; k++) {
        covered += u32(textureLoad(depth_tex, pixel, k) < 1.0);
        edge = edge || any(textureLoad(gb_normal_depth, pixel, k) != g0) || textureLoad(gb_material, pixel, k).x != m0;
    }
    if covered == 0u {
        var background = vec4<f32>(0.0);
        if GLASS {
            background = all_under_glass(pixel, background);
        }
        textureStore(out_color, pixel, background);
        return;
    }
    if !edge && covered == DEPTH_SAMPLES {
        textureStore(out_color, pixel, gbuffer_centre(pixel, g0.w, zbin));
        return;
    }
    var c = vec4<f32>(0.0);
    for (var k = 0u; k < DEPTH_SAMPLES; k++) {
        let z = textureLoad(depth_tex, pixel, k);
        var ck = vec4<f32>(0.0);
        if z < 1.0 {
            let q = view_point(screen_ndc(vec2<f32>(pixel) + sample_position(k)), -linear_depth(z));
            let p = (frame.world_from_view * vec4<f32>(q, 1.0)).xyz;
            ck = vec4<f32>(shade_point(pixel, z, gbuffer_surface(p, pixel, k), zbin), 1.0);
        }
        if GLASS {
            ck = under_glass(pixel, k, ck);
        }
        c += ck;
    }
    textureStore(out_color, pixel, c / f32(DEPTH_SAMPLES));
}

// A visibility buffer's pixel, lit as the G-buffer's is: where one triangle covers every
// sample, once at the pixel centre (on the triangle: the samples' hull holds the centre), looked
// up at that point's depth held within its samples' (which it lies between but for rounding;
// the culling bounds cover those); elsewhere each covered sample at its own position on its
// triangle, looked up at its depth (each under the glass with GLASS).
fn shade_triangles_msaa(pixel: vec2<u32>, zbin: bool) {
    let id0 = textureLoad(gb_material, pixel, 0).x;
    var one = id0 != 0u;
    var z_range = vec2<f32>(1.0, 0.0);
    for (var k = 0u; k < DEPTH_SAMPLES; k++) {
        one = one && textureLoad(gb_material, pixel, k).x == id0;
        let z = textureLoad(depth_tex, pixel, k);
        z_range = vec2<f32>(min(z_range.x, z), max(z_range.y, z));
    }
    if one {
        let s = visibility_surface(screen_ndc(vec2<f32>(pixel) + 0.5), id0 - 1u);
        let z = clamp(world_ndc_depth(s.p), z_range.x, z_range.y);
        var c = vec4<f32>(shade_point(pixel, z, s, zbin), 1.0);
        if GLASS {
            c = all_under_glass(pixel, c);
        }
        textureStore(out_color, pixel, c);
        return;
    }
    textureStore(out_color, pixel, triangle_samples(pixel, zbin));
}

// The mean of a pixel's samples each lit at its own position on its triangle (the ids in
// gb_material), looked up at its depth (each under the glass with GLASS).
fn triangle_samples(pixel: vec2<u32>, zbin: bool) -> vec4<f32> {
    var c = vec4<f32>(0.0);
    for (var k = 0u; k < DEPTH_SAMPLES; k++) {
        let id = textureLoad(gb_material, pixel, k).x;
        var ck = vec4<f32>(0.0);
        if id != 0u {
            let s = visibility_surface(screen_ndc(vec2<f32>(pixel) + sample_position(k)), id - 1u);
            ck = vec4<f32>(shade_point(pixel, textureLoad(depth_tex, pixel, k), s, zbin), 1.0);
        }
        if GLASS {
            ck = under_glass(pixel, k, ck);
        }
        c += ck;
    }
    return c / f32(DEPTH_SAMPLES);
}

// A G-buffer's pixel with GBUFFER_IDS: where one fragment covers every sample (one triangle,
// and the same G-buffer values: a rasteriser may split a pixel of one triangle into fragments,
// as llvmpipe does at some edges, each interpolated elsewhere), once at the centre from
// G-buffer sample 0 (the centroid of a fragment that covers every sample is the centre), as
// the pixel is lit without the ids; elsewhere each covered sample on its triangle
// (triangle_samples), as the reference lights it.
fn shade_gbuffer_ids_msaa(pixel: vec2<u32>, zbin: bool) {
    let id0 = textureLoad(gb_material, pixel, 0).x;
    let g0 = textureLoad(gb_normal_depth, pixel, 0);
    var one = id0 != 0u;
    for (var k = 1u; k < DEPTH_SAMPLES; k++) {
        one = one && textureLoad(gb_material, pixel, k).x == id0 && all(textureLoad(gb_normal_depth, pixel, k) == g0);
    }
    if one {
        textureStore(out_color, pixel, gbuffer_centre(pixel, g0.w, zbin));
        return;
    }
    textureStore(out_color, pixel, triangle_samples(pixel, zbin));
}
