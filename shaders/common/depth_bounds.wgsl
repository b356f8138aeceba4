// prepass.depth_bounds (manylights_gpu::msaa_bounds): the multisampled depth texture culling
// takes its bounds from under MSAA, drawn by one triangle over the screen and run for every
// sample (sample_index). A covered pixel's first sample holds the nearest depth of the ranges
// its visible fragments keep (depth_range.wgsl), its other samples the farthest, kept short of
// the far plane, which means no surface; an uncovered pixel's samples stay at 1.0. Bounds over
// every sample of a tile or a cluster then hold every depth a forward pass looks a list up at.
@group(0) @binding(0) var ranges: texture_multisampled_2d<f32>;
@group(0) @binding(1) var depth: texture_depth_multisampled_2d;

@vertex
fn vs_screen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_bounds(@builtin(position) pos: vec4<f32>, @builtin(sample_index) k: u32) -> @builtin(frag_depth) f32 {
    let p = vec2<u32>(pos.xy);
    var lo = 1.0;
    var hi = 0.0;
    var covered = false;
    for (var s = 0u; s < textureNumSamples(depth); s++) {
        if textureLoad(depth, p, s) < 1.0 {
            let r = textureLoad(ranges, p, s).xy;
            lo = min(lo, r.x);
            hi = max(hi, r.y);
            covered = true;
        }
    }
    if !covered {
        return 1.0;
    }
    // The largest f32 below 1.0.
    let below_far = 0.99999994;
    return clamp(select(hi, lo, k == 0u), 0.0, below_far);
}
