// The material models: the WGSL twin of manylights_scene::brdf (f64), each model's reflectance
// times the cosine (the wrapped diffuse: its wrapped cosine) for unit normal n (facing the
// viewer), light direction l and view direction v. Finite at every direction and parameter:
// roughness is at least MIN_ROUGHNESS, the visibility's denominator at least n.l alpha > 0, and
// the half vector of l = -v is zero.
//
// MATERIAL_MODELS: the models a pipeline shades, a bit each (1 << MODEL_*). Forward draws each
// model with a pipeline of its own bit, so its fragments run that model's code alone; deferred
// and the references branch on the pixel's model over the scene's models (or every model).
override MATERIAL_MODELS: u32 = 0xffffffffu;

fn shades_model(model: u32) -> bool {
    return (MATERIAL_MODELS & (1u << model)) != 0u;
}

// The model a pixel runs: its material's, or where the pipeline shades one model, that one
// (a constant, so the other models' code is gone).
fn material_model(m: Material) -> u32 {
    if countOneBits(MATERIAL_MODELS) == 1u {
        return firstTrailingBit(MATERIAL_MODELS);
    }
    return m.model;
}

fn ggx_alpha(r: f32) -> f32 {
    let x = max(r, MIN_ROUGHNESS);
    return x * x;
}

fn d_ggx(nh: f32, a: f32) -> f32 {
    let a2 = a * a;
    let t = nh * nh * (a2 - 1.0) + 1.0;
    return a2 / (PI * t * t);
}

// Smith's height-correlated visibility G / (4 n.l n.v).
fn v_smith(nl: f32, nv: f32, a: f32) -> f32 {
    let a2 = a * a;
    let gv = nl * sqrt(nv * nv * (1.0 - a2) + a2);
    let gl = nv * sqrt(nl * nl * (1.0 - a2) + a2);
    return 0.5 / (gv + gl);
}

fn schlick_weight(vh: f32) -> f32 {
    let x = 1.0 - vh;
    let x2 = x * x;
    return x2 * x2 * x;
}

fn d_charlie(nh: f32, a: f32) -> f32 {
    let inv = 1.0 / a;
    let sin2 = max(1.0 - nh * nh, 0.0);
    return (2.0 + inv) * pow(sin2, 0.5 * inv) / (2.0 * PI);
}

fn v_neubelt(nl: f32, nv: f32) -> f32 {
    return 0.25 / (nl + nv - nl * nv);
}

// glTF's metallic-roughness BRDF (no cosine) at n.l > 0.
fn brdf_ggx(base: vec3<f32>, metallic: f32, roughness: f32, nl: f32, nv: f32, nh: f32, vh: f32) -> vec3<f32> {
    let a = ggx_alpha(roughness);
    let f0 = mix(vec3<f32>(F0_DIELECTRIC), base, metallic);
    let f = f0 + (vec3<f32>(1.0) - f0) * schlick_weight(vh);
    let diffuse = (vec3<f32>(1.0) - f) * base * ((1.0 - metallic) / PI);
    return diffuse + f * (d_ggx(nh, a) * v_smith(nl, nv, a));
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

// Reflectance times cosine of material m for directions n, l, v.
fn brdf_cos(m: Material, n: vec3<f32>, l: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let model = material_model(m);
    let nl = dot(n, l);
    if shades_model(MODEL_WRAP) && model == MODEL_WRAP {
        let w = m.params.x;
        return m.base_color * (clamp((nl + w) / ((1.0 + w) * (1.0 + w)), 0.0, 1.0) / PI);
    }
    if nl <= 0.0 {
        return vec3<f32>(0.0);
    }
    let nv = max(dot(n, v), 0.0);
    // n.h and v.h with h = (l + v) / |l + v|, h never formed: one reciprocal square root and
    // no normalised vector (about 1% off the lighting pass on an H100). l = -v (a light exactly
    // behind the viewer's line) gives h = 0, where normalize would give NaN. Clamped into [0, 1]:
    // rounding can take a dot product of unit vectors past 1, and Schlick's (1 - v.h)^5
    // negative with it.
    let lv = l + v;
    let lv2 = dot(lv, lv);
    let inv_h = select(0.0, inverseSqrt(lv2), lv2 > 0.0);
    let nh = clamp(dot(n, lv) * inv_h, 0.0, 1.0);
    let vh = clamp(dot(v, lv) * inv_h, 0.0, 1.0);
    var f = vec3<f32>(0.0);
    if shades_model(MODEL_GGX) && model == MODEL_GGX {
        f = brdf_ggx(m.base_color, m.params.x, m.params.y, nl, nv, nh, vh);
    } else if shades_model(MODEL_SHEEN) && model == MODEL_SHEEN {
        let a = ggx_alpha(m.params.w);
        f = m.base_color / PI + m.params.xyz * (d_charlie(nh, a) * v_neubelt(nl, nv));
    } else if shades_model(MODEL_CLEAR_COAT) && model == MODEL_CLEAR_COAT {
        let under = brdf_ggx(m.base_color, m.params.x, m.params.y, nl, nv, nh, vh);
        let ac = ggx_alpha(m.params.w);
        let fc = m.params.z * (F0_DIELECTRIC + (1.0 - F0_DIELECTRIC) * schlick_weight(vh));
        f = under * (1.0 - fc) + vec3<f32>(fc * d_ggx(nh, ac) * v_smith(nl, nv, ac));
    } else if shades_model(MODEL_BLINN_PHONG) {
        let spec_norm = (SHININESS + 8.0) / (8.0 * PI);
        f = m.base_color / PI + vec3<f32>(m.params.x * spec_norm * shininess_pow(nh));
    }
    return f * nl;
}
