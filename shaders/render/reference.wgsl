// shade.reference: brute-force forward shading of every light, no culling. The accuracy
// reference of every strategy and backend. Runs after prepass.depth with depth test `Equal`,
// so each pixel is shaded once. Besides the HDR colour it writes the shaded surface point and
// the shading normal (turned towards the viewer: surfaces are two-sided) for the CPU oracles.

struct ReferenceOut {
    @location(0) color: vec4<f32>,
    // xyz = world position, w = 1 where covered (the clear value is w = 0).
    @location(1) position: vec4<f32>,
    // xyz = unit shading normal.
    @location(2) normal: vec4<f32>,
}

@fragment @early_depth_test(force)
fn fs_reference(in: VertexOut) -> ReferenceOut {
    shading_pixel = vec2<u32>(in.clip.xy);
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    let c = shade_all(in.world, n, v, materials[in.material]);
    return ReferenceOut(vec4<f32>(c, 1.0), vec4<f32>(in.world, 1.0), vec4<f32>(n, f32(in.material)));
}

// The surfaces alone (no light evaluated; colour 0 where covered): the input of the
// infinite-range reference's compute pass where the windowed reference is not wanted.
@fragment
fn fs_surface(in: VertexOut) -> ReferenceOut {
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    return ReferenceOut(vec4<f32>(0.0, 0.0, 0.0, 1.0), vec4<f32>(in.world, 1.0), vec4<f32>(n, f32(in.material)));
}

// shade.reference over transparent surfaces: after the opaque ones, back to front, tested
// against the opaque depth without writing it; the surface's radiance with its opacity as the
// blend weight, into the colour target only (the position and normal stay the opaque
// surface's).
@fragment @early_depth_test(force)
fn fs_reference_transparent(in: VertexOut) -> @location(0) vec4<f32> {
    shading_pixel = vec2<u32>(in.clip.xy);
    let v = view_dir(in.world);
    let n = facing_normal(normalize(in.normal), v);
    let m = materials[in.material];
    return vec4<f32>(shade_all(in.world, n, v, m), m.opacity);
}
