// The shading model shared by every backend: the WGSL twin of manylights_scene::light::shade.
// Lambert plus a normalised Blinn-Phong lobe of fixed exponent SHININESS (generated prelude).
// Materials: struct Material in scene.wgsl.

// The shading normal: the geometric normal turned towards the viewer (surfaces are two-sided).
fn facing_normal(n: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    return select(n, -n, dot(n, v) < 0.0);
}

// Radiance from every light in the scene (the brute-force sum of the reference and naive
// forward).
fn shade_all(p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    var c = vec3<f32>(0.0);
    for (var i = 0u; i < frame.light_count; i++) {
        c += shade_light(lights[i], p, n, v, m);
    }
    return c;
}

// Radiance towards `v` from surface point `p` (unit normal `n`) lit by one light.
fn shade_light(light: Light, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    let to_light = light.position - p;
    return shade_light_at(light, to_light, length(to_light), n, v, m);
}

// x^SHININESS: five squarings where SHININESS is 32 (a few ulp from exact, where pow's
// exp2(log2(x) * 32) is further, and no special-function unit's two operations a light).
fn shininess_pow(x: f32) -> f32 {
    if SHININESS == 32.0 {
        let x2 = x * x;
        let x4 = x2 * x2;
        let x8 = x4 * x4;
        let x16 = x8 * x8;
        return x16 * x16;
    }
    return pow(x, SHININESS);
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

// One light at `p` with the infinite-range falloff whatever the frame's flags (the compute
// reference, reference_infinite.wgsl).
fn light_infinite(light: Light, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    let to_light = light.position - p;
    let d = length(to_light);
    return shade_light_atten(light, to_light, d, light_falloff_infinite(d), n, v, m);
}

// The BRDF, spot cone and cosine of one light whose falloff at distance `d` is `atten`.
fn shade_light_atten(light: Light, to_light: vec3<f32>, d: f32, atten: f32, n: vec3<f32>, v: vec3<f32>, m: Material) -> vec3<f32> {
    if atten == 0.0 {
        return vec3<f32>(0.0);
    }
    let l = select(n, to_light / d, d > 0.0);
    var cone = 1.0;
    if light.kind == LIGHT_KIND_SPOT {
        cone = light_spot(dot(-l, light.direction), light.cos_inner, light.cos_outer);
    }
    let ndotl = max(dot(n, l), 0.0);
    if cone == 0.0 || ndotl == 0.0 {
        return vec3<f32>(0.0);
    }
    // normalize(0) is NaN in WGSL; l = -v (light exactly behind the viewer's line) gives h = 0.
    let lv = l + v;
    let h = select(vec3<f32>(0.0), normalize(lv), dot(lv, lv) > 0.0);
    let spec_norm = (SHININESS + 8.0) / (8.0 * PI);
    let brdf = m.base_color / PI + vec3<f32>(m.specular * spec_norm * shininess_pow(max(dot(n, h), 0.0)));
    return light.color * (light.intensity * atten * cone * ndotl) * brdf;
}
