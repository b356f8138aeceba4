// prepass.depth_bounds (manylights_gpu::lookup_bounds): the depth texture culling takes its
// bounds from, of BOUND_SAMPLES samples a pixel, drawn by one triangle over the screen: with
// MSAA twice, each run once a pixel (fs_bounds_far into every sample, then fs_bounds_near into
// sample 0), as run once a sample each sample would repeat the pixel's loads; at one sample a
// pixel once, run once a sample (fs_bounds). A covered pixel's first sample holds the nearest depth at which a fragment drawn there is looked up, its other samples the farthest (kept short of the
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

// A pixel's nearest and farthest lookup depth, and whether anything covers it (z: 1.0 or
// 0.0).
fn pixel_bounds(p: vec2<u32>) -> vec3<f32> {
    var lo = 1.0;
    var hi = 0.0;
    var covered = 0.0;
    for (var s = 0u; s < DEPTH_SAMPLES; s++) {
        let z = textureLoad(depth, p, s);
        if z < 1.0 {
            var r = vec2<f32>(z, z);
            if RANGES {
                r = textureLoad(ranges, p, s).xy;
            }
            lo = min(lo, r.x);
            hi = max(hi, r.y);
            covered = 1.0;
        }
        if TRANSPARENT {
            let n = textureLoad(near, p, s);
            if n < 1.0 {
                lo = min(lo, n);
                hi = max(hi, textureLoad(far, p, s));
                covered = 1.0;
            }
        }
    }
    return vec3<f32>(lo, hi, covered);
}

// The depth written: the bound, kept short of the far plane (which means no surface); 1.0
// where nothing covers the pixel.
fn bound_depth(b: vec3<f32>, bound: f32) -> f32 {
    // The largest f32 below 1.0.
    let below_far = 0.99999994;
    return select(1.0, clamp(bound, 0.0, below_far), b.z > 0.0);
}

// Run once a sample: where the frame has one sample a pixel (its loads are then few, and one
// draw writes each of the 4 samples once).
@fragment
fn fs_bounds(@builtin(position) pos: vec4<f32>, @builtin(sample_index) k: u32) -> @builtin(frag_depth) f32 {
    let b = pixel_bounds(vec2<u32>(pos.xy));
    return bound_depth(b, select(b.y, b.x, k == 0u));
}

// Run once a pixel in two draws of one pass: the farthest into every sample, then (the
// pipeline's sample mask 1) the nearest into sample 0. Where the frame has several samples a
// pixel, whose loads each sample would repeat.
@fragment
fn fs_bounds_far(@builtin(position) pos: vec4<f32>) -> @builtin(frag_depth) f32 {
    let b = pixel_bounds(vec2<u32>(pos.xy));
    return bound_depth(b, b.y);
}

@fragment
fn fs_bounds_near(@builtin(position) pos: vec4<f32>) -> @builtin(frag_depth) f32 {
    let b = pixel_bounds(vec2<u32>(pos.xy));
    return bound_depth(b, b.x);
}
