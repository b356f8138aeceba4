// shade.gbuffer: the geometry pass of the deferred backend. It writes depth (read by culling)
// and only what lighting needs: the shading normal with the linear view depth, and the material
// index (the material table holds the albedo and specular weight). Position is reconstructed
// from the view depth and the pixel centre (deferred.wgsl). Everything is f32 so that deferred
// and forward shading agree to rounding; 20 bytes a pixel plus 4 of depth.
struct GBufferOut {
    // xyz = shading normal (turned towards the viewer), w = view-space z.
    @location(0) normal_depth: vec4<f32>,
    @location(1) material: u32,
}

@fragment
fn fs_gbuffer(in: VertexOut) -> GBufferOut {
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    let view_z = (frame.view_from_world * vec4<f32>(in.world, 1.0)).z;
    return GBufferOut(vec4<f32>(n, view_z), in.material);
}
