// One triangle over the whole screen (vertex_index 0..3): the vertex stage of the full-screen
// passes (prepass.depth_bounds, shade.deferred_expand); manylights_gpu::pipeline::screen.
@vertex
fn vs_screen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}
