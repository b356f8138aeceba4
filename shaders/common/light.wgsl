// Lights and the falloff: the WGSL twin of manylights_scene::light (see its module docs for the
// formulas). Constants D_MIN, SPOT_EPS, LIGHT_KIND_* and XI_BITS come from the generated
// prelude.
// Host mirror: manylights_gpu::layout::GpuLight.
struct Light {
    position: vec3<f32>,
    radius: f32,
    color: vec3<f32>,
    intensity: f32,
    // Spot axis (unit); unused for point lights.
    direction: vec3<f32>,
    // Its shape (LIGHT_KIND_POINT or LIGHT_KIND_SPOT, LIGHT_SHAPE_MASK), falloff
    // (LIGHT_FALLOFF_WINDOWED, _STOCHASTIC or _BAND, LIGHT_FALLOFF_MASK) and flags
    // (LIGHT_FLAG_HARD_BAND), or-ed.
    kind: u32,
    cos_inner: f32,
    cos_outer: f32,
    // LIGHT_FALLOFF_STOCHASTIC: stochastic light culling's alpha (manylights_scene::stochastic),
    // the light shaded with max(1 / d^2, alpha) inside its radius, the range drawn for this
    // frame (lights.stochastic). LIGHT_FALLOFF_BAND: a light of the lighting grid hierarchy
    // (manylights_scene::hierarchy::Band), alpha its band's r (light_band). Unread otherwise.
    alpha: f32,
    // LIGHT_FALLOFF_STOCHASTIC: interleaved ranges (manylights_scene::stochastic), 0 none;
    // otherwise n << 24 | key, and a pixel of class c of n x n evaluates the light out to its
    // class's range (light_range), within `radius`, the longest of the classes' ranges.
    // LIGHT_FALLOFF_BAND: the bits of the band's inner distance.
    interleave: u32,
}

// The light's shape: LIGHT_KIND_POINT or LIGHT_KIND_SPOT.
fn light_shape(light: Light) -> u32 {
    return light.kind & LIGHT_SHAPE_MASK;
}

// The pixel being shaded: every entry point that shades lights sets it first, for the classes
// of interleaved stochastic ranges (light_range).
var<private> shading_pixel: vec2<u32>;

// PCG's output hash, as manylights_scene::motion::pcg: the random numbers of the passes that
// change lights each frame (motion.wgsl, stochastic.wgsl) and of the interleaved ranges.
fn pcg(v: u32) -> u32 {
    let s = v * 747796405u + 2891336453u;
    let w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return (w >> 22u) ^ w;
}

// manylights_scene::stochastic::unit: a hash's top XI_BITS bits as a number in (0, 1).
fn stochastic_unit(h: u32) -> f32 {
    return (f32(h >> (32u - XI_BITS)) + 0.5) / f32(1u << XI_BITS);
}

// The range a stochastic light (LIGHT_FALLOFF_STOCHASTIC) is evaluated to at shading_pixel: its radius, or
// with interleaving its pixel class's range 1 / sqrt(alpha * xi) (manylights_scene::stochastic::
// StochasticParams::at_pixel).
fn light_range(light: Light) -> f32 {
    if light.interleave == 0u {
        return light.radius;
    }
    let n = light.interleave >> 24u;
    let c = shading_pixel.x % n + n * (shading_pixel.y % n);
    let xi = stochastic_unit(pcg((light.interleave & 0xffffffu) ^ (c << 24u)));
    return 1.0 / sqrt(light.alpha * xi);
}

// clamp(1 - (d / r)^4, 0, 1)^2: exactly zero for d >= r.
fn light_window(d: f32, r: f32) -> f32 {
    let x = d / r;
    let x2 = x * x;
    let w = clamp(1.0 - x2 * x2, 0.0, 1.0);
    return w * w;
}

// Windowed inverse-square falloff.
fn light_falloff(d: f32, r: f32) -> f32 {
    return light_window(d, r) / max(d * d, D_MIN * D_MIN);
}

// Inverse-square falloff without the window: the infinite-range reference of the accuracy
// metrics (what the radius cut-off itself costs).
fn light_falloff_infinite(d: f32) -> f32 {
    return 1.0 / max(d * d, D_MIN * D_MIN);
}

// Spot cone factor; exactly zero at and outside the outer cone.
fn light_spot(cos_theta: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    let t = clamp((cos_theta - cos_outer) / max(cos_inner - cos_outer, SPOT_EPS), 0.0, 1.0);
    return t * t;
}
