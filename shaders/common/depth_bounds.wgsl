// prepass.depth_bounds (manylights_gpu::lookup_bounds): a compute pass, a thread a pixel, that
// writes the lookup bounds culling reads (shaders/cull/common/depth_input_bounds.wgsl): a covered
// pixel's nearest depth at which a fragment drawn there is looked up into x and its farthest
// into y (kept short of the far plane, which means no surface); an uncovered pixel's both 1.0.
// Bounds over every pixel of a tile or a cluster then hold every depth a forward pass looks a
// list up at:
// - the opaque surface's: with MSAA forward the depth ranges its visible fragments keep
//   (depth_range.wgsl, RANGES: a fragment is looked up at its centroid); otherwise its depth
//   samples (deferred lighting looks up at its samples and, where one fragment covers them
//   all, at the pixel centre, between their depths);
// - with TRANSPARENT surfaces, the nearest and the farthest transparent fragment's (their
//   depth ranges over their pixels, as depth_range.wgsl's passes keep them): a pixel behind
//   glass needs lights from the glass to the opaque surface (AMD's TiledLighting11), and a
//   pixel of glass over the background is covered.
// Its textures and DEPTH_SAMPLES come from depth_bounds_inputs.wgsl (one sample a pixel) or
// depth_bounds_inputs_msaa.wgsl (multisampled) before it; RANGES and TRANSPARENT are the
// pipeline's override constants.
override RANGES: bool = false;
override TRANSPARENT: bool = false;

@group(0) @binding(4) var bounds: texture_storage_2d<rg32float, write>;

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

@compute @workgroup_size(8, 8)
fn depth_bounds(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(bounds);
    if any(id.xy >= size) {
        return;
    }
    let b = pixel_bounds(id.xy);
    textureStore(bounds, id.xy, vec4<f32>(bound_depth(b, b.x), bound_depth(b, b.y), 0.0, 0.0));
}
