// cull.exact: the exact per-pixel oracle on the GPU, for images too large for the CPU's
// O(pixels x lights). With MSAA, every covered sample of a pixel, at its standard position. Per covered pixel: the surface point reconstructed from the depth buffer
// (as the CPU oracle does, but in f32), the number of lights reaching it (needed), the length of
// its list (evaluated) and how many list entries reach it (found). Lists hold no duplicates
// (tested), so false negatives = needed - found. Decisions within f32 rounding of a light's
// radius or cone may differ from the f64 CPU oracle; a test bounds that difference.
// Host mirror: manylights_cull::layout::GpuExactParams.
struct ExactParams {
    world_from_clip: mat4x4<f32>,
    // Only pixels whose x and y are multiples of stride are evaluated (1: every pixel); the
    // others report as not covered. Lets large experiments sample the O(pixels x lights) oracle.
    stride: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(1) @binding(4) var<storage, read_write> counts: array<vec4<u32>>;
@group(1) @binding(5) var<uniform> exact: ExactParams;

// manylights_scene::Light::reaches, in f32.
fn reaches(l: Light, p: vec3<f32>) -> bool {
    let to_p = p - l.position;
    let d = length(to_p);
    if d >= l.radius {
        return false;
    }
    if l.kind == LIGHT_KIND_SPOT {
        return d > 0.0 && dot(to_p, l.direction) / d > l.cos_outer;
    }
    return true;
}

// One sample of a pixel: (evaluated, needed, found) at its surface point (depth z, at the
// sample's position in the pixel).
fn sample_counts(pixel: vec2<u32>, z: f32, at: vec2<f32>) -> vec3<u32> {
    let ndc = vec4<f32>((f32(pixel.x) + at.x) * frame.viewport.z * 2.0 - 1.0, 1.0 - (f32(pixel.y) + at.y) * frame.viewport.w * 2.0, z, 1.0);
    let q = exact.world_from_clip * ndc;
    let p = q.xyz / q.w;
    var needed = 0u;
    for (var k = 0u; k < frame.light_count; k++) {
        if reaches(lights[k], p) {
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
                    if reaches(lights[light_indices[k]], p) {
                        found += 1u;
                    }
                }
            }
        }
    } else {
        let list = light_list(pixel, z);
        evaluated = list.y;
        for (var k = 0u; k < list.y; k++) {
            if reaches(lights[light_indices[list.x + k]], p) {
                found += 1u;
            }
        }
    }
    return vec3<u32>(evaluated, needed, found);
}

// Per pixel: (evaluated, needed, found, covered), summed over its covered samples with MSAA
// (covered: how many), each sample checked against the list its own depth selects.
@compute @workgroup_size(8, 8)
fn exact_counts(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let i = id.y * size.x + id.x;
    var total = vec4<u32>(0u);
    if id.x % exact.stride == 0u && id.y % exact.stride == 0u {
        for (var sample_k = 0u; sample_k < DEPTH_SAMPLES; sample_k++) {
            let z = textureLoad(depth_tex, id.xy, sample_k);
            if z < 1.0 {
                total += vec4<u32>(sample_counts(id.xy, z, sample_position(sample_k)), 1u);
            }
        }
    }
    counts[i] = total;
}
