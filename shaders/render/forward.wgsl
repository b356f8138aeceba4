// shade.forward (Forward+, Harada et al. 2012): after prepass.depth and culling, the geometry is
// drawn again with depth test `Equal` (the shared invariant vertex stage makes the depths
// bit-identical, so each pixel is shaded once), and each fragment loops over the list its pixel
// reads through lookup.wgsl. shade.naive: the same pass over every light, no culling (the
// baseline).

@fragment
fn fs_forward(in: VertexOut) -> @location(0) vec4<f32> {
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    let m = materials[in.material];
    let list = light_list(vec2<u32>(in.clip.xy), in.clip.z);
    return vec4<f32>(shade_list(list, in.world, n, v, m), 1.0);
}

// shade.forward over z-binning's lists.
@fragment
fn fs_forward_zbin(in: VertexOut) -> @location(0) vec4<f32> {
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    let m = materials[in.material];
    let cell = zbin_cell(vec2<u32>(in.clip.xy), in.clip.z);
    return vec4<f32>(shade_zbin(cell, in.world, n, v, m), 1.0);
}

@fragment
fn fs_naive(in: VertexOut) -> @location(0) vec4<f32> {
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    return vec4<f32>(shade_all(in.world, n, v, materials[in.material]), 1.0);
}
