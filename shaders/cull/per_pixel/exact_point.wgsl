// The exact oracle on the GPU, for images too large for the CPU's O(pixels x lights):
// cull.exact (exact.wgsl) at every covered sample of the depth buffer (with MSAA each at its
// standard position), cull.exact_transparent (exact_transparent.wgsl) at every visible
// transparent fragment. At each surface point (reconstructed from the depth buffer as the CPU
// oracle does, but in f32; a transparent fragment's interpolated point): the number of lights
// reaching it (needed; with shadows, reaching and seen), the length of its list (evaluated) and how many list entries reach it
// (found). Lists hold no duplicates (tested), so false negatives = needed - found. Decisions
// within f32 rounding of a light's radius or cone may differ from the f64 CPU oracle; a test
// bounds that difference.
// Host mirror: manylights_cull::layout::GpuExactParams.
struct ExactParams {
    world_from_clip: mat4x4<f32>,
    // Only pixels whose x and y are multiples of stride are evaluated (1: every pixel); the
    // others report as not covered. Lets large experiments sample the O(pixels x lights) oracle.
    stride: u32,
    // 1: the exact set is shadowed (seen).
    shadows: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(1) @binding(5) var<uniform> exact: ExactParams;

// manylights_scene::Light::reaches, in f32.
fn reaches(l: Light, p: vec3<f32>) -> bool {
    let to_p = p - l.position;
    let d = length(to_p);
    if d >= l.radius {
        return false;
    }
    if light_shape(l) == LIGHT_KIND_SPOT {
        return d > 0.0 && dot(to_p, l.direction) / d > l.cos_outer;
    }
    return true;
}

// Whether light `l`, reaching p, is seen from it: where the segment to the light from p lifted
// towards it by a shadow ray's lift (SHADOW_OFFSET times p's largest coordinate's magnitude, at
// least 1: the normal is not at hand; culling by visibility spares that lift in every direction)
// is clear through the BVH.
fn seen(l: Light, p: vec3<f32>) -> bool {
    let a = abs(p);
    let origin = p + normalize(l.position - p) * (SHADOW_OFFSET * max(max(a.x, a.y), max(a.z, 1.0)));
    return !bvh_blocked(origin, l.position);
}

// Whether light `l` is in the exact set of p: it reaches p and, with `shadowed`, is seen.
fn needs(l: Light, p: vec3<f32>, shadowed: bool) -> bool {
    return reaches(l, p) && (!shadowed || seen(l, p));
}

// A surface point p of a pixel, whose list is looked up at NDC depth z: (evaluated, needed,
// found), the exact set shadowed with exact.shadows. The test is made outside the loops, each
// call with a constant: llvmpipe enters a loop that no lane runs, such as the BVH's in a light's
// test without shadows, and counts that against its loop limit (GpuContext::loop_limit), which
// three loops a light ran out of at 21,846 lights.
fn point_counts(pixel: vec2<u32>, z: f32, p: vec3<f32>) -> vec3<u32> {
    if exact.shadows != 0u {
        return counts_at(pixel, z, p, true);
    }
    return counts_at(pixel, z, p, false);
}

fn counts_at(pixel: vec2<u32>, z: f32, p: vec3<f32>, shadowed: bool) -> vec3<u32> {
    var needed = 0u;
    for (var k = 0u; k < frame.light_count; k++) {
        if needs(lights[k], p, shadowed) {
            needed += 1u;
        }
    }
    var evaluated = 0u;
    var found = 0u;
    if zbin_lists() {
        let c = zbin_cell(pixel, z);
        if c.first < c.end {
            for (var w = c.first / 32u; w <= (c.end - 1u) / 32u; w++) {
                var bits = zbin_bits(c, w);
                while bits != 0u {
                    let k = w * 32u + firstTrailingBit(bits);
                    bits &= bits - 1u;
                    evaluated += 1u;
                    if needs(lights[light_indices[k]], p, shadowed) {
                        found += 1u;
                    }
                }
            }
        }
    } else {
        let list = light_list(pixel, z);
        evaluated = list.y;
        for (var k = 0u; k < list.y; k++) {
            if needs(lights[light_indices[list.x + k]], p, shadowed) {
                found += 1u;
            }
        }
    }
    return vec3<u32>(evaluated, needed, found);
}
