//! The exposure rule of generated lights (`LightSpec::irradiance`): one intensity for every
//! light, chosen so that the median surface point of the scene receives a given irradiance.
//!
//! A frame is exposed sensibly when its typical surface is lit about as brightly whatever the
//! number of lights, their placement or the scene: at irradiance 1 a white Lambertian surface
//! has radiance 1/pi, a mid-grey after the tonemapper at exposure 1. The rule measures the
//! irradiance the lights give at unit intensity, at [`POINTS`] area-weighted points on every
//! surface of the scene: each light as it is (infinite range, `1 / max(d^2, D_MIN^2)`), its
//! colour's luminance (Rec. 709), the cosine at the surface (zero behind it), a spot's cone, no
//! shadows. The median over the points of that irradiance, `E_1`, sets every light's intensity
//! to `irradiance / E_1`. Above [`LIGHTS`] lights a point's irradiance is estimated from
//! [`LIGHTS`] of them drawn at random, scaled by the lights over those drawn (the median of an
//! unbiased estimate; the draws and points from the spec's seed, so the rule is deterministic).
//! Lights spread over a surface at `rho` a square metre give it an irradiance of about
//! `2 pi rho` times their intensity, whatever their distance from it, so the rule's intensity
//! falls as one over the number of lights. With `Threshold(t)` radii a light's reach falls as
//! the square root of its intensity: lights lifted off their surfaces by more than their reach
//! then light it less, and the lights a point needs fall with the count.

use glam::Vec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

use crate::light::{falloff_infinite, luminance};
use crate::{Light, Scene, SceneError, placement};

/// Surface points the rule measures at.
pub const POINTS: usize = 1024;
/// Lights each point's irradiance is measured from (all of them, where there are fewer).
pub const LIGHTS: usize = 4096;

/// The irradiance at `p` (normal `n`) from `l` at unit intensity, as the rule measures it.
fn unit_irradiance(l: &Light, p: Vec3, n: Vec3) -> f64 {
    let to = (l.position - p).as_dvec3();
    let d = to.length();
    if d <= 0.0 {
        return 0.0;
    }
    let w = to / d;
    let cos = w.dot(n.as_dvec3());
    if cos <= 0.0 {
        return 0.0;
    }
    luminance(l.color) * cos * l.cone_toward(w) * falloff_infinite(d)
}

/// The median over the scene's surface points of the irradiance `lights` give at unit
/// intensity (`E_1` of the module's rule), from the points and lights `seed` draws.
pub fn median_unit_irradiance(
    scene: &Scene,
    lights: &[Light],
    seed: u64,
) -> Result<f64, SceneError> {
    // Its own stream, so that the lights' draws are those of a spec without the rule.
    let mut rng = Pcg64::seed_from_u64(seed ^ 0x6578_706f_7375_7265);
    let points = placement::surface_points(scene, POINTS, &mut rng);
    if points.is_empty() {
        return Err(SceneError::invalid(
            "lights.irradiance",
            "a scene without surfaces",
            "a scene with at least one triangle of positive area to expose",
        ));
    }
    let drawn: Vec<&Light> = if lights.len() <= LIGHTS {
        lights.iter().collect()
    } else {
        (0..LIGHTS)
            .map(|_| &lights[rng.random_range(0..lights.len())])
            .collect()
    };
    let scale = lights.len() as f64 / drawn.len().max(1) as f64;
    let mut e: Vec<f64> = points
        .iter()
        .map(|&(p, n)| scale * drawn.iter().map(|l| unit_irradiance(l, p, n)).sum::<f64>())
        .collect();
    e.sort_by(f64::total_cmp);
    let median = e[e.len() / 2];
    if median > 0.0 && median.is_finite() {
        Ok(median)
    } else {
        Err(SceneError::invalid(
            "lights.irradiance",
            format!("a median surface irradiance of {median} at unit intensity"),
            "lights that reach at least half of the scene's surface (area-weighted); \
             leave `irradiance` out and set `intensity`",
        ))
    }
}
