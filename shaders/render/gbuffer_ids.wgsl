// shade.gbuffer with MSAA where the device has `@builtin(primitive_index)` (GBUFFER_IDS in
// deferred_msaa.wgsl): the G-buffer's normal and view depth, and in the material's place the
// triangle's id (its index in the scene's index buffer plus one, as the visibility buffer writes
// it; 0 where no triangle covers a sample), from which deferred lighting finds an edge sample's
// point, normal and material on its triangle, as the reference does, and a pixel's material.
// (The opaque triangles are drawn in one draw from the index buffer's start.)
enable primitive_index;

@fragment
fn fs_gbuffer_ids(in: VertexOut, @builtin(primitive_index) triangle: u32) -> GBufferOut {
    return GBufferOut(gbuffer_of(in).normal_depth, triangle + 1u);
}
