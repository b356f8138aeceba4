// lights.stochastic: stochastic light culling's ranges for one frame (Tokuyoshi and Harada
// 2016; manylights_scene::stochastic states the estimator and is this pass's oracle). Host side:
// manylights_gpu::stochastic. Each thread draws xi for one light of [first, first + count) from
// the seed, the frame and the light's index, and writes the light's range 1 / sqrt(alpha * xi)
// into its radius and alpha beside it; culling then runs unchanged over these spheres and
// shading uses max(1 / d^2, alpha) inside them (light_attenuation, light.wgsl).
// XI_BITS comes from the Rust constant.

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
    rho_max: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> stochastic: StochasticParams;
@group(0) @binding(1) var<storage, read_write> drawn: array<Light>;

// manylights_scene::stochastic::xi: in (0, 1), never 0.
fn stochastic_xi(index: u32) -> f32 {
    let h = pcg(index ^ pcg(stochastic.frame ^ pcg(stochastic.seed)));
    return (f32(h >> (32u - XI_BITS)) + 0.5) / f32(1u << XI_BITS);
}

// manylights_scene::stochastic::StochasticParams::alpha.
fn stochastic_alpha(l: Light) -> f32 {
    let scale = stochastic.exposure * l.intensity * max(l.color.x, max(l.color.y, l.color.z)) * stochastic.rho_max;
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
    drawn[index].radius = 1.0 / sqrt(alpha * stochastic_xi(index));
    drawn[index].alpha = select(alpha, 0.0, stochastic.biased != 0u);
}
