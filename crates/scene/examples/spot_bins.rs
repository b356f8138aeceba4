//! A probe of the hierarchy's spots in f64: for a scene lit by spots and point lights, the
//! lights evaluated a point (those whose band holds it) and the mean relative error against
//! infinite range, for several numbers of spot bins (`HierarchyParams::spot_bins`), beside the
//! same lights as point lights alone. The points are the centres of every n-th triangle (their
//! normals' cosine in the sum), the estimate `sum w P cone cos / d^2`.
//!
//! Usage: `cargo run --release -p manylights-scene --example spot_bins -- [--scene NAME]
//! [--lights N] [--spots F] [--alpha A] BINS ...` (the city with 20,000 uniform lights, 30%
//! spots of 35 degrees, alpha 1, by default; NAME a procedural scene).

use glam::DVec3;
use manylights_scene::hierarchy::{Hierarchy, HierarchyParams, TOP_LIGHTS};
use manylights_scene::light::falloff_infinite;
use manylights_scene::procedural::ProceduralScene;
use manylights_scene::{Light, LightGenerator, LightKind, LightSpec, RadiusRule};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let (mut name, mut count, mut spots, mut alpha, mut bins) =
        ("city".to_string(), 20_000, 0.3, 1.0, Vec::new());
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--scene" => name = value()?,
            "--lights" => count = value()?.parse()?,
            "--spots" => spots = value()?.parse()?,
            "--alpha" => alpha = value()?.parse()?,
            b => bins.push(b.parse::<u32>()?),
        }
    }
    let mut scene = ProceduralScene::from_name(&name)?.build()?;
    let spec = LightSpec {
        generator: LightGenerator::Uniform,
        count,
        seed: 68,
        radius: RadiusRule::Fixed(1.0),
        intensity: 0.5,
        spot_fraction: spots,
        spot_outer_deg: 35.0,
        ..Default::default()
    };
    scene.lights = spec.generate(&scene)?;
    let as_points: Vec<Light> = scene
        .lights
        .iter()
        .map(|l| Light {
            kind: LightKind::Point,
            ..*l
        })
        .collect();
    let mut points = Vec::new();
    for p in &scene.primitives {
        for t in p.indices.chunks(3) {
            let v = |i: u32| p.positions[i as usize].as_dvec3();
            let n = t
                .iter()
                .map(|&i| p.normals[i as usize].as_dvec3())
                .sum::<DVec3>()
                .normalize();
            points.push(((v(t[0]) + v(t[1]) + v(t[2])) / 3.0 + n * 1e-3, n));
        }
    }
    let stride = (points.len() / 300).max(1);
    let points: Vec<_> = points.into_iter().step_by(stride).collect();
    // One light's term at x (normal n): cosine, falloff, cone, the power's channels.
    let term = |x: DVec3, n: DVec3, l: &Light| {
        let v = l.position.as_dvec3() - x;
        let d = v.length();
        let power = (l.color * l.intensity).as_dvec3().element_sum();
        (n.dot(v) / d).max(0.0) * falloff_infinite(d) * l.cone_toward(v / d) * power
    };
    let probe = |what: &str, lights: &[Light], spot_bins: u32| {
        let params = HierarchyParams {
            alpha,
            spacing: 0.1,
            finest_nodes: manylights_scene::hierarchy::FINEST_NODES,
            growth: 1.15,
            ramp: 1.1,
            top_lights: TOP_LIGHTS,
            sample_from: None,
            spot_bins,
        };
        let h = Hierarchy::build(lights, params);
        let (flat, bands) = h.flatten(1e6);
        let (mut evaluated, mut error) = (0usize, 0.0);
        for &(x, n) in &points {
            let exact: f64 = lights.iter().map(|l| term(x, n, l)).sum();
            let mut estimate = 0.0;
            for (l, b) in flat.iter().zip(&bands) {
                let w = b.weight(x.distance(l.position.as_dvec3()));
                if w > 0.0 {
                    evaluated += 1;
                    estimate += w * term(x, n, l);
                }
            }
            error += (estimate - exact).abs() / exact.max(1e-30);
        }
        let np = points.len() as f64;
        let sizes: Vec<usize> = h.levels.iter().map(Vec::len).collect();
        println!(
            "{what}: {} bins, {:.0} lights a point, mean relative error {:.4}; levels {sizes:?}",
            h.bins.len(),
            evaluated as f64 / np,
            error / np
        );
    };
    probe("points alone", &as_points, 1);
    for b in bins {
        probe(&format!("spot_bins {b}"), &scene.lights, b);
    }
    Ok(())
}
