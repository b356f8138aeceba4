// shade.gbuffer: the geometry pass of the deferred backends. It writes depth (read by culling)
// and only what lighting needs: the shading normal with the linear view depth, and the material
// index (the material table holds the albedo and specular weight); 20 bytes a pixel plus 4 of
// depth. `deferred` rebuilds the position from the view depth and the pixel centre
// (deferred.wgsl); `deferred_stored_position` (fs_gbuffer_stored) also stores the interpolated
// world position (16 bytes more), which is what forward shading evaluates, so that the two agree
// to rounding on any GPU.
struct GBufferOut {
    // xyz = shading normal (turned towards the viewer), w = view-space z.
    @location(0) normal_depth: vec4<f32>,
    @location(1) material: u32,
}

fn gbuffer_of(in: VertexOut) -> GBufferOut {
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    let view_z = (frame.view_from_world * vec4<f32>(in.world, 1.0)).z;
    return GBufferOut(vec4<f32>(n, view_z), in.material);
}

@fragment
fn fs_gbuffer(in: VertexOut) -> GBufferOut {
    return gbuffer_of(in);
}

struct GBufferStoredOut {
    @location(0) normal_depth: vec4<f32>,
    @location(1) material: u32,
    // xyz = interpolated world position.
    @location(2) position: vec4<f32>,
}

@fragment
fn fs_gbuffer_stored(in: VertexOut) -> GBufferStoredOut {
    let g = gbuffer_of(in);
    return GBufferStoredOut(g.normal_depth, g.material, vec4<f32>(in.world, 1.0));
}
