// shade.forward (Forward+, Harada et al. 2012): after prepass.depth and culling, the geometry is
// drawn again with depth test `Equal` (the shared invariant vertex stage makes the depths
// bit-identical, so each pixel is shaded once), and each fragment loops over the list its pixel
// reads through lookup.wgsl. shade.naive: the same pass over every light, no culling (the
// baseline). With MSAA each fragment is shaded once, at its centroid, and resolved.
// Every entry point forces the depth test before it (`@early_depth_test(force)`): a shader that
// writes storage (the shadow-ray counters, shading.wgsl) is otherwise tested after it runs, and
// every fragment drawn, hidden ones too, would be shaded.

// The NDC depth a fragment's list is looked up at: with one sample a pixel the depth buffer's
// own (the pixel centre's, bit-identical to the prepass's); with MSAA that of the shaded point,
// the centroid (a covered sample's or, where every sample is covered, the centre's, between
// the samples' depths), which the lists' bounds over every sample hold.
fn lookup_depth(in: VertexOut) -> f32 {
    if DEPTH_SAMPLES == 1u {
        return in.clip.z;
    }
    let c = frame.clip_from_world * vec4<f32>(in.world, 1.0);
    return c.z / c.w;
}

@fragment @early_depth_test(force)
fn fs_forward(in: VertexOut) -> @location(0) vec4<f32> {
    shading_pixel = vec2<u32>(in.clip.xy);
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    let m = materials[in.material];
    let list = light_list(vec2<u32>(in.clip.xy), lookup_depth(in));
    return vec4<f32>(shade_list(list, in.world, n, v, m), 1.0);
}

// shade.forward over z-binning's lists.
@fragment @early_depth_test(force)
fn fs_forward_zbin(in: VertexOut) -> @location(0) vec4<f32> {
    shading_pixel = vec2<u32>(in.clip.xy);
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    let m = materials[in.material];
    let cell = zbin_cell(vec2<u32>(in.clip.xy), lookup_depth(in));
    return vec4<f32>(shade_zbin(cell, in.world, n, v, m), 1.0);
}

@fragment @early_depth_test(force)
fn fs_naive(in: VertexOut) -> @location(0) vec4<f32> {
    shading_pixel = vec2<u32>(in.clip.xy);
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    return vec4<f32>(shade_all(in.world, n, v, materials[in.material]), 1.0);
}

// shade.naive over transparent surfaces: after the opaque ones, back to front, tested against
// the opaque depth without writing it, blended with the surface's opacity.
@fragment @early_depth_test(force)
fn fs_naive_transparent(in: VertexOut) -> @location(0) vec4<f32> {
    shading_pixel = vec2<u32>(in.clip.xy);
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    let m = materials[in.material];
    return vec4<f32>(shade_all(in.world, n, v, m), m.opacity);
}

// shade.forward_transparent: transparent surfaces over the lists (forward's, and deferred's after
// its lighting), after the opaque ones, back to front, tested against the opaque depth without
// writing it, blended with the surface's opacity. Each fragment is looked up where the lookup
// bounds hold it (manylights_gpu::lookup_bounds): culling for it covers the transparent
// surfaces' depths as well as the opaque ones'.
@fragment @early_depth_test(force)
fn fs_forward_transparent(in: VertexOut) -> @location(0) vec4<f32> {
    shading_pixel = vec2<u32>(in.clip.xy);
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    let m = materials[in.material];
    let list = light_list(vec2<u32>(in.clip.xy), lookup_depth(in));
    return vec4<f32>(shade_list(list, in.world, n, v, m), m.opacity);
}

@fragment @early_depth_test(force)
fn fs_forward_transparent_zbin(in: VertexOut) -> @location(0) vec4<f32> {
    shading_pixel = vec2<u32>(in.clip.xy);
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    let m = materials[in.material];
    let cell = zbin_cell(vec2<u32>(in.clip.xy), lookup_depth(in));
    return vec4<f32>(shade_zbin(cell, in.world, n, v, m), m.opacity);
}
