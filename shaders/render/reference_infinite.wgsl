// shade.reference_infinite: the infinite-range reference (no radius cut-off) as a compute pass
// over the reference's surface points, for scenes where a fragment shader looping over every
// light at every pixel is too slow (a million lights at 1080p). Host side:
// manylights_shade::infinite, which dispatches it once a chunk of lights, so that no dispatch
// runs long, each chunk adding into the running sums of the chunks before it.
//
// Each pixel keeps its sum with Kahan's compensated summation (a running sum and the low-order
// part lost from it): a million terms of widely different size (1 / d^2 spans eight decades in
// a hall) summed in plain f32 lose up to about 1e-4 of the total; compensated, the error stays
// within a few ulps of the f64 sum (tests/reference.rs checks it against light::shade in f64).
// Lights reach the workgroup through workgroup memory, a batch of WG at a time, as an n-body
// kernel reads its bodies: every thread of a workgroup reads every light of the chunk.
// With SHADOWS (InfiniteReference::with_shadows) each light's contribution is shadowed, a ray
// a (pixel, light): the shadowed infinite-range reference.
// With SHADOWS and ESTIMATE_RAYS = R > 0 (InfiniteReference::with_estimate) it is estimated
// without bias, R rays a pixel in expectation: each light's unshadowed radiance c casts its ray
// with probability q = min(1, R luminance(c) / L), L the pixel's unshadowed luminance (the
// compensation texel's w, which the host seeds from the unshadowed reference), and adds its
// shadowed radiance over q where it does, nothing where it does not: E = the shadowed c.

struct InfiniteParams {
    // The chunk: lights [first, first + count).
    first: u32,
    count: u32,
    // Pixels in the image.
    pixels: u32,
    // Threads in a row of the dispatch grid (workgroups in x times WG).
    row: u32,
    // The estimate's draws (ESTIMATE_RAYS): a seed of their own for each independent estimate.
    seed: u32,
}

@group(1) @binding(0) var<uniform> params: InfiniteParams;
// Two texels a pixel: the surface point (w = 1 where covered) and the shading normal (turned
// towards the viewer) with the material index in w.
@group(1) @binding(1) var<storage, read> surface: array<vec4<f32>>;
// Two a pixel: the running sum (rgb) and its compensation (rgb).
@group(1) @binding(2) var<storage, read_write> sums: array<vec4<f32>>;

const WG: u32 = 64u;

override ESTIMATE_RAYS: f32 = 0.0;

var<workgroup> batch: array<Light, WG>;

@compute @workgroup_size(64)
fn reference_infinite(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let i = gid.x + gid.y * params.row;
    let live = i < params.pixels;
    var p = vec4<f32>(0.0);
    var n = vec4<f32>(0.0);
    var sum = vec3<f32>(0.0);
    var comp = vec3<f32>(0.0);
    var lum = 0.0;
    if live {
        p = surface[2u * i];
        n = surface[2u * i + 1u];
        sum = sums[2u * i].xyz;
        comp = sums[2u * i + 1u].xyz;
        lum = sums[2u * i + 1u].w;
    }
    let covered = live && p.w > 0.0;
    let m = materials[u32(n.w)];
    // The emission once, with the first chunk of lights.
    if covered && params.first == 0u {
        sum = emitted(m);
        comp = vec3<f32>(0.0);
    }
    let v = view_dir(p.xyz);
    // Every thread runs every batch (the barriers need uniform control flow); only covered
    // pixels shade.
    for (var base = 0u; base < params.count; base += WG) {
        if base + li < params.count {
            batch[li] = lights[params.first + base + li];
        }
        workgroupBarrier();
        if covered {
            let k = min(WG, params.count - base);
            for (var j = 0u; j < k; j++) {
                var c = light_infinite(batch[j], p.xyz, n.xyz, v, m);
                if ESTIMATE_RAYS > 0.0 {
                    let w = shading_luminance(c);
                    if w > 0.0 {
                        let q = select(1.0, min(1.0, ESTIMATE_RAYS * w / lum), lum > 0.0);
                        let u = f32(pcg(i ^ pcg((params.first + base + j) ^ pcg(params.seed))) >> 8u) * (1.0 / 16777216.0);
                        if u < q {
                            c = shadowed(c, batch[j], p.xyz, n.xyz) / q;
                        } else {
                            c = vec3<f32>(0.0);
                        }
                    }
                } else {
                    c = shadowed(c, batch[j], p.xyz, n.xyz);
                }
                let y = c - comp;
                let t = sum + y;
                comp = (t - sum) - y;
                sum = t;
            }
        }
        workgroupBarrier();
    }
    if live {
        sums[2u * i] = vec4<f32>(sum, p.w);
        sums[2u * i + 1u] = vec4<f32>(comp, lum);
    }
}
