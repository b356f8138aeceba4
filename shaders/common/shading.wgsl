// The shading model shared by every backend: the WGSL twin of manylights_scene::light::shade.
// Each light's irradiance times the material model's reflectance and cosine (brdf.wgsl);
// materials: struct Material in scene.wgsl. The emission is added once a pixel by the loops
// over lights (emitted).

// The shading normal: the geometric normal turned towards the viewer (surfaces are two-sided).
fn facing_normal(n: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    return select(n, -n, dot(n, v) < 0.0);
}

// Radiance from every light in the scene (the brute-force sum of the reference and naive
// forward).
fn shade_all(p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    var c = emitted(m);
    for (var i = 0u; i < frame.light_count; i++) {
        c += shade_light(lights[i], p, n, v, m);
    }
    lights_walked += frame.light_count;
    count_lights_walked(c);
    return shadow_estimate(c);
}

// The material's emitted radiance: where each loop over lights starts its sum.
fn emitted(m: Material) -> vec3<f32> {
    return m.emissive;
}

// The falloff a light is shaded with, by its kind's falloff bits: a hierarchy light's band
// times 1 / d^2 (LIGHT_FALLOFF_BAND), the windowed one or, for stochastic light culling
// (LIGHT_FALLOFF_STOCHASTIC), max(1 / d^2, alpha) inside the range drawn for the frame
// (light_range): 1 / d^2 divided by the probability min(d^-2 / alpha, 1) that the light
// reaches d, an unbiased estimate of the infinite-range falloff (manylights_scene::stochastic).
fn light_attenuation(light: Light, d: f32) -> f32 {
    let falloff = light.kind & LIGHT_FALLOFF_MASK;
    if falloff == LIGHT_FALLOFF_BAND {
        return light_band(light, d) * light_falloff_infinite(d);
    }
    if falloff == LIGHT_FALLOFF_STOCHASTIC {
        return select(0.0, max(light_falloff_infinite(d), light.alpha), d < light_range(light));
    }
    return light_falloff(d, light.radius);
}

// A hierarchy light's band weight at distance d (manylights_scene::hierarchy::Band::weight):
// rising from 0 at `inner` to 1 at frame.band_ramp times it (1 throughout where inner is 0),
// falling from 1 at r to 0 at band_ramp times r (1 throughout where r is infinite), each ramp's
// fraction times frame.band_slope, 1 / (band_ramp - 1) (1 for the papers' ramps of 2); a
// sampled band (LIGHT_FLAG_HARD_BAND) is 1 between inner and r and 0 elsewhere. r is the
// light's alpha, inner the bits of its interleave. Here with the frame, not in light.wgsl, as
// the frame carries the ramp.
fn light_band(light: Light, d: f32) -> f32 {
    let r = light.alpha;
    let inner = bitcast<f32>(light.interleave);
    if (light.kind & LIGHT_FLAG_HARD_BAND) != 0u {
        return select(0.0, 1.0, d > inner && d < r);
    }
    var rising = 1.0;
    if inner > 0.0 {
        if d <= inner {
            return 0.0;
        }
        rising = min((d - inner) / inner * frame.band_slope, 1.0);
    }
    return min(rising, clamp((frame.band_ramp - d / r) * frame.band_slope, 0.0, 1.0));
}

// Radiance towards `v` from surface point `p` (unit normal `n`) lit by one light (shadowed
// where the pipeline is built with SHADOWS).
fn shade_light(light: Light, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    let to_light = light.position - p;
    return shadowed(shade_light_at(light, to_light, length(to_light), n, v, m), light, p, n);
}

// SHADOWS: every light that adds radiance at a point is tested with a shadow ray (`shadows:
// Exact`): from the point lifted off its surface along the shading normal (SHADOW_OFFSET times
// its largest coordinate's magnitude, at least 1: manylights_scene::ray::shadow_origin) to the
// light, through the BVH of the opaque triangles (bvh.wgsl); a blocked light adds nothing.
// Lights that add nothing (out of range, outside a cone, behind the surface) cast no ray.
// Transparent surfaces cast no shadow (the BVH holds only opaque triangles) and receive shadows
// as opaque ones do. manylights_shade::Renderer::with_shadows builds the pipelines with it.
override SHADOWS: bool = false;

// Whether the segment from surface point `p` (shading normal `n`) to `light` is blocked.
fn shadow_blocked(light: Light, p: vec3<f32>, n: vec3<f32>) -> bool {
    let a = abs(p);
    let origin = p + n * (SHADOW_OFFSET * max(max(a.x, a.y), max(a.z, 1.0)));
    return bvh_blocked(origin, light.position);
}

// Group 0, binding 5: RAY_COUNT_SLOTS counters of the shadow rays a frame with
// FRAME_FLAG_COUNT_RAYS casts (manylights_gpu::GpuScene::count_rays), a ray adding one to the
// slot its surface point hashes to. Frames that are timed leave the flag off.
@group(0) @binding(5) var<storage, read_write> ray_counts: array<atomic<u32>>;

fn count_ray(p: vec3<f32>) {
    if (frame.flags & FRAME_FLAG_COUNT_RAYS) != 0u {
        let h = (bitcast<u32>(p.x) * 0x9e3779b1u) ^ (bitcast<u32>(p.y) * 0x85ebca6bu) ^ bitcast<u32>(p.z);
        atomicAdd(&ray_counts[(h ^ (h >> 15u)) % RAY_COUNT_SLOTS], 1u);
    }
}

// The lights this invocation's pixel (fragment, sample group) has walked: each light whose
// distance it computes against the light's range, in every loop over a list, a z-bin cell or
// every light (one add a batch or a light; lists and masks narrowed before the pixel's loop,
// such as shade_parts_list's box test, count only what passes). lights_checked adds it to
// group 0's counters in a frame with FRAME_FLAG_COUNT_LIGHTS
// (manylights_gpu::GpuScene::count_lights_walked) and starts it again from zero, for an
// invocation that shades several sample groups.
var<private> lights_walked: u32 = 0u;

fn count_lights_walked(c: vec3<f32>) {
    if (frame.flags & FRAME_FLAG_COUNT_LIGHTS) != 0u && lights_walked != 0u {
        let h = (bitcast<u32>(c.x) * 0x9e3779b1u) ^ (bitcast<u32>(c.y) * 0x85ebca6bu) ^ (lights_walked * 0xc2b2ae35u);
        atomicAdd(&ray_counts[(h ^ (h >> 15u)) % RAY_COUNT_SLOTS], lights_walked);
    }
    lights_walked = 0u;
}

// `c`, the radiance one light adds at `p`, or zero where SHADOWS and its shadow ray is blocked.
// With SHADOW_RAYS the light is offered to the pixel's draws instead and `c` returned whole: the
// loop's sum is the unshadowed one until shadow_estimate scales it.
fn shadowed(c: vec3<f32>, light: Light, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    if SHADOWS && any(c != vec3<f32>(0.0)) {
        if SHADOW_RAYS > 0u {
            shadow_offer(c, light.position, p, n);
            return c;
        }
        count_ray(p);
        if shadow_blocked(light, p, n) {
            return vec3<f32>(0.0);
        }
    }
    return c;
}

// SHADOW_RAYS = K > 0 (with SHADOWS): stochastic shadows (`shadows: Stochastic`), K rays a
// pixel. Every light the loop evaluates is offered (shadow_offer) with its unshadowed radiance
// c_i; K weighted reservoirs keep one light each in proportion to luminance(c_i) (one uniform
// number a light, shifted by k / K for reservoir k, so that each reservoir's draw has the right
// marginal and the K together are stratified); shadow_estimate traces the K rays and returns
// the ratio estimator (Heitz et al. 2018): the analytic unshadowed sum U times, per channel,
// sum_k s_k V_k / sum_k s_k, where s_k = c_k / luminance(c_k) and V_k is 1 where ray k is
// clear. Biased for finite K (a ratio of estimates), consistent as K grows; exact where every
// drawn light is clear or every one blocked, and, where the lights' colours are alike, U times
// the fraction of clear rays, whose expectation is the shadowed sum (manylights_scene::
// shadow_estimate, the CPU twin). The numbers hash the pixel, the frame's shadow_frame and the
// loops run so far in the invocation (MSAA shades several sample groups a pixel).
override SHADOW_RAYS: u32 = 0u;
// The most rays a pixel (manylights_shade::Shadows::MAX_RAYS).
const SHADOW_RAYS_MAX: u32 = 16u;

var<private> shadow_targets: array<vec3<f32>, SHADOW_RAYS_MAX>;
var<private> shadow_shares: array<vec3<f32>, SHADOW_RAYS_MAX>;
// The luminance and the radiance offered so far, the random state, the surface point and normal.
var<private> shadow_total: f32;
var<private> shadow_lit: vec3<f32>;
var<private> shadow_rng: u32;
var<private> shadow_p: vec3<f32>;
var<private> shadow_n: vec3<f32>;
// The loops this invocation has estimated (a term of each loop's seed).
var<private> shadow_loops: u32;

fn shading_luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// Offers light radiance `c` from `towards` at point `p` (normal `n`) to the K reservoirs.
fn shadow_offer(c: vec3<f32>, towards: vec3<f32>, p: vec3<f32>, n: vec3<f32>) {
    let w = shading_luminance(c);
    if !(w > 0.0) {
        return;
    }
    if shadow_total == 0.0 {
        shadow_rng = pcg(shading_pixel.x ^ pcg(shading_pixel.y ^ pcg(frame.shadow_frame ^ pcg(shadow_loops))));
        shadow_p = p;
        shadow_n = n;
    }
    shadow_total += w;
    shadow_lit += c;
    shadow_rng = pcg(shadow_rng);
    let u = f32(shadow_rng >> 8u) * (1.0 / 16777216.0);
    let keep = w / shadow_total;
    let share = c / w;
    for (var k = 0u; k < SHADOW_RAYS; k++) {
        if fract(u + f32(k) / f32(SHADOW_RAYS)) < keep {
            shadow_targets[k] = towards;
            shadow_shares[k] = share;
        }
    }
}

// The loop's sum `c` with its offered lights' part scaled by the K rays' ratio (see
// SHADOW_RAYS), and the draws cleared for the next loop; `c` itself without SHADOW_RAYS or where
// nothing was offered.
fn shadow_estimate(c: vec3<f32>) -> vec3<f32> {
    if !SHADOWS || SHADOW_RAYS == 0u || shadow_total == 0.0 {
        return c;
    }
    var drawn = vec3<f32>(0.0);
    var clear = vec3<f32>(0.0);
    var seen = 0u;
    let a = abs(shadow_p);
    let origin = shadow_p + shadow_n * (SHADOW_OFFSET * max(max(a.x, a.y), max(a.z, 1.0)));
    for (var k = 0u; k < SHADOW_RAYS; k++) {
        count_ray(shadow_p);
        drawn += shadow_shares[k];
        if !bvh_blocked(origin, shadow_targets[k]) {
            clear += shadow_shares[k];
            seen++;
        }
    }
    let ratio = select(vec3<f32>(f32(seen) / f32(SHADOW_RAYS)), clear / drawn, drawn > vec3<f32>(0.0));
    let out = c - shadow_lit * (vec3<f32>(1.0) - ratio);
    shadow_total = 0.0;
    shadow_lit = vec3<f32>(0.0);
    shadow_loops++;
    return out;
}

// shade_light for a caller that already has `to_light = light.position - p` and
// `d = length(to_light)` (the per-pixel reject of list_shading.wgsl computes them first): the
// same arithmetic, so a light the reject keeps adds exactly what shade_light adds.
fn shade_light_at(light: Light, to_light: vec3<f32>, d: f32, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    var atten = light_attenuation(light, d);
    if (frame.flags & FRAME_FLAG_INFINITE_RANGE) != 0u {
        atten = light_falloff_infinite(d);
    }
    return shade_light_atten(light, to_light, d, atten, n, v, m);
}

// POINT_LIGHTS: the pipeline is built for frames whose lights are all point lights shaded with
// the windowed falloff (no spot cone, no stochastic alpha; manylights_shade::Renderer builds it
// where the scene's manylights_gpu::LightPath says so). Its loops over lists then shade with shade_point_light
// alone: with the general model's code beside it in the same loop, the lighting pass kept most
// of that code's cost (docs/bench/HISTORY.md, "The lighting pass against its floor").
override POINT_LIGHTS: bool = false;

// STOCHASTIC_POINTS (with POINT_LIGHTS): the frame's lights are all point lights with
// stochastic ranges drawn for the frame and no interleaving (FRAME_FLAG_STOCHASTIC_POINTS, from a
// scene uploaded for them, LightPath::StochasticPoints): shade_point_light shades max(1 / d^2, alpha) inside the
// drawn range, light_attenuation's stochastic arm, on the same short path.
override STOCHASTIC_POINTS: bool = false;

// BAND_POINTS (with POINT_LIGHTS): the frame's lights are all the lighting grid hierarchy's point
// lights (FRAME_FLAG_BAND_POINTS, LightPath::BandPoints): shade_point_light shades
// each with its band times 1 / d^2 (light_band: alpha its r, interleave its inner,
// LIGHT_FLAG_HARD_BAND a sampled band), light_attenuation's hierarchy arm, on the same short
// path.
override BAND_POINTS: bool = false;

// Whether the frame says its lights are of the kind this pipeline is built for (the frame's flags
// of the scene's LightPath, and no infinite-range falloff).
fn point_lights_only() -> bool {
    let want = FRAME_FLAG_POINT_LIGHTS | select(0u, FRAME_FLAG_STOCHASTIC_POINTS, STOCHASTIC_POINTS)
        | select(0u, FRAME_FLAG_BAND_POINTS, BAND_POINTS);
    let kinds = FRAME_FLAG_POINT_LIGHTS | FRAME_FLAG_STOCHASTIC_POINTS | FRAME_FLAG_BAND_POINTS;
    return (frame.flags & (kinds | FRAME_FLAG_INFINITE_RANGE)) == want;
}

// A listed light the per-pixel reject kept (d < radius, or any d with the infinite-range
// falloff) at surface point `p` (`to_light` = its position - p): shade_point_light in a
// POINT_LIGHTS pipeline, else shade_light_at; shadowed with SHADOWS.
fn shade_listed(light: Light, p: vec3<f32>, to_light: vec3<f32>, d: f32, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    if POINT_LIGHTS {
        return shadowed(shade_point_light(light, to_light, d, n, v, m), light, p, n);
    }
    return shadowed(shade_light_at(light, to_light, d, n, v, m), light, p, n);
}

// A loop's sum `c` (with SHADOW_RAYS, shadow_estimate's), or NaN where a POINT_LIGHTS
// pipeline shades a frame whose lights are not all windowed point lights: a count of
// non-finite pixels in the results, never a plausible image. (Renderer::render refuses that combination first.) The NaN's bits are or-ed with a
// runtime zero, so that it is not a constant expression for the shader compiler to refuse.
fn lights_checked(c: vec3<f32>) -> vec3<f32> {
    count_lights_walked(c);
    if POINT_LIGHTS && !point_lights_only() {
        return vec3<f32>(bitcast<f32>(0x7fc00000u | (frame.flags & 0u)));
    }
    return shadow_estimate(c);
}

// shade_light_at for a point light with the windowed falloff and no stochastic alpha: the same
// sum without the general model's branches and loads (its cone is 1, and a zero falloff adds
// zero, as brdf_cos is finite).
// With STOCHASTIC_POINTS the falloff is max(1 / d^2, alpha): the loops call it only inside the
// drawn range (d < radius), where light_attenuation gives the same. With BAND_POINTS it is the
// band's weight times 1 / d^2, light_attenuation's own arithmetic.
fn shade_point_light(light: Light, to_light: vec3<f32>, d: f32, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    let l = select(n, to_light / d, d > 0.0);
    var atten = select(light_falloff(d, light.radius), max(light_falloff_infinite(d), light.alpha), STOCHASTIC_POINTS);
    if BAND_POINTS {
        atten = light_band(light, d) * light_falloff_infinite(d);
    }
    return light.color * (light.intensity * atten) * brdf_cos(m, n, l, v);
}

// One light at `p` with the infinite-range falloff whatever the frame's flags (the compute
// reference, reference_infinite.wgsl).
fn light_infinite(light: Light, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    let to_light = light.position - p;
    let d = length(to_light);
    return shade_light_atten(light, to_light, d, light_falloff_infinite(d), n, v, m);
}

// The spot cone and the BRDF times cosine of one light whose falloff at distance `d` is `atten`.
fn shade_light_atten(light: Light, to_light: vec3<f32>, d: f32, atten: f32, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    if atten == 0.0 {
        return vec3<f32>(0.0);
    }
    let l = select(n, to_light / d, d > 0.0);
    var cone = 1.0;
    if light_shape(light) == LIGHT_KIND_SPOT {
        cone = light_spot(dot(-l, light.direction), light.cos_inner, light.cos_outer);
    }
    if cone == 0.0 {
        return vec3<f32>(0.0);
    }
    return light.color * (light.intensity * atten * cone) * brdf_cos(m, n, l, v);
}
