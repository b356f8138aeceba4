//! Spot lights in the hierarchy. Without bins (`spot_bins` 0, the default) a spot spreads into
//! the point lights' nodes with its power times its cone's flux over a point light's
//! ([`POINT_FLUX`]): the aggregates emit the spots' flux, over every direction, at no more
//! aggregates than the point lights make. With bins, their axes are sorted into direction
//! bins, each bin's levels built as the point lights' are, and each of its aggregates shaded
//! as a spot of the bin's cone:
//!
//! - A spot's bin is its axis's cell of an octahedral map of `n x n` cells
//!   ([`super::HierarchyParams::spot_bins`]; the map's centre straight down, where fixtures
//!   aim). Only cells that hold a spot are bins, numbered from 1 in the order of their cells
//!   (0 is the point lights').
//! - A bin's cone holds every cone of its spots: its axis is the mean of their axes, its outer
//!   angle the largest of a spot's outer angle plus the angle between its axis and the bin's
//!   (at most pi), and its inner angle that less the widest penumbra among them (the outer
//!   minus the inner angle). A bin of one spot, or of spots that share an axis and a cone, has
//!   their cone.
//! - A spot spreads into its bin's nodes of level 1 with its power times its cone's flux over
//!   the bin's ([`spot_flux`]): an aggregate emits, over every direction, what the spots it
//!   gathers emit, through the wider cone. So a lone spot is exact at every distance (every
//!   level places it at its own position, with its power and cone), and many spots of one bin
//!   far away are lit by their level's aggregate, whose cone is as wide as the bin's spread.
//!
//! The cones depend on the spots' axes and angles alone, which motion does not change, so a
//! hierarchy built again from moved lights has the same bins (the GPU build uploads them once).

use glam::{DVec2, DVec3, Vec3};

use crate::light::{Light, LightKind, SPOT_EPS};

/// A direction bin's cone: what each of its aggregates is shaded with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotBin {
    /// The cone's axis (unit): the mean of the spots' axes.
    pub axis: Vec3,
    /// Half-angle inside which an aggregate is at full strength, radians.
    pub inner_angle: f32,
    /// Half-angle at and beyond which it emits nothing, radians (at most pi).
    pub outer_angle: f32,
}

impl SpotBin {
    /// As a light of the scene model: a spot of this cone at `position`, of `radius`, colour
    /// `power` and intensity 1.
    pub fn light(&self, position: Vec3, radius: f32, power: Vec3) -> Light {
        Light {
            kind: LightKind::Spot {
                direction: self.axis,
                inner_angle: self.inner_angle,
                outer_angle: self.outer_angle,
            },
            position,
            radius,
            color: power,
            intensity: 1.0,
        }
    }

    /// The cone's flux ([`spot_flux`]) from its cosines as a light holds them.
    pub fn flux(&self) -> f64 {
        let (_, ci, co) = self.light(Vec3::ZERO, 1.0, Vec3::ONE).cone().unwrap();
        spot_flux(ci.into(), co.into())
    }
}

/// The integral over the cosine `c` in [-1, 1] of the spot cone
/// `clamp((c - cos_outer) / max(cos_inner - cos_outer, SPOT_EPS), 0, 1)^2`
/// ([`crate::light::spot`]): the cone's flux over `2 pi`.
pub fn spot_flux(cos_inner: f64, cos_outer: f64) -> f64 {
    let w = (cos_inner - cos_outer).max(SPOT_EPS);
    let t = (1.0 - cos_outer).min(w).max(0.0);
    t * t * t / (3.0 * w * w) + (1.0 - cos_outer - w).max(0.0)
}

/// The octahedral map's cell of unit axis `a` in an `n x n` map, its centre straight down.
fn cell(a: DVec3, n: u32) -> u32 {
    let a = a / a.abs().element_sum();
    let mut p = DVec2::new(a.x, a.z);
    if a.y > 0.0 {
        // The upper hemisphere folds out over the map's corners.
        let sign = DVec2::new(p.x.signum(), p.y.signum());
        p = (DVec2::ONE - DVec2::new(p.y.abs(), p.x.abs())) * sign;
    }
    let c = ((p + 1.0) * 0.5 * f64::from(n))
        .floor()
        .clamp(DVec2::ZERO, DVec2::splat(f64::from(n - 1)));
    c.y as u32 * n + c.x as u32
}

/// The angle between unit vectors `a` and `b`, exact near 0 (where `acos` of their dot
/// product is not).
fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// The direction bins of `lights`' spots in an `n x n` octahedral map, and each light's bin:
/// 0 for a point light, else its bin's number (from 1; `bins[number - 1]`). `n` 0: no bins,
/// every light's 0.
pub fn spot_bins(lights: &[Light], n: u32) -> (Vec<SpotBin>, Vec<u32>) {
    if n == 0 {
        return (Vec::new(), vec![0; lights.len()]);
    }
    let cones: Vec<Option<(DVec3, f64, f64)>> = lights
        .iter()
        .map(|l| match l.kind {
            LightKind::Point => None,
            LightKind::Spot {
                direction,
                inner_angle,
                outer_angle,
            } => Some((
                direction.normalize().as_dvec3(),
                f64::from(inner_angle),
                f64::from(outer_angle),
            )),
        })
        .collect();
    // Each occupied cell's number, in the order of the cells.
    let mut number = vec![0u32; (n * n) as usize];
    for (a, _, _) in cones.iter().flatten() {
        number[cell(*a, n) as usize] = 1;
    }
    let mut next = 0;
    for k in number.iter_mut().filter(|k| **k != 0) {
        next += 1;
        *k = next;
    }
    let of: Vec<u32> = cones
        .iter()
        .map(|c| c.map_or(0, |(a, _, _)| number[cell(a, n) as usize]))
        .collect();
    let bins = (1..=next)
        .map(|b| {
            let members = || cones.iter().zip(&of).filter(|(_, k)| **k == b);
            let sum: DVec3 = members().map(|(c, _)| c.unwrap().0).sum();
            let axis = if sum.length() > 1e-9 {
                sum.normalize()
            } else {
                members().next().unwrap().0.unwrap().0
            };
            let (mut outer, mut penumbra) = (0f64, 0f64);
            for (c, _) in members() {
                let (a, inner, out) = c.unwrap();
                let spread = angle(axis, a);
                outer = outer.max(spread + out);
                penumbra = penumbra.max(out - inner);
            }
            let outer = outer.min(std::f64::consts::PI);
            SpotBin {
                axis: axis.as_vec3(),
                inner_angle: (outer - penumbra).max(0.0) as f32,
                outer_angle: outer as f32,
            }
        })
        .collect();
    (bins, of)
}

/// The power spot `light` spreads into bin `bin`'s nodes (`None`: the point lights'): its
/// power times its cone's flux over the bin's (a point light's).
pub fn binned_power(light: &Light, bin: Option<&SpotBin>) -> DVec3 {
    let (_, ci, co) = light.cone().expect("a spot");
    light.color.as_dvec3() * f64::from(light.intensity) * spot_flux(ci.into(), co.into())
        / bin.map_or(POINT_FLUX, SpotBin::flux)
}

/// The flux of a point light (its cone 1 at every cosine): what a spot's power is scaled
/// against where it spreads into the point lights' nodes (no bins).
pub const POINT_FLUX: f64 = 2.0;

#[cfg(test)]
mod tests {
    use super::*;

    fn spot(direction: Vec3, outer_deg: f32) -> Light {
        Light {
            kind: LightKind::Spot {
                direction,
                inner_angle: 0.8 * outer_deg.to_radians(),
                outer_angle: outer_deg.to_radians(),
            },
            ..Light::point(Vec3::ZERO, 1.0, Vec3::ONE, 1.0)
        }
    }

    /// The flux is the cone's integral (a fine midpoint sum), full for a cone of pi.
    #[test]
    fn the_flux_is_the_cones_integral() {
        for (ci, co) in [
            (0.9, 0.8),
            (1.0, 0.5),
            (0.3, -0.2),
            (-0.5, -1.0),
            (0.7, 0.7),
        ] {
            let n = 200_000;
            let sum: f64 = (0..n)
                .map(|k| {
                    let c = -1.0 + 2.0 * (f64::from(k) + 0.5) / f64::from(n);
                    crate::light::spot(c, ci, co)
                })
                .sum::<f64>()
                * 2.0
                / f64::from(n);
            assert!((sum - spot_flux(ci, co)).abs() < 1e-4, "{ci} {co}: {sum}");
        }
        // A cone of pi whose penumbra is the whole sphere: the integral of ((c + 1) / 2)^2.
        assert!((spot_flux(1.0, -1.0) - 2.0 / 3.0).abs() < 1e-12);
    }

    /// One spot, or spots of one axis and cone, make a bin of their cone; spots aimed apart
    /// make a bin whose cone holds each of theirs; opposite axes fall in different bins.
    #[test]
    fn a_bins_cone_holds_its_spots() {
        let down = spot(-Vec3::Y, 35.0);
        let (bins, of) = spot_bins(&[down, Light::point(Vec3::ONE, 1.0, Vec3::ONE, 1.0)], 4);
        assert_eq!(of, vec![1, 0]);
        assert!((bins[0].axis + Vec3::Y).length() < 1e-6);
        assert!((bins[0].outer_angle - 35f32.to_radians()).abs() < 1e-6);
        assert!((bins[0].inner_angle - 28f32.to_radians()).abs() < 1e-6);
        assert!(
            (binned_power(&down, Some(&bins[0])) - DVec3::ONE)
                .abs()
                .max_element()
                < 1e-5
        );
        let tilted: Vec<Light> = (0..8)
            .map(|k| {
                let a = k as f32 * 0.7;
                spot(Vec3::new(0.2 * a.cos(), -1.0, 0.2 * a.sin()), 30.0)
            })
            .chain([spot(Vec3::Y, 30.0)])
            .collect();
        let (bins, of) = spot_bins(&tilted, 4);
        assert_ne!(of[0], of[8], "up and down share a bin");
        for (l, &b) in tilted.iter().zip(&of) {
            let bin = &bins[b as usize - 1];
            let (a, _, _) = l.cone().unwrap();
            let spread = angle(bin.axis.as_dvec3(), a.as_dvec3());
            assert!(spread + f64::from(30f32.to_radians()) <= f64::from(bin.outer_angle) + 1e-6);
            assert!(binned_power(l, Some(bin)).x <= 1.0 + 1e-6);
        }
    }
}
