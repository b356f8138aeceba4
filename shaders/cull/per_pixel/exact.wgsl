// cull.exact: the exact per-pixel oracle on the GPU, for images too large for the CPU's
// O(pixels x lights). Per covered pixel: the surface point reconstructed from the depth buffer
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

@compute @workgroup_size(8, 8)
fn exact_counts(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let i = id.y * size.x + id.x;
    let z = textureLoad(depth_tex, id.xy, 0);
    if z >= 1.0 || id.x % exact.stride != 0u || id.y % exact.stride != 0u {
        counts[i] = vec4<u32>(0u);
        return;
    }
    let ndc = vec4<f32>((f32(id.x) + 0.5) * frame.viewport.z * 2.0 - 1.0, 1.0 - (f32(id.y) + 0.5) * frame.viewport.w * 2.0, z, 1.0);
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
        let c = zbin_cell(id.xy, z);
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
        let list = light_list(id.xy, z);
        evaluated = list.y;
        for (var k = 0u; k < list.y; k++) {
            if reaches(lights[light_indices[list.x + k]], p) {
                found += 1u;
            }
        }
    }
    counts[i] = vec4<u32>(evaluated, needed, found, 1u);
}
