// prepass.depth_bounds (manylights_gpu::lookup_bounds): the depth texture culling takes its
// bounds from, of BOUND_SAMPLES samples a pixel, drawn by one triangle over the screen and run
// for every sample (sample_index). A covered pixel's first sample holds the nearest depth at
// which a fragment drawn there is looked up, its other samples the farthest (kept short of the
// far plane, which means no surface); an uncovered pixel's samples stay at 1.0. Bounds over
// every sample of a tile or a cluster then hold every depth a forward pass looks a list up at:
// - the opaque surface's: with MSAA forward the depth ranges its visible fragments keep
//   (depth_range.wgsl, RANGES: a fragment is looked up at its centroid); otherwise its depth
//   (deferred lighting looks up at its samples and, where one fragment covers them all, at
//   the pixel centre, between their depths);
// - with TRANSPARENT surfaces, the nearest and the farthest transparent fragment's (their
//   depth ranges over their pixels, as depth_range.wgsl's passes keep them): a pixel behind
//   glass needs lights from the glass to the opaque surface (AMD's TiledLighting11), and a
//   pixel of glass over the background is covered.
// DEPTH_SAMPLES, RANGES and TRANSPARENT are set by the host, and the textures declared
// multisampled where DEPTH_SAMPLES is more than one.
const DEPTH_SAMPLES: u32 = 1u;
const RANGES: bool = false;
const TRANSPARENT: bool = false;

@group(0) @binding(0) var ranges: texture_2d<f32>;
@group(0) @binding(1) var depth: texture_depth_2d;
@group(0) @binding(2) var near: texture_depth_2d;
@group(0) @binding(3) var far: texture_depth_2d;

@fragment
fn fs_bounds(@builtin(position) pos: vec4<f32>, @builtin(sample_index) k: u32) -> @builtin(frag_depth) f32 {
    let p = vec2<u32>(pos.xy);
    var lo = 1.0;
    var hi = 0.0;
    var covered = false;
    for (var s = 0u; s < DEPTH_SAMPLES; s++) {
        let z = textureLoad(depth, p, s);
        if z < 1.0 {
            var r = vec2<f32>(z, z);
            if RANGES {
                r = textureLoad(ranges, p, s).xy;
            }
            lo = min(lo, r.x);
            hi = max(hi, r.y);
            covered = true;
        }
        if TRANSPARENT {
            let n = textureLoad(near, p, s);
            if n < 1.0 {
                lo = min(lo, n);
                hi = max(hi, textureLoad(far, p, s));
                covered = true;
            }
        }
    }
    if !covered {
        return 1.0;
    }
    // The largest f32 below 1.0.
    let below_far = 0.99999994;
    return clamp(select(hi, lo, k == 0u), 0.0, below_far);
}
