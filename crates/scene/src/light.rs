//! Lights, the falloff, and the shading model, written once on the CPU side.
//!
//! The WGSL twin of everything here lives in `shaders/common/light.wgsl` (falloff and spot cone)
//! and `shaders/common/shading.wgsl` (the BRDF); a GPU test compares rendered pixels against
//! [`shade`] evaluated in f64.
//!
//! # Falloff
//! A windowed inverse-square law (the form used by Frostbite and Unreal):
//!
//! ```text
//! window(d, r)  = clamp(1 - (d / r)^4, 0, 1)^2
//! falloff(d, r) = window(d, r) / max(d^2, D_MIN^2)        D_MIN = 0.01
//! ```
//!
//! `window` reaches exactly zero at `d = r` and stays zero beyond it, so a light contributes
//! nothing outside its radius; this is what makes culling by radius exact rather than an
//! approximation. `D_MIN` (1 cm) keeps the singularity at `d = 0` finite.
//!
//! # Spot cone
//! `spot(cos_theta) = clamp((cos_theta - cos_outer) / max(cos_inner - cos_outer, SPOT_EPS), 0, 1)^2`,
//! where `theta` is the angle between the spot axis and the direction from the light to the
//! point. It is exactly zero at and outside the outer cone.
//!
//! # Shading model
//! Each light adds its irradiance times the material's reflectance and cosine, the material
//! model's [`crate::brdf::brdf_cos`]; the material's emission is added once:
//!
//! ```text
//! E  = colour * intensity * falloff(d, r) * spot
//! Lo = emissive + sum over lights of  E * brdf_cos(material, n, l, v)
//! ```
//! The models ([`crate::Brdf`]): Lambert plus a normalised Blinn-Phong lobe of fixed exponent
//! [`SHININESS`] (`base_colour / pi + specular * (s + 8) / (8 pi) * max(n.h, 0)^s`, the
//! procedural scenes' own), glTF's metallic-roughness GGX, a sheen lobe over Lambert, a clear
//! coat over GGX, and a wrapped diffuse.

use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

use crate::{Material, SceneError};

/// Minimum distance in the inverse-square term (1 cm), see the module docs.
pub const D_MIN: f64 = 0.01;
/// Lower bound on `cos_inner - cos_outer`, so a hard-edged spot (inner = outer) stays finite.
pub const SPOT_EPS: f64 = 1e-4;
/// Fixed Blinn-Phong exponent of the shading model.
pub const SHININESS: f64 = 32.0;

/// The kind of a light and the data only that kind has.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum LightKind {
    /// An omnidirectional point light.
    Point,
    /// A spot light.
    Spot {
        /// Unit axis of the cone (normalised on validation).
        direction: Vec3,
        /// Half-angle in radians inside which the spot is at full strength, `0 <= inner <= outer`.
        inner_angle: f32,
        /// Half-angle in radians at and beyond which the spot contributes nothing, `0 < outer <= pi`.
        outer_angle: f32,
    },
}

/// A point or spot light.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Light {
    /// Point or spot, with the spot's cone.
    pub kind: LightKind,
    /// Position in world space.
    pub position: Vec3,
    /// Radius of influence: the light contributes exactly nothing at or beyond it.
    pub radius: f32,
    /// Linear RGB colour, each channel >= 0.
    pub color: Vec3,
    /// Scalar intensity >= 0 (radiant intensity; the image is linear in it).
    pub intensity: f32,
}

impl Light {
    /// A point light.
    pub fn point(position: Vec3, radius: f32, color: Vec3, intensity: f32) -> Self {
        Self {
            kind: LightKind::Point,
            position,
            radius,
            color,
            intensity,
        }
    }

    /// Checks the light's data; `index` names it in the error.
    pub fn validate(&self, index: usize) -> Result<(), SceneError> {
        let f = |field: &str| format!("lights[{index}].{field}");
        if !self.position.is_finite() {
            return Err(SceneError::invalid(
                f("position"),
                format!("{:?}", self.position),
                "finite coordinates",
            ));
        }
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(SceneError::invalid(
                f("radius"),
                self.radius,
                "a finite value > 0",
            ));
        }
        if !(self.intensity.is_finite() && self.intensity >= 0.0) {
            return Err(SceneError::invalid(
                f("intensity"),
                self.intensity,
                "a finite value >= 0",
            ));
        }
        if !(self.color.is_finite() && self.color.min_element() >= 0.0) {
            return Err(SceneError::invalid(
                f("color"),
                format!("{:?}", self.color),
                "finite channels >= 0",
            ));
        }
        if let LightKind::Spot {
            direction,
            inner_angle,
            outer_angle,
        } = self.kind
        {
            if !(direction.is_finite() && direction.length_squared() > 1e-12) {
                return Err(SceneError::invalid(
                    f("direction"),
                    format!("{direction:?}"),
                    "a finite non-zero vector",
                ));
            }
            if !(outer_angle > 0.0 && outer_angle <= std::f32::consts::PI) {
                return Err(SceneError::invalid(
                    f("outer_angle"),
                    outer_angle,
                    "a half-angle in (0, pi] radians",
                ));
            }
            if !(inner_angle >= 0.0 && inner_angle <= outer_angle) {
                return Err(SceneError::invalid(
                    f("inner_angle"),
                    inner_angle,
                    format!("a half-angle in [0, outer_angle = {outer_angle}] radians"),
                ));
            }
        }
        Ok(())
    }

    /// The spot axis (normalised) and the cosines of the inner and outer half-angles, or `None`
    /// for a point light.
    pub fn cone(&self) -> Option<(Vec3, f32, f32)> {
        match self.kind {
            LightKind::Point => None,
            LightKind::Spot {
                direction,
                inner_angle,
                outer_angle,
            } => Some((direction.normalize(), inner_angle.cos(), outer_angle.cos())),
        }
    }

    /// The spot factor toward unit direction `l` from the lit point to the light (1 for a
    /// point light).
    pub fn cone_toward(&self, l: DVec3) -> f64 {
        match self.cone() {
            None => 1.0,
            Some((axis, cos_inner, cos_outer)) => spot(
                -l.dot(axis.as_dvec3()),
                f64::from(cos_inner),
                f64::from(cos_outer),
            ),
        }
    }

    /// Whether this light contributes anything at point `p` (inside the radius and, for a spot,
    /// strictly inside the outer cone). This defines the *exact set* of a surface point.
    pub fn reaches(&self, p: DVec3) -> bool {
        reaches(
            self.position,
            self.radius,
            self.cone().map(|(axis, _, cos_outer)| (axis, cos_outer)),
            p,
        )
    }
}

/// [`Light::reaches`] for a light given as the GPU holds it: its position, radius and, for a
/// spot, its unit axis and the cosine of its outer half-angle (as exports store them).
pub fn reaches(position: Vec3, radius: f32, cone: Option<(Vec3, f32)>, p: DVec3) -> bool {
    let to_p = p - position.as_dvec3();
    let d = to_p.length();
    if d >= f64::from(radius) {
        return false;
    }
    match cone {
        None => true,
        Some((axis, cos_outer)) => d > 0.0 && to_p.dot(axis.as_dvec3()) / d > f64::from(cos_outer),
    }
}

/// `clamp(1 - (d / r)^4, 0, 1)^2`: exactly zero for `d >= r`.
pub fn window(d: f64, r: f64) -> f64 {
    let x = d / r;
    let x2 = x * x;
    let w = (1.0 - x2 * x2).clamp(0.0, 1.0);
    w * w
}

/// The windowed inverse-square falloff, see the module docs.
pub fn falloff(d: f64, r: f64) -> f64 {
    window(d, r) / (d * d).max(D_MIN * D_MIN)
}

/// Infinite-range falloff (no window): the reference that measures what the cut-off costs.
pub fn falloff_infinite(d: f64) -> f64 {
    1.0 / (d * d).max(D_MIN * D_MIN)
}

/// Rec. 709 luminance of a linear colour.
pub fn luminance(c: Vec3) -> f64 {
    0.2126 * f64::from(c.x) + 0.7152 * f64::from(c.y) + 0.0722 * f64::from(c.z)
}

/// The spot factor for `cos_theta` between the axis and the light-to-point direction.
pub fn spot(cos_theta: f64, cos_inner: f64, cos_outer: f64) -> f64 {
    let t = ((cos_theta - cos_outer) / (cos_inner - cos_outer).max(SPOT_EPS)).clamp(0.0, 1.0);
    t * t
}

/// Whether the radius window is applied (the normal case) or ignored (the infinite-range
/// reference of the accuracy metrics).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Range {
    /// `falloff(d, r)`: zero at and beyond the radius.
    Windowed,
    /// `falloff_infinite(d)`: no cut-off.
    Infinite,
}

/// Outgoing radiance at surface point `p` with unit normal `n` towards the unit direction `v`
/// (from `p` to the viewer; constant for an orthographic camera), in f64: the CPU statement of
/// the shading model that every GPU backend implements.
pub fn shade(
    p: DVec3,
    n: DVec3,
    v: DVec3,
    material: &Material,
    lights: &[Light],
    range: Range,
) -> DVec3 {
    shade_with(p, n, v, material, lights, |_, light, d| match range {
        Range::Windowed => falloff(d, f64::from(light.radius)),
        Range::Infinite => falloff_infinite(d),
    })
}

/// [`shade`] with the falloff of light `k` at distance `d` given by `atten(k, light, d)`: the
/// shading model once, for every way a light's range is set (the stochastic ranges of
/// [`crate::stochastic::shade`]).
pub fn shade_with(
    p: DVec3,
    n: DVec3,
    v: DVec3,
    material: &Material,
    lights: &[Light],
    atten: impl Fn(usize, &Light, f64) -> f64,
) -> DVec3 {
    let base = material.base_color.as_dvec3();
    let mut out = material.emissive.as_dvec3();
    for (k, light) in lights.iter().enumerate() {
        let to_light = light.position.as_dvec3() - p;
        let d = to_light.length();
        let atten = atten(k, light, d);
        if atten == 0.0 {
            continue;
        }
        let l = if d > 0.0 { to_light / d } else { n };
        let cone = light.cone_toward(l);
        if cone == 0.0 {
            continue;
        }
        let f = crate::brdf::brdf_cos(&material.brdf, base, n, l, v);
        out += light.color.as_dvec3() * f64::from(light.intensity) * atten * cone * f;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn falloff_is_zero_at_and_beyond_radius() {
        assert_eq!(falloff(2.0, 2.0), 0.0);
        assert_eq!(falloff(2.5, 2.0), 0.0);
        assert!(falloff(1.999, 2.0) > 0.0);
        // Close to the light the window is ~1 and the law is inverse-square.
        let ratio = falloff(0.1, 100.0) / falloff(0.2, 100.0);
        assert!((ratio - 4.0).abs() < 1e-6);
    }

    #[test]
    fn spot_is_zero_outside_outer_cone() {
        let (ci, co) = (0.3f64.cos(), 0.5f64.cos());
        assert_eq!(spot(0.5f64.cos(), ci, co), 0.0);
        assert_eq!(spot(0.7f64.cos(), ci, co), 0.0);
        assert_eq!(spot(0.2f64.cos(), ci, co), 1.0);
        // Hard-edged cone (inner == outer) stays finite.
        assert_eq!(spot(0.49f64.cos(), co, co), 1.0);
    }

    #[test]
    fn invalid_lights_name_the_field() {
        let mut l = Light::point(Vec3::ZERO, -1.0, Vec3::ONE, 1.0);
        assert!(
            l.validate(7)
                .unwrap_err()
                .to_string()
                .contains("lights[7].radius = -1")
        );
        l.radius = 1.0;
        l.intensity = f32::NAN;
        assert!(
            l.validate(0)
                .unwrap_err()
                .to_string()
                .contains("intensity = NaN")
        );
    }
}
