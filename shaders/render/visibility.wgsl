// shade.visibility: the visibility buffer's raster pass (Burns and Hunt 2013). It writes depth
// (read by culling) and a 32-bit id a pixel (a sample with MSAA): the opaque triangle's index in
// the scene's index buffer plus one, 0 where no triangle covers it (the target's clear value).
// The opaque triangles are drawn in one draw from the index buffer's start, so the primitive
// index is the triangle's. Lighting (deferred.wgsl with VISIBILITY) fetches the triangle and
// interpolates its attributes at the pixel; 8 bytes a pixel with depth, against the G-buffer's 24.
// (ShaderDef puts the enable directive before the composed text: a directive comes first.)
enable primitive_index;

@fragment
fn fs_visibility(@builtin(primitive_index) triangle: u32) -> @location(0) u32 {
    return triangle + 1u;
}
