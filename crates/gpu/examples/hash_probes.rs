//! A probe of the hierarchy build's hash tables on the CPU: for the plan of a procedural scene's
//! uniform lights (`HierarchyPlan::for_scene`, the last fraction of them moving as
//! `lights.moving` moves them), each level's keys as the build splats them (the 8 nodes around
//! each light of the level below, `manylights_scene::hierarchy::Hierarchy::build_fixed` at home)
//! inserted by linear probing from the build's hash (`slot_of` in
//! `shaders/lights/hierarchy.wgsl` before its triangular probes), from a mixed one (murmur3's finaliser) and from Fibonacci
//! hashing's high bits (the slot `(key 2654435769 mod 2^32) count / 2^32`): the mean and the
//! longest probe run a splat walks. None is best everywhere: at a million lights with 1% moving
//! the build's hash walks 29.8 slots a splat into level 4 (the high bits 0.24), in the hall at
//! 50,000 the high bits walk 1.86 into level 1 (the build's 0.59). The build's hash with
//! `slot_of`'s triangular probes: 4.8 there, and within a few tenths of linear probing or below
//! it in every other table.
//!
//! Usage: `cargo run --release -p manylights-gpu --example hash_probes -- [--scene NAME]
//! [--lights N] [--moving F] [--alpha A] [--spacing H]` (the atrium with 1,048,576 lights,
//! 1% moving, alpha 0.75, growth 1.15, ramps 1.1, by default).

use glam::DVec3;
use manylights_gpu::hierarchy::{HierarchyPlan, Moving};
use manylights_scene::hierarchy::Hierarchy;
use manylights_scene::procedural::ProceduralScene;
use manylights_scene::{LightGenerator, LightSpec, Motion, RadiusRule};

/// The build's hash of a key (`slot_of`).
fn build_hash(key: u32) -> u32 {
    key.wrapping_mul(2654435769) ^ (key >> 15)
}

/// murmur3's 32-bit finaliser.
fn mixed_hash(key: u32) -> u32 {
    let mut h = key;
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^ (h >> 16)
}

/// Fibonacci hashing, the slot from the product's high bits (`(h count) >> 32`).
fn high_bits(key: u32, count: u32) -> u32 {
    ((u64::from(key.wrapping_mul(2654435769)) * u64::from(count)) >> 32) as u32
}

/// `TRIANGULAR_PROBES` in `shaders/lights/hierarchy.wgsl`.
const TRIANGULAR: u32 = 64;

/// Mean and longest probe run of `splats` (keys, repeated as splatted) into `count` slots,
/// each key's first slot `start(key, count)`, stepping 1, 2, 3, ... slots on for the first
/// `triangular` probes (`slot_of`), then one slot at a time.
fn probes(
    splats: &[u32],
    count: u32,
    start: &dyn Fn(u32, u32) -> u32,
    triangular: u32,
) -> (f64, u32) {
    let mut table = vec![0u32; count as usize];
    let (mut total, mut longest) = (0u64, 0u32);
    for &key in splats {
        let mut at = start(key, count);
        let mut run = 0;
        while table[at as usize] != 0 && table[at as usize] != key {
            run += 1;
            at = (at + if run < triangular { run } else { 1 }) % count;
        }
        table[at as usize] = key;
        total += u64::from(run);
        longest = longest.max(run);
    }
    (total as f64 / splats.len().max(1) as f64, longest)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let (mut name, mut count, mut moving, mut alpha, mut spacing) =
        ("atrium".to_string(), 1_048_576u32, 0.01f32, 0.75, 0.25);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--scene" => name = value()?,
            "--lights" => count = value()?.parse()?,
            "--moving" => moving = value()?.parse()?,
            "--alpha" => alpha = value()?.parse()?,
            "--spacing" => spacing = value()?.parse()?,
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    let mut scene = ProceduralScene::from_name(&name)?.build()?;
    let radius = RadiusRule::Hierarchy {
        alpha,
        spacing,
        finest_nodes: manylights_scene::hierarchy::FINEST_NODES as f32,
        growth: 1.15,
        ramp: 1.1,
        sample_from: None,
        spot_bins: manylights_scene::hierarchy::SPOT_BINS,
    };
    let motion = Motion::Noise(2.0);
    let spec = LightSpec {
        generator: LightGenerator::Uniform,
        count,
        seed: 1_000_000,
        radius,
        intensity: 0.5,
        motion,
        moving,
        ..Default::default()
    };
    scene.lights = spec.generate(&scene)?;
    let params = radius.hierarchy_params().expect("a hierarchy rule");
    let first = (count - spec.moving_count()) as usize;
    let m = Moving {
        motion: &motion,
        first,
        frames: 5,
        anchors: &[],
    };
    let (plan, _) = HierarchyPlan::for_scene(&scene, params, (moving > 0.0).then_some(m))?;
    let home = Hierarchy::build_fixed(&scene.lights, params, plan.h, plan.levels);
    println!(
        "{name}, {count} lights, {moving} moving: h {}, {} levels",
        plan.h, plan.levels
    );
    for l in 1..plan.levels {
        let g = plan.grids[l - 1];
        let s = f64::from(g.spacing);
        let mut splats = Vec::new();
        for light in &home.levels[l - 1] {
            let u: DVec3 = light.position / s;
            let base = u.floor();
            for c in 0..8u32 {
                let bit = DVec3::new(f64::from(c & 1), f64::from((c >> 1) & 1), f64::from(c >> 2));
                let n = (base + bit).as_ivec3() - glam::IVec3::from(g.first);
                let d = g.dims;
                let idx = (n.z as u32 * d[1] + n.y as u32) * d[0] + n.x as u32;
                splats.push(idx + 1 + light.bin * d[0] * d[1] * d[2]);
            }
        }
        let count = plan.slots[l - 1];
        let starts: [(&str, &dyn Fn(u32, u32) -> u32); 3] = [
            ("build's", &|k, n| build_hash(k) % n),
            ("murmur3", &|k, n| mixed_hash(k) % n),
            ("high bits", &high_bits),
        ];
        let mut runs: Vec<String> = starts
            .iter()
            .map(|(what, start)| {
                let (mean, longest) = probes(&splats, count, start, 0);
                format!("{what} {mean:.2}/{longest}")
            })
            .collect();
        let (mean, longest) = probes(&splats, count, &|k, n| build_hash(k) % n, TRIANGULAR);
        runs.push(format!("the build's, triangular {mean:.2}/{longest}"));

        println!(
            "level {l}: {} splats into {count} slots (mean/longest run): {}",
            splats.len(),
            runs.join(", ")
        );
    }
    Ok(())
}
