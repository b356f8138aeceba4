//! Deterministic light generators: the same spec, scene and seed give the same lights, bit for
//! bit, on every machine (PCG64 streams and plain f32 arithmetic).

use glam::Vec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use serde::{Deserialize, Serialize};

use crate::placement;
pub use crate::radius::RadiusRule;
use crate::stochastic::StochasticParams;
use crate::{Light, LightKind, Motion, Scene, SceneError};

/// How light positions are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum LightGenerator {
    /// Uniformly distributed in the scene's light volume.
    Uniform,
    /// On the scene's surfaces (area-weighted), lifted `offset` metres along the normal.
    SurfaceHugging {
        /// Lift along the surface normal, metres, >= 0.
        offset: f32,
    },
    /// Gaussian hot spots around `clusters` centres drawn uniformly in the light volume.
    Clustered {
        /// Number of hot spots, >= 1.
        clusters: u32,
        /// Standard deviation of each hot spot, metres, > 0.
        spread: f32,
    },
    /// A stratified field filling the light volume, one jittered light per cell, as in the
    /// Forward+ paper's demo (3,072 point lights scattered through the scene).
    LightField,
    /// On the scene's surfaces, area-weighted, each lifted along its surface's shading normal
    /// (the vertex normals there) by a distance drawn uniformly in `offset`, metres; a spot
    /// aims along that normal. Lights stay in the rooms a real interior has.
    OnSurfaces {
        /// The range of the lift, `(lowest, highest)`, metres, `0 <= lowest <= highest`.
        offset: (f32, f32),
    },
    /// Fixtures as designers place them: hanging `drop` metres under downward-facing surfaces
    /// (ceilings, beams: normals within 45 degrees of down), spots aimed straight down, and
    /// mounted `drop` out from walls (normals within 30 degrees of horizontal), spots aimed out
    /// of the wall and 30 degrees down; `on_walls` of them (a fraction) on walls. Each kind is
    /// area-weighted over its surfaces; a scene without one kind puts every light on the other.
    Fixtures {
        /// Distance from the surface, metres, >= 0.
        drop: f32,
        /// The fraction on walls, in [0, 1].
        on_walls: f32,
    },
}

/// A complete description of a generated light set. Every field has a default (see
/// `LightSpec::default`), so experiment files name only what they change.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LightSpec {
    /// Placement.
    pub generator: LightGenerator,
    /// Number of lights.
    pub count: u32,
    /// Seed of every random choice.
    pub seed: u64,
    /// Radius rule.
    pub radius: RadiusRule,
    /// Intensity of every light, >= 0 (unused where `irradiance` is set).
    pub intensity: f32,
    /// Where set, > 0: every light's intensity is the one at which the median surface point of
    /// the scene receives this irradiance from the lights (the exposure rule,
    /// [`crate::exposure`]); it replaces `intensity`. Left out of the serialised form where
    /// unset, so that earlier experiments keep their cell identifiers.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub irradiance: Option<f32>,
    /// Fraction of the lights that are spots, in [0, 1].
    pub spot_fraction: f32,
    /// Outer half-angle of generated spots in degrees, in (0, 180]; the inner one is 80% of it.
    pub spot_outer_deg: f32,
    /// How the generated lights move from frame to frame (`Static`, the default, left out of
    /// the serialised form so that earlier experiments keep their cell identifiers).
    #[serde(skip_serializing_if = "is_static")]
    pub motion: Motion,
    /// Fraction of the generated lights that `motion` moves, in [0, 1] (default 1, every
    /// one; left out of the serialised form then): the last [`LightSpec::moving_count`] of
    /// them, the others staying home, as an application's few moving lights among many fixed
    /// ones.
    #[serde(skip_serializing_if = "is_all")]
    pub moving: f32,
}

fn is_static(m: &Motion) -> bool {
    *m == Motion::Static
}

fn is_all(f: &f32) -> bool {
    *f == 1.0
}

impl Default for LightSpec {
    fn default() -> Self {
        Self {
            generator: LightGenerator::Uniform,
            count: 256,
            seed: 1,
            radius: RadiusRule::Fixed(3.0),
            intensity: 4.0,
            irradiance: None,
            spot_fraction: 0.0,
            spot_outer_deg: 35.0,
            motion: Motion::Static,
            moving: 1.0,
        }
    }
}

impl LightSpec {
    /// How many of the generated lights move: `moving` of `count`, rounded to the nearest;
    /// none where `motion` is static.
    pub fn moving_count(&self) -> u32 {
        if self.motion.is_static() {
            return 0;
        }
        (f64::from(self.moving) * f64::from(self.count)).round() as u32
    }

    /// Checks every field; the error names the field, the value and what is accepted.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.motion.validate()?;
        if !(0.0..=1.0).contains(&self.moving) {
            return Err(SceneError::invalid(
                "lights.moving",
                self.moving,
                "a fraction in [0, 1] of the generated lights that move",
            ));
        }
        if !(self.intensity.is_finite() && self.intensity >= 0.0) {
            return Err(SceneError::invalid(
                "lights.intensity",
                self.intensity,
                "a finite value >= 0",
            ));
        }
        if let Some(e) = self.irradiance
            && !(e.is_finite() && e > 0.0)
        {
            return Err(SceneError::invalid(
                "lights.irradiance",
                e,
                "a finite irradiance > 0 (the median surface point's; 1 is a sensible exposure)",
            ));
        }
        self.radius.validate()?;
        if !(0.0..=1.0).contains(&self.spot_fraction) {
            return Err(SceneError::invalid(
                "lights.spot_fraction",
                self.spot_fraction,
                "a fraction in [0, 1]",
            ));
        }
        if !(self.spot_outer_deg > 0.0 && self.spot_outer_deg <= 180.0) {
            return Err(SceneError::invalid(
                "lights.spot_outer_deg",
                self.spot_outer_deg,
                "a half-angle in (0, 180] degrees",
            ));
        }
        match self.generator {
            LightGenerator::SurfaceHugging { offset } if !(offset.is_finite() && offset >= 0.0) => {
                Err(SceneError::invalid(
                    "lights.offset",
                    offset,
                    "a finite value >= 0",
                ))
            }
            LightGenerator::OnSurfaces { offset: (lo, hi) }
                if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi) =>
            {
                Err(SceneError::invalid(
                    "lights.offset",
                    format!("({lo}, {hi})"),
                    "(lowest, highest) metres with 0 <= lowest <= highest",
                ))
            }
            LightGenerator::Fixtures { drop, .. } if !(drop.is_finite() && drop >= 0.0) => Err(
                SceneError::invalid("lights.drop", drop, "a finite value >= 0 (metres)"),
            ),
            LightGenerator::Fixtures { on_walls, .. } if !(0.0..=1.0).contains(&on_walls) => Err(
                SceneError::invalid("lights.on_walls", on_walls, "a fraction in [0, 1]"),
            ),
            LightGenerator::Clustered { clusters, .. } if clusters == 0 => Err(
                SceneError::invalid("lights.clusters", clusters, "an integer >= 1"),
            ),
            LightGenerator::Clustered { spread, .. } if !(spread.is_finite() && spread > 0.0) => {
                Err(SceneError::invalid(
                    "lights.spread",
                    spread,
                    "a finite value > 0",
                ))
            }
            _ => Ok(()),
        }
    }

    /// Generates the lights for `scene` (its geometry and light volume).
    pub fn generate(&self, scene: &Scene) -> Result<Vec<Light>, SceneError> {
        self.validate()?;
        let b = scene.light_bounds;
        if !b.is_valid() {
            return Err(SceneError::invalid(
                "scene.light_bounds",
                format!("{b:?}"),
                "a non-empty box",
            ));
        }
        let mut rng = Pcg64::seed_from_u64(self.seed);
        let stochastic = self.stochastic(scene);
        let placed = self.place(scene, &mut rng)?;
        let mut lights: Vec<Light> = placed
            .into_iter()
            .map(|(position, aim, _)| {
                let color = hue_to_rgb(rng.random::<f32>());
                let kind = if rng.random::<f32>() < self.spot_fraction {
                    let direction = aim.unwrap_or_else(|| {
                        // Mostly downward axes, tilted up to 60 degrees.
                        let tilt = rng.random::<f32>() * 60f32.to_radians();
                        let az = rng.random::<f32>() * std::f32::consts::TAU;
                        Vec3::new(tilt.sin() * az.cos(), -tilt.cos(), tilt.sin() * az.sin())
                    });
                    let outer = self.spot_outer_deg.to_radians();
                    LightKind::Spot {
                        direction,
                        inner_angle: 0.8 * outer,
                        outer_angle: outer,
                    }
                } else {
                    LightKind::Point
                };
                Light {
                    kind,
                    position,
                    radius: 0.0,
                    color,
                    intensity: self.intensity,
                }
            })
            .collect();
        if let Some(e) = self.irradiance
            && !lights.is_empty()
        {
            for l in &mut lights {
                l.intensity = 1.0;
            }
            let e1 = crate::exposure::median_unit_irradiance(scene, &lights, self.seed)?;
            let intensity = (f64::from(e) / e1) as f32;
            for l in &mut lights {
                l.intensity = intensity;
            }
        }
        for l in &mut lights {
            l.radius = self.radius_of(l, stochastic.as_ref());
        }
        Ok(lights)
    }

    /// The anchor normal of each light [`LightSpec::generate`] makes for `scene`, in its order:
    /// the normal of the surface it was placed on (`OnSurfaces`, `Fixtures`), up for the volume
    /// generators. What `Motion::Glide` moves the lights across; the lights themselves carry no
    /// normal, as shading needs none.
    pub fn anchors(&self, scene: &Scene) -> Result<Vec<Vec3>, SceneError> {
        self.validate()?;
        let mut rng = Pcg64::seed_from_u64(self.seed);
        Ok(self
            .place(scene, &mut rng)?
            .into_iter()
            .map(|(_, _, n)| n)
            .collect())
    }

    /// Each light's place, for the surface placements the direction a spot aims along, and its
    /// anchor normal (up for the volume generators): the first draws of `rng`.
    fn place(
        &self,
        scene: &Scene,
        rng: &mut Pcg64,
    ) -> Result<Vec<(Vec3, Option<Vec3>, Vec3)>, SceneError> {
        let n = self.count as usize;
        Ok(match self.generator {
            LightGenerator::OnSurfaces { offset } => placement::on_surfaces(scene, n, offset, rng)?
                .into_iter()
                .map(|(p, aim, normal)| (p, Some(aim), normal))
                .collect(),
            LightGenerator::Fixtures { drop, on_walls } => {
                placement::fixtures(scene, n, drop, on_walls, rng)?
                    .into_iter()
                    .map(|(p, aim, normal)| (p, Some(aim), normal))
                    .collect()
            }
            g => self
                .positions(g, scene, n, rng)?
                .into_iter()
                .map(|p| (p, None, Vec3::Y))
                .collect(),
        })
    }

    /// The radius the spec's rule gives light `l` (its intensity and colour set).
    fn radius_of(&self, l: &Light, stochastic: Option<&StochasticParams>) -> f32 {
        match stochastic {
            // The shortest range, at xi = 1.
            Some(p) => StochasticParams::range(p.alpha(l), 1.0),
            None => match self.radius {
                RadiusRule::Fixed(r) => r,
                RadiusRule::Threshold(t) => {
                    (l.intensity * l.color.max_element() / t).sqrt().max(1e-3)
                }
                RadiusRule::Stochastic { .. } => 0.0,
                RadiusRule::Hierarchy { alpha, spacing, .. } => 2.0 * alpha * spacing,
            },
        }
    }

    /// The places of the volume and surface-hugging generators' `n` lights.
    fn positions(
        &self,
        g: LightGenerator,
        scene: &Scene,
        n: usize,
        rng: &mut Pcg64,
    ) -> Result<Vec<Vec3>, SceneError> {
        let b = scene.light_bounds;
        let uniform = |rng: &mut Pcg64| {
            b.min
                + b.extent()
                    * Vec3::new(
                        rng.random::<f32>(),
                        rng.random::<f32>(),
                        rng.random::<f32>(),
                    )
        };
        Ok(match g {
            LightGenerator::Uniform => (0..n).map(|_| uniform(rng)).collect(),
            LightGenerator::SurfaceHugging { offset } => surface_points(scene, n, offset, rng)?,
            LightGenerator::Clustered { clusters, spread } => {
                let centres: Vec<Vec3> = (0..clusters).map(|_| uniform(rng)).collect();
                (0..n)
                    .map(|i| {
                        let c = centres[i % centres.len()];
                        let g = Vec3::new(gaussian(rng), gaussian(rng), gaussian(rng));
                        (c + g * spread).clamp(b.min, b.max)
                    })
                    .collect()
            }
            LightGenerator::LightField => light_field(b.min, b.extent(), n, rng),
            LightGenerator::OnSurfaces { .. } | LightGenerator::Fixtures { .. } => {
                unreachable!("placed on surfaces by generate")
            }
        })
    }

    /// The parameters of the stochastic ranges in `scene`, where the radius rule is
    /// `Stochastic` (the seed is the light set's, folded to 32 bits).
    pub fn stochastic(&self, scene: &Scene) -> Option<StochasticParams> {
        match self.radius {
            RadiusRule::Stochastic {
                error,
                bound,
                exposure,
                interleave,
                draw,
                ..
            } => Some(StochasticParams {
                error,
                exposure,
                scale: bound.scale(&scene.materials),
                seed: (self.seed ^ (self.seed >> 32)) as u32,
                interleave,
                draw,
            }),
            _ => None,
        }
    }
}

/// Standard normal sample (Box-Muller).
/// The places of the `n` lights `generator` makes in `scene` with `seed` (radius and intensity
/// at their defaults): points off the surfaces, in the box or at fixtures, for what needs the
/// generators' places rather than lights (the shadow rays' tests and benchmark).
pub fn places(
    scene: &Scene,
    generator: LightGenerator,
    n: u32,
    seed: u64,
) -> Result<Vec<Vec3>, SceneError> {
    let spec = LightSpec {
        generator,
        count: n,
        seed,
        radius: RadiusRule::Fixed(1.0),
        ..LightSpec::default()
    };
    Ok(spec.generate(scene)?.iter().map(|l| l.position).collect())
}

fn gaussian(rng: &mut Pcg64) -> f32 {
    let u1 = rng.random::<f32>().max(1e-7);
    let u2 = rng.random::<f32>();
    (-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos()
}

/// A fully saturated colour of the given hue in [0, 1), max channel 1.
fn hue_to_rgb(h: f32) -> Vec3 {
    let x = h * 6.0;
    let c = |k: f32| (((x + k) % 6.0 - 3.0).abs() - 1.0).clamp(0.0, 1.0);
    Vec3::new(c(0.0), c(4.0), c(2.0))
}

fn surface_points(
    scene: &Scene,
    n: usize,
    offset: f32,
    rng: &mut Pcg64,
) -> Result<Vec<Vec3>, SceneError> {
    // Cumulative triangle areas over the whole scene, then inverse-CDF sampling.
    let mut tris = Vec::new();
    let mut cdf = Vec::new();
    let mut total = 0.0f64;
    for p in &scene.primitives {
        for t in p.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| p.positions[i as usize]);
            let area = 0.5 * f64::from((b - a).cross(c - a).length());
            if area > 0.0 {
                total += area;
                tris.push((a, b, c));
                cdf.push(total);
            }
        }
    }
    if tris.is_empty() {
        return Err(SceneError::invalid(
            "lights.generator",
            "SurfaceHugging",
            "a scene with at least one non-degenerate triangle",
        ));
    }
    Ok((0..n)
        .map(|_| {
            let x = rng.random::<f64>() * total;
            let k = cdf.partition_point(|&c| c < x).min(tris.len() - 1);
            let (a, b, c) = tris[k];
            let (mut u, mut v) = (rng.random::<f32>(), rng.random::<f32>());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let normal = (b - a).cross(c - a).normalize();
            a + (b - a) * u + (c - a) * v + normal * offset
        })
        .collect())
}

fn light_field(min: Vec3, extent: Vec3, n: usize, rng: &mut Pcg64) -> Vec<Vec3> {
    if n == 0 {
        return Vec::new();
    }
    // Cells proportional to the volume's extent, at least n of them.
    let e = extent.max(Vec3::splat(1e-3));
    let cell = (e.x * e.y * e.z / n as f32).cbrt();
    let mut dims = (e / cell).ceil().max(Vec3::ONE).as_uvec3();
    while (dims.x * dims.y * dims.z) < n as u32 {
        dims.x += 1;
    }
    let cells = (dims.x * dims.y * dims.z) as usize;
    // Choose n distinct cells (partial Fisher-Yates), one jittered light in each.
    let mut order: Vec<u32> = (0..cells as u32).collect();
    for i in 0..n {
        let j = rng.random_range(i..cells);
        order.swap(i, j);
    }
    order[..n]
        .iter()
        .map(|&c| {
            let idx = Vec3::new(
                (c % dims.x) as f32,
                ((c / dims.x) % dims.y) as f32,
                (c / (dims.x * dims.y)) as f32,
            );
            let jitter = Vec3::new(
                rng.random::<f32>(),
                rng.random::<f32>(),
                rng.random::<f32>(),
            );
            min + (idx + jitter) / dims.as_vec3() * extent
        })
        .collect()
}

#[cfg(test)]
mod tests {

    use super::*;
    use crate::procedural::ProceduralScene;

    fn scene() -> Scene {
        ProceduralScene::from_name("atrium")
            .unwrap()
            .build()
            .unwrap()
    }

    #[test]
    fn generators_are_deterministic_valid_and_in_bounds() {
        let s = scene();
        let gens = [
            LightGenerator::Uniform,
            LightGenerator::SurfaceHugging { offset: 0.1 },
            LightGenerator::Clustered {
                clusters: 4,
                spread: 1.0,
            },
            LightGenerator::LightField,
        ];
        for g in gens {
            let spec = LightSpec {
                generator: g,
                count: 3072,
                spot_fraction: 0.25,
                ..LightSpec::default()
            };
            let a = spec.generate(&s).unwrap();
            assert_eq!(a, spec.generate(&s).unwrap(), "{g:?} not deterministic");
            assert_eq!(a.len(), 3072);
            for (i, l) in a.iter().enumerate() {
                l.validate(i).unwrap();
            }
            assert!(a.iter().any(|l| l.cone().is_some()), "{g:?}: no spots");
            if !matches!(g, LightGenerator::SurfaceHugging { .. }) {
                let b = s.light_bounds;
                assert!(
                    a.iter()
                        .all(|l| l.position.cmpge(b.min).all() && l.position.cmple(b.max).all()),
                    "{g:?} out of bounds"
                );
            }
            let other = LightSpec { seed: 2, ..spec }.generate(&s).unwrap();
            assert_ne!(a, other, "{g:?}: the seed changes nothing");
        }
    }

    #[test]
    fn threshold_radius_solves_the_inverse_square() {
        let spec = LightSpec {
            radius: RadiusRule::Threshold(0.01),
            intensity: 4.0,
            count: 16,
            ..LightSpec::default()
        };
        for l in spec.generate(&scene()).unwrap() {
            let at_r = l.intensity * l.color.max_element() / (l.radius * l.radius);
            assert!((at_r - 0.01).abs() < 1e-5, "{at_r}");
        }
    }

    #[test]
    fn bad_specs_name_the_field() {
        let e = LightSpec {
            radius: RadiusRule::Fixed(-1.0),
            ..LightSpec::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("lights.radius = -1"), "{e}");
        let e = LightSpec {
            intensity: f32::NAN,
            ..LightSpec::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("lights.intensity = NaN"), "{e}");
        let e = LightSpec {
            moving: 1.5,
            ..LightSpec::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("lights.moving = 1.5"), "{e}");
    }

    #[test]
    fn a_fraction_of_the_lights_moves() {
        let spec = LightSpec {
            count: 1000,
            motion: Motion::Noise(1.0),
            moving: 0.1,
            ..LightSpec::default()
        };
        assert_eq!(spec.moving_count(), 100);
        assert_eq!(
            LightSpec {
                moving: 1.0,
                ..spec
            }
            .moving_count(),
            1000
        );
        assert_eq!(
            LightSpec {
                motion: Motion::Static,
                ..spec
            }
            .moving_count(),
            0
        );
        // Every light moving is left out of the written form (cell identifiers keep).
        let all = ron::to_string(&LightSpec {
            moving: 1.0,
            ..spec
        })
        .unwrap();
        assert!(!all.contains("moving"), "{all}");
        assert!(ron::to_string(&spec).unwrap().contains("moving:0.1"));
    }
}
