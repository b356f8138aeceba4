// shade.visibility_depth: the compute visibility pass's NDC depths (visibility_resolve.wgsl) into
// a depth buffer, for what reads one (the exact oracle, the per-pixel list consumers). Drawn once
// a frame outside its timed passes: culling and lighting read the R32Float depths themselves,
// as a compute pass cannot write a depth texture. Depth32Float holds each f32 as it is, so the
// oracle checks the very depths the lists were built over.
@group(0) @binding(0) var vd_depth: texture_2d<f32>;

// One triangle over the whole target.
@vertex
fn vis_depth_vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn vis_depth_fs(@builtin(position) p: vec4<f32>) -> @builtin(frag_depth) f32 {
    return textureLoad(vd_depth, vec2<u32>(p.xy), 0).x;
}
