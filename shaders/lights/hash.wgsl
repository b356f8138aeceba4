// PCG's output hash, as manylights_scene::motion::pcg: the random numbers of the passes that
// change lights each frame (motion.wgsl, stochastic.wgsl).
fn pcg(v: u32) -> u32 {
    let s = v * 747796405u + 2891336453u;
    let w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return (w >> 22u) ^ w;
}
