//! A probe of the lighting grid hierarchy's bands in f64: lights evaluated a point
//! and the mean relative error against infinite range, for bands more general than the
//! papers'. Level `l >= 1` takes over from level `l - 1` at `T_l = alpha k^(l-1) h 2^(l-1)`
//! over a ramp from `T_l` to `c T_l` (`Hierarchy::band` with `HierarchyParams::growth` k and
//! `ramp` c); `k = 1, c = 2` are the papers' bands.
//! The points are the centres of every n-th triangle of the scene (their normals' cosine in the
//! sum), the estimate `sum w P cos / d^2` (`falloff_infinite`).
//!
//! Usage: `cargo run --release -p manylights-scene --example band_schedule -- [--hall]
//! [--lights N] [--points N] ALPHA,K,C ...` (the atrium with 2^20 uniform lights by default;
//! `--hall`: the CIS 5650 hall, 50,000; 200 points by default).

use glam::DVec3;
use manylights_scene::hierarchy::{FINEST_NODES, Hierarchy, HierarchyParams, TOP_LIGHTS};
use manylights_scene::light::falloff_infinite;
use manylights_scene::procedural::{AtriumParams, atrium, cis5650};
use manylights_scene::{LightGenerator, LightSpec, RadiusRule};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1).peekable();
    let (mut hall, mut count, mut configs, mut wanted) = (false, None, Vec::new(), 200);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--hall" => hall = true,
            "--lights" => count = Some(args.next().ok_or("--lights N")?.parse::<u32>()?),
            "--points" => wanted = args.next().ok_or("--points N")?.parse::<usize>()?.max(1),
            c => {
                let v: Vec<f64> = c.split(',').map(str::parse).collect::<Result<_, _>>()?;
                let [alpha, k, ramp] = v[..] else {
                    return Err(format!("`{c}`: ALPHA,K,C").into());
                };
                if !(alpha > 0.0 && k > 0.0 && ramp > 1.0) {
                    return Err(format!("`{c}`: ALPHA > 0, K > 0, C > 1").into());
                }
                configs.push((alpha, k, ramp));
            }
        }
    }
    let mut scene = if hall {
        cis5650(&Default::default())?
    } else {
        atrium(&AtriumParams::default())?
    };
    let spec = LightSpec {
        generator: LightGenerator::Uniform,
        count: count.unwrap_or(if hall { 50_000 } else { 1 << 20 }),
        seed: if hall { 5650 } else { 1_000_000 },
        radius: RadiusRule::Fixed(1.0),
        intensity: 0.5,
        ..Default::default()
    };
    scene.lights = spec.generate(&scene)?;
    let params = HierarchyParams {
        alpha: 1.0,
        spacing: 0.25,
        finest_nodes: FINEST_NODES,
        growth: manylights_scene::hierarchy::GROWTH,
        ramp: manylights_scene::hierarchy::RAMP,
        top_lights: TOP_LIGHTS,
        sample_from: None,
        spot_bins: manylights_scene::hierarchy::SPOT_BINS,
    };
    // The levels do not hang on alpha, growth or the ramps: one build, its bands set per
    // configuration.
    let mut h = Hierarchy::build(&scene.lights, params);
    let last = h.levels.len() - 1;
    let sizes: Vec<usize> = h.levels.iter().map(Vec::len).collect();
    println!("h {} m, levels {sizes:?}", h.h);
    let mut points = Vec::new();
    for p in &scene.primitives {
        for t in p.indices.chunks(3) {
            let v = |i: u32| p.positions[i as usize].as_dvec3();
            let n = t
                .iter()
                .map(|&i| p.normals[i as usize].as_dvec3())
                .sum::<DVec3>();
            let n = n.normalize();
            points.push(((v(t[0]) + v(t[1]) + v(t[2])) / 3.0 + n * 1e-3, n));
        }
    }
    let stride = (points.len() / wanted).max(1);
    let points: Vec<_> = points.into_iter().step_by(stride).collect();
    let term = |x: DVec3, n: DVec3, at: DVec3, power: DVec3| {
        let v = at - x;
        let d = v.length();
        (n.dot(v) / d).max(0.0) * falloff_infinite(d) * (power.x + power.y + power.z)
    };
    let exact: Vec<f64> = points
        .iter()
        .map(|&(x, n)| {
            h.levels[0]
                .iter()
                .map(|l| term(x, n, l.position, l.power))
                .sum()
        })
        .collect();
    for (alpha, k, c) in configs {
        h.params = HierarchyParams {
            alpha,
            growth: k,
            ramp: c,
            ..params
        };
        if c > 2.0 * k * (1.0 + 1e-12) {
            println!("alpha {alpha} k {k} c {c}: a ramp reaches past the next takeover (C <= 2K)");
            continue;
        }
        let mut per_level = vec![0.0; last + 1];
        let mut error = 0.0;
        for (&(x, n), exact) in points.iter().zip(&exact) {
            let mut estimate = 0.0;
            for (l, lights) in h.levels.iter().enumerate() {
                for light in lights {
                    let w = h.band(l, x.distance(light.position));
                    if w > 0.0 {
                        per_level[l] += 1.0;
                        estimate += w * term(x, n, light.position, light.power);
                    }
                }
            }
            error += (estimate - exact).abs() / exact.max(1e-30);
        }
        let np = points.len() as f64;
        let levels: Vec<i64> = per_level.iter().map(|v| (v / np).round() as i64).collect();
        println!(
            "alpha {alpha} k {k} c {c}: {:.0} lights a point {levels:?}, mean relative error {:.4}",
            per_level.iter().sum::<f64>() / np,
            error / np
        );
    }
    Ok(())
}
