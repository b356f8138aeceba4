// The one vertex stage of every raster pass: depth prepass, reference, forward and G-buffer.
// Sharing it (with an invariant position) makes the prepass depth and the later passes' depth
// bit-identical, so those passes can test depth with `Equal` and shade each pixel once.
// Host mirror of the vertex: manylights_gpu::layout::GpuVertex.
struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) material: u32,
}

// The surface point and normal are interpolated at the centroid: with one sample a pixel that
// is the pixel centre; with MSAA, a point of the pixel the primitive covers (the centre where
// it covers every sample), never a point off the primitive, whose depth no sample has.
struct VertexOut {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) @interpolate(perspective, centroid) world: vec3<f32>,
    @location(1) @interpolate(perspective, centroid) normal: vec3<f32>,
    @location(2) @interpolate(flat) material: u32,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.clip_from_world * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.material = v.material;
    return out;
}
