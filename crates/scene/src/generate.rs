//! Deterministic light generators: the same spec, scene and seed give the same lights, bit for
//! bit, on every machine (PCG64 streams and plain f32 arithmetic).

use glam::Vec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use serde::{Deserialize, Serialize};

use crate::stochastic::{StochasticBound, StochasticDraw, StochasticParams};
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
}

/// How each light's radius is set.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum RadiusRule {
    /// The same radius for every light, metres, > 0.
    Fixed(f32),
    /// The distance at which the un-windowed inverse-square irradiance of the light's brightest
    /// channel falls to this threshold: `r = sqrt(intensity * max(colour) / threshold)`, > 0.
    Threshold(f32),
    /// Stochastic light culling ([`crate::stochastic`]): every frame each light gets a random
    /// range, drawn so that the image is an unbiased estimate of the infinite-range one. The
    /// generated radius is the shortest range (`xi = 1`); `lights.stochastic` draws each
    /// frame's.
    Stochastic {
        /// Bound on one light's standard deviation, > 0: of its exposed incident contribution
        /// (`exposure * intensity * max(colour) * falloff`) with the default `bound: Light`,
        /// of its reflected radiance off the scene's most reflective diffuse-equivalent
        /// surface with `bound: Albedo` ([`crate::stochastic`]).
        error: f32,
        /// What `error` bounds: `Light` (the default, left out of the serialised form) or
        /// `Albedo`.
        #[serde(default, skip_serializing_if = "is_light_bound")]
        bound: StochasticBound,
        /// The exposure `error` is measured at, > 0 (default 1).
        #[serde(default = "unit")]
        exposure: f32,
        /// Frames averaged into one image with fresh ranges, as a renderer accumulates
        /// temporally: 0 (the default) none, otherwise at least 2.
        #[serde(default)]
        accumulate: u32,
        /// Independent draws measured for the noise and bias columns, >= 1 (default 4).
        #[serde(default = "four")]
        seeds: u32,
        /// Interleaved sampling over `n x n` pixel classes, each drawing its own ranges
        /// ([`crate::stochastic`]): 1 (the default, left out of the serialised form so that
        /// earlier cells keep their identifiers) none, up to
        /// [`crate::stochastic::INTERLEAVE_MAX`].
        #[serde(default = "one", skip_serializing_if = "is_one")]
        interleave: u32,
        /// How a frame's numbers are drawn across the lights: `Stratified` (the default, left
        /// out of the serialised form) or `Independent` ([`crate::stochastic`]).
        #[serde(default, skip_serializing_if = "is_stratified")]
        draw: StochasticDraw,
    },
    /// The lighting grid hierarchy ([`crate::hierarchy`]): the point lights near a shading
    /// point as they are, far ones from aggregates on nested grids, every light a sphere of
    /// bounded range; deterministic, with a bias that shrinks as `alpha` grows. The generated
    /// radius is level 0's reach, `2 alpha spacing`.
    Hierarchy {
        /// The accuracy parameter, > 0 (the papers use 1 and more): level `l`'s lights reach
        /// `2 alpha h 2^l`, `h` the finest grid's spacing.
        alpha: f32,
        /// The finest grid's spacing, metres, > 0, at least: it doubles while that grid would
        /// hold more than `finest_nodes` times as many nodes as there are point lights.
        spacing: f32,
        /// The most nodes the finest grid may hold a point light, > 0
        /// (`HierarchyParams::finest_nodes`): 2 by default (left out of the serialised form),
        /// the authors' implementation 0.25.
        #[serde(default = "finest_nodes", skip_serializing_if = "is_finest_nodes")]
        finest_nodes: f32,
        /// Stochastic band selection from this level on (`HierarchyParams::sample_from`):
        /// those levels' lights draw their bands each frame, unbiased, with shorter lists.
        /// Absent: none.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        sample_from: Option<u32>,
    },
}

fn is_stratified(d: &StochasticDraw) -> bool {
    *d == StochasticDraw::Stratified
}

fn is_light_bound(b: &StochasticBound) -> bool {
    *b == StochasticBound::Light
}

fn one() -> u32 {
    1
}

fn finest_nodes() -> f32 {
    crate::hierarchy::FINEST_NODES as f32
}

fn is_finest_nodes(r: &f32) -> bool {
    *r == finest_nodes()
}

fn is_one(n: &u32) -> bool {
    *n == 1
}

fn unit() -> f32 {
    1.0
}

fn four() -> u32 {
    4
}

impl RadiusRule {
    /// The name of the rule in cell names and result columns: `fixed`, `threshold`,
    /// `stochastic` or `hierarchy`.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Fixed(_) => "fixed",
            Self::Threshold(_) => "threshold",
            Self::Stochastic { .. } => "stochastic",
            Self::Hierarchy { .. } => "hierarchy",
        }
    }
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
    /// Intensity of every light, >= 0.
    pub intensity: f32,
    /// Fraction of the lights that are spots, in [0, 1].
    pub spot_fraction: f32,
    /// Outer half-angle of generated spots in degrees, in (0, 180]; the inner one is 80% of it.
    pub spot_outer_deg: f32,
    /// How the generated lights move from frame to frame (`Static`, the default, left out of
    /// the serialised form so that earlier experiments keep their cell identifiers).
    #[serde(skip_serializing_if = "is_static")]
    pub motion: Motion,
}

fn is_static(m: &Motion) -> bool {
    *m == Motion::Static
}

impl Default for LightSpec {
    fn default() -> Self {
        Self {
            generator: LightGenerator::Uniform,
            count: 256,
            seed: 1,
            radius: RadiusRule::Fixed(3.0),
            intensity: 4.0,
            spot_fraction: 0.0,
            spot_outer_deg: 35.0,
            motion: Motion::Static,
        }
    }
}

impl LightSpec {
    /// Checks every field; the error names the field, the value and what is accepted.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.motion.validate()?;
        if !(self.intensity.is_finite() && self.intensity >= 0.0) {
            return Err(SceneError::invalid(
                "lights.intensity",
                self.intensity,
                "a finite value >= 0",
            ));
        }
        match self.radius {
            RadiusRule::Fixed(r) if !(r.is_finite() && r > 0.0) => {
                return Err(SceneError::invalid(
                    "lights.radius",
                    r,
                    "a finite radius > 0",
                ));
            }
            RadiusRule::Threshold(t) if !(t.is_finite() && t > 0.0) => {
                return Err(SceneError::invalid(
                    "lights.threshold",
                    t,
                    "a finite cut-off threshold > 0",
                ));
            }
            RadiusRule::Hierarchy {
                alpha,
                spacing,
                finest_nodes,
                ..
            } => {
                if !(finest_nodes.is_finite() && finest_nodes > 0.0) {
                    return Err(SceneError::invalid(
                        "lights.radius.finest_nodes",
                        finest_nodes,
                        "a finite number of nodes a point light > 0 (2 by default; 0.25 the \
                         authors')",
                    ));
                }
                if !(alpha.is_finite() && alpha > 0.0) {
                    return Err(SceneError::invalid(
                        "lights.radius.alpha",
                        alpha,
                        "a finite accuracy parameter > 0",
                    ));
                }
                if !(spacing.is_finite() && spacing > 0.0) {
                    return Err(SceneError::invalid(
                        "lights.radius.spacing",
                        spacing,
                        "a finite grid spacing > 0 (metres)",
                    ));
                }
            }
            RadiusRule::Stochastic {
                error,
                exposure,
                accumulate,
                seeds,
                interleave,
                ..
            } => {
                if !(1..=crate::stochastic::INTERLEAVE_MAX).contains(&interleave) {
                    return Err(SceneError::invalid(
                        "lights.radius.interleave",
                        interleave,
                        format!(
                            "1 (none) to {} (n x n pixel classes)",
                            crate::stochastic::INTERLEAVE_MAX
                        ),
                    ));
                }
                if !(error.is_finite() && error > 0.0) {
                    return Err(SceneError::invalid(
                        "lights.radius.error",
                        error,
                        "a finite error bound > 0",
                    ));
                }
                if !(exposure.is_finite() && exposure > 0.0) {
                    return Err(SceneError::invalid(
                        "lights.radius.exposure",
                        exposure,
                        "a finite exposure > 0",
                    ));
                }
                if accumulate == 1 {
                    return Err(SceneError::invalid(
                        "lights.radius.accumulate",
                        accumulate,
                        "0 (no accumulation) or at least 2 frames",
                    ));
                }
                if seeds == 0 {
                    return Err(SceneError::invalid(
                        "lights.radius.seeds",
                        seeds,
                        "at least 1 seed",
                    ));
                }
            }
            _ => {}
        }
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
        let n = self.count as usize;
        let uniform = |rng: &mut Pcg64| {
            b.min
                + b.extent()
                    * Vec3::new(
                        rng.random::<f32>(),
                        rng.random::<f32>(),
                        rng.random::<f32>(),
                    )
        };
        let positions: Vec<Vec3> = match self.generator {
            LightGenerator::Uniform => (0..n).map(|_| uniform(&mut rng)).collect(),
            LightGenerator::SurfaceHugging { offset } => {
                surface_points(scene, n, offset, &mut rng)?
            }
            LightGenerator::Clustered { clusters, spread } => {
                let centres: Vec<Vec3> = (0..clusters).map(|_| uniform(&mut rng)).collect();
                (0..n)
                    .map(|i| {
                        let c = centres[i % centres.len()];
                        let g =
                            Vec3::new(gaussian(&mut rng), gaussian(&mut rng), gaussian(&mut rng));
                        (c + g * spread).clamp(b.min, b.max)
                    })
                    .collect()
            }
            LightGenerator::LightField => light_field(b.min, b.extent(), n, &mut rng),
        };
        let lights = positions
            .into_iter()
            .map(|position| {
                let color = hue_to_rgb(rng.random::<f32>());
                let radius = match self.radius {
                    RadiusRule::Fixed(r) => r,
                    RadiusRule::Threshold(t) => {
                        (self.intensity * color.max_element() / t).sqrt().max(1e-3)
                    }
                    RadiusRule::Stochastic { .. } => 0.0,
                    RadiusRule::Hierarchy { alpha, spacing, .. } => 2.0 * alpha * spacing,
                };
                let kind = if rng.random::<f32>() < self.spot_fraction {
                    // Mostly downward axes, tilted up to 60 degrees.
                    let tilt = rng.random::<f32>() * 60f32.to_radians();
                    let az = rng.random::<f32>() * std::f32::consts::TAU;
                    let direction =
                        Vec3::new(tilt.sin() * az.cos(), -tilt.cos(), tilt.sin() * az.sin());
                    let outer = self.spot_outer_deg.to_radians();
                    LightKind::Spot {
                        direction,
                        inner_angle: 0.8 * outer,
                        outer_angle: outer,
                    }
                } else {
                    LightKind::Point
                };
                let light = Light {
                    kind,
                    position,
                    radius,
                    color,
                    intensity: self.intensity,
                };
                match &stochastic {
                    // The shortest range, at xi = 1.
                    Some(p) => Light {
                        radius: StochasticParams::range(p.alpha(&light), 1.0),
                        ..light
                    },
                    None => light,
                }
            })
            .collect();
        Ok(lights)
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

    #[test]
    fn bad_stochastic_settings_name_their_field() {
        let rule = |error: f32, accumulate: u32, seeds: u32| LightSpec {
            radius: RadiusRule::Stochastic {
                error,
                bound: StochasticBound::Light,
                exposure: 1.0,
                accumulate,
                seeds,
                interleave: 1,
                draw: StochasticDraw::Stratified,
            },
            ..LightSpec::default()
        };
        let interleaved = |interleave: u32| LightSpec {
            radius: RadiusRule::Stochastic {
                error: 0.1,
                bound: StochasticBound::Light,
                exposure: 1.0,
                accumulate: 0,
                seeds: 4,
                interleave,
                draw: StochasticDraw::Stratified,
            },
            ..LightSpec::default()
        };
        for (spec, field) in [
            (rule(0.0, 0, 4), "lights.radius.error = 0"),
            (rule(-1.0, 0, 4), "lights.radius.error = -1"),
            (rule(f32::NAN, 0, 4), "lights.radius.error = NaN"),
            (rule(f32::INFINITY, 0, 4), "lights.radius.error = inf"),
            (rule(0.1, 1, 4), "lights.radius.accumulate = 1"),
            (rule(0.1, 0, 0), "lights.radius.seeds = 0"),
            (interleaved(0), "lights.radius.interleave = 0"),
            (interleaved(9), "lights.radius.interleave = 9"),
        ] {
            let e = spec.validate().unwrap_err().to_string();
            assert!(e.contains(field), "{e}");
        }
        assert!(rule(0.1, 4, 1).validate().is_ok());
        assert!(rule(0.1, 0, 4).validate().is_ok());
        assert!(interleaved(8).validate().is_ok());
        // Interleave 1 is left out of the serialised form (cell identifiers stay), and read
        // back as the default.
        let text = ron::to_string(&rule(0.1, 0, 4).radius).unwrap();
        assert!(!text.contains("interleave"), "{text}");
        let back: RadiusRule = ron::from_str("Stochastic(error: 0.1)").unwrap();
        assert_eq!(back, rule(0.1, 0, 4).radius);
        let text = ron::to_string(&interleaved(2).radius).unwrap();
        assert!(text.contains("interleave:2"), "{text}");
        // The bound likewise: `Light` left out, `Albedo` named.
        assert!(!text.contains("bound"), "{text}");
        let back: RadiusRule = ron::from_str("Stochastic(error: 0.1, bound: Albedo)").unwrap();
        assert!(matches!(
            back,
            RadiusRule::Stochastic {
                bound: StochasticBound::Albedo,
                ..
            }
        ));
        assert!(ron::to_string(&back).unwrap().contains("bound:Albedo"));
        let e = ron::from_str::<RadiusRule>("Stochastic(error: 0.1, bound: Peak)").unwrap_err();
        assert!(e.to_string().contains("Light"), "{e}");
        // The draw likewise: `Stratified` left out, `Independent` named.
        assert!(!text.contains("draw"), "{text}");
        let back: RadiusRule = ron::from_str("Stochastic(error: 0.1, draw: Independent)").unwrap();
        assert!(matches!(
            back,
            RadiusRule::Stochastic {
                draw: StochasticDraw::Independent,
                ..
            }
        ));
        assert!(ron::to_string(&back).unwrap().contains("draw:Independent"));
        let e = ron::from_str::<RadiusRule>("Stochastic(error: 0.1, draw: Sobol)").unwrap_err();
        assert!(e.to_string().contains("Stratified"), "{e}");
    }

    /// The hierarchy's alpha is any finite value above 0 (below the papers' 1 too), its
    /// spacing any finite one above 0; bad ones name their field.
    #[test]
    fn bad_hierarchy_settings_name_their_field() {
        let rule = |alpha: f32, spacing: f32| LightSpec {
            radius: RadiusRule::Hierarchy {
                alpha,
                spacing,
                finest_nodes: 2.0,
                sample_from: None,
            },
            ..LightSpec::default()
        };
        let nodes = |finest_nodes: f32| LightSpec {
            radius: RadiusRule::Hierarchy {
                alpha: 1.0,
                spacing: 0.25,
                finest_nodes,
                sample_from: None,
            },
            ..LightSpec::default()
        };
        for (spec, field) in [
            (nodes(0.0), "lights.radius.finest_nodes = 0"),
            (nodes(f32::NAN), "lights.radius.finest_nodes = NaN"),
            (rule(0.0, 0.25), "lights.radius.alpha = 0"),
            (rule(-1.0, 0.25), "lights.radius.alpha = -1"),
            (rule(f32::NAN, 0.25), "lights.radius.alpha = NaN"),
            (rule(f32::INFINITY, 0.25), "lights.radius.alpha = inf"),
            (rule(1.0, 0.0), "lights.radius.spacing = 0"),
        ] {
            let e = spec.validate().unwrap_err().to_string();
            assert!(e.contains(field) && e.contains("> 0"), "{e}");
        }
        for alpha in [0.5, 0.8, 1.0, 4.0] {
            assert!(rule(alpha, 0.25).validate().is_ok(), "{alpha}");
        }
        assert!(nodes(0.25).validate().is_ok());
        // The default is left out of the serialised form (cell identifiers stay), and read
        // back; another value is named.
        let text = ron::to_string(&rule(1.0, 0.25).radius).unwrap();
        assert!(!text.contains("finest_nodes"), "{text}");
        let back: RadiusRule = ron::from_str("Hierarchy(alpha: 1.0, spacing: 0.25)").unwrap();
        assert_eq!(back, rule(1.0, 0.25).radius);
        let text = ron::to_string(&nodes(0.25).radius).unwrap();
        assert!(text.contains("finest_nodes:0.25"), "{text}");
    }

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
    }
}
