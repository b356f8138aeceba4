// lights.stochastic: stochastic light culling's ranges for one frame (Tokuyoshi and Harada
// 2016; manylights_scene::stochastic states the estimator and is this pass's oracle). Host side:
// manylights_gpu::stochastic. Each thread draws xi for one light of [first, first + count) from
// the seed, the frame and the light's index (or, stratified, from its stratum on one shifted
// lattice), and writes the light's range 1 / sqrt(alpha * xi)
// into its radius and alpha beside it; culling then runs unchanged over these spheres and
// shading uses max(1 / d^2, alpha) inside them (light_attenuation, light.wgsl). With
// interleaving over n x n pixel classes, each class draws its own xi from the light's key, the
// radius is the longest class's range, and the key is kept in the light's `interleave` for
// shading (light_range, light.wgsl).

struct StochasticParams {
    first: u32,
    count: u32,
    // Threads in one row of the dispatch grid (workgroups in x times 256).
    row: u32,
    seed: u32,
    frame: u32,
    // 1: write alpha = 0, so that the light is shaded with the windowed falloff over its drawn
    // range (Russian roulette without the reweighting): a deliberately biased estimate, for
    // the test that the unbiasedness test can fail.
    biased: u32,
    error: f32,
    exposure: f32,
    // StochasticParams::scale: 1 bounds the light's own contribution (the default).
    scale: f32,
    // n of n x n pixel classes; 1: no interleaving.
    interleave: u32,
    // 1: stratified draws, frac(u + stratum phi) over `strata` (StochasticDraw::Stratified);
    // 0: one hash a light.
    stratified: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> stochastic: StochasticParams;
@group(0) @binding(1) var<storage, read_write> drawn: array<Light>;
// Each drawn light's stratum (manylights_scene::stochastic::strata), indexed from `first`.
@group(0) @binding(2) var<storage, read> strata: array<u32>;

// manylights_scene::stochastic::stratified_xi: the lattice frac(u + stratum phi) on XI_BITS
// bits, shifted by one hash of the seed and frame.
fn stratified_xi(stratum: u32) -> f32 {
    let u = pcg(stochastic.frame ^ pcg(stochastic.seed)) >> (32u - XI_BITS);
    let bits = (u + stratum * PHI_BITS) & ((1u << XI_BITS) - 1u);
    return (f32(bits) + 0.5) / f32(1u << XI_BITS);
}

// The hash of manylights_scene::stochastic::xi and ::key.
fn stochastic_hash(index: u32) -> u32 {
    return pcg(index ^ pcg(stochastic.frame ^ pcg(stochastic.seed)));
}

// manylights_scene::stochastic::StochasticParams::alpha.
fn stochastic_alpha(l: Light) -> f32 {
    let scale = stochastic.exposure * l.intensity * max(l.color.x, max(l.color.y, l.color.z)) * stochastic.scale;
    let largest = 1.0 / (D_MIN * D_MIN);
    return select(largest, min(2.0 * stochastic.error / scale, largest), scale > 0.0);
}

@compute @workgroup_size(256)
fn draw(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * stochastic.row;
    if (i >= stochastic.count) {
        return;
    }
    let index = stochastic.first + i;
    let alpha = stochastic_alpha(drawn[index]);
    let h = stochastic_hash(index);
    let n = stochastic.interleave;
    if n <= 1u {
        var xi = stochastic_unit(h);
        if stochastic.stratified != 0u {
            xi = stratified_xi(strata[i]);
        }
        drawn[index].radius = 1.0 / sqrt(alpha * xi);
        drawn[index].interleave = 0u;
    } else {
        // The smallest class xi: the longest class range (StochasticParams::at_frame).
        let key = h >> 8u;
        var xi = 1.0;
        for (var c = 0u; c < n * n; c++) {
            xi = min(xi, stochastic_unit(pcg(key ^ (c << 24u))));
        }
        drawn[index].radius = 1.0 / sqrt(alpha * xi);
        drawn[index].interleave = n << 24u | key;
    }
    drawn[index].alpha = select(alpha, 0.0, stochastic.biased != 0u);
    // Biased (the windowed falloff over the drawn range) or stochastic light culling's.
    let falloff = select(LIGHT_FALLOFF_STOCHASTIC, LIGHT_FALLOFF_WINDOWED, stochastic.biased != 0u);
    drawn[index].kind = (drawn[index].kind & ~LIGHT_FALLOFF_MASK) | falloff;
}
