//! The lighting grid hierarchy (C. Yuksel and C. Yuksel, "Lighting Grid Hierarchy for
//! Self-illuminating Explosions", TOG 36(4), 2017; D. Lin and C. Yuksel, "Real-Time Rendering
//! with Lighting Grid Hierarchy", I3D 2019), in f64: the oracle of the hierarchy light model
//! (issue 48). A shading point takes the lights near it as they are and far ones from coarse
//! aggregates, so every light it evaluates is a sphere of bounded range and the estimate is
//! deterministic, with a bias that shrinks as `alpha` grows.
//!
//! Levels, with `h` the spacing and `r_l = alpha h 2^l`:
//! - level 0 is the point lights themselves;
//! - level `l >= 1` holds lights on the grid of spacing `h 2^(l-1)`, with nodes at integer
//!   multiples of it in world space (so the grids nest and a light that moves changes only its
//!   own nodes). Every light of level `l - 1` spreads its power (colour x intensity) to the 8
//!   nodes of the cell it lies in with trilinear weights; a node's light sits at the mean of the
//!   positions it gathered, weighted by trilinear weight times power (the sum of the power's
//!   channels), and carries the weighted sum of their powers. Each level is formed from the
//!   level below, as the papers describe it (the authors' implementation, cyCodeBase
//!   `cyLightingGrid.h`, gathers every level from the point lights, and weights positions by
//!   the trilinear weight alone): a level's work is its own lights, so the GPU build
//!   (`manylights_gpu::hierarchy`) costs the point lights once and a third of them more.
//! - the finest grid kept is the first, from the given spacing up by doublings, that holds at
//!   most `finest_nodes` times as many lights as there are point lights, and `h` is its
//!   spacing. The authors' implementation skips finer grids the same way with a quarter;
//!   [`FINEST_NODES`], 2, keeps a grid one or two doublings finer, which evaluates a third
//!   fewer lights a point at the same error in this workspace's scenes (the point lights' band,
//!   `2 alpha h`, holds fewer of them; the levels above are the same grids): see
//!   docs/STRATEGIES.md, "The lighting grid hierarchy";
//! - levels are added until one holds at most `top_lights` lights, or the next would hold no
//!   fewer (a grid much coarser than the lights' spread keeps the 8 to 27 nodes around them):
//!   that is the last level.
//!
//! [`Hierarchy::build`] chooses `h` and the number of levels from the lights;
//! [`Hierarchy::build_fixed`] takes them, as the GPU build does every frame with those of the
//! first frame (so moving lights keep the hierarchy's shape).
//!
//! Blending (the implementation's, a partition of unity over the levels at every distance `d`
//! from a level's light): level 0 has weight 1 up to `r_0`, falling linearly to 0 at `2 r_0`;
//! a middle level `l` rises linearly from 0 at `r_(l-1)` to 1 at `r_l` and falls to 0 at
//! `2 r_l = r_(l+1)`; the last level rises from `r_(l-1)` to `r_l` and stays 1 beyond. So a
//! level's light is a sphere of range `2 r_l` (the last level's unbounded) that contributes
//! nothing inside `r_(l-1)`; adjacent levels' weights sum to 1, so a single light, which every
//! level places at its own position with its whole power, is exact at every distance.
//!
//! Spot lights are not aggregated: they stay as they are, with their cones, at every distance
//! (weight 1 at every level's band; what a spot-heavy scene costs is theirs).

use std::collections::BTreeMap;

use glam::DVec3;

use crate::Material;
use crate::light::{Light, LightKind, falloff_infinite, shade_with};

mod band;
pub use band::{Band, band_xi, node_draw};

/// The most lights the last level holds by default: what the experiments' and the command
/// line's hierarchies are built with.
pub const TOP_LIGHTS: usize = 64;

/// The finest grid holds at most this many nodes a point light by default
/// ([`HierarchyParams::finest_nodes`]; the authors' implementation: 0.25).
pub const FINEST_NODES: f64 = 2.0;

/// The hierarchy's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HierarchyParams {
    /// The accuracy parameter: level `l`'s band ends at `2 alpha h 2^l`. Above 0; the papers
    /// use 1 and more. Below 1 a level's aggregates are taken from the distance of its own
    /// grid's spacing inwards, nearer than the lights they gather may lie: fewer lights a point,
    /// a bias that grows fast.
    pub alpha: f64,
    /// The finest grid's spacing `h`, metres, at least: it doubles while the grid would hold
    /// more than `finest_nodes` times as many lights as there are point lights.
    pub spacing: f64,
    /// The most nodes the finest grid may hold a point light ([`FINEST_NODES`] by default;
    /// the authors' 0.25 keeps coarser grids), above 0.
    pub finest_nodes: f64,
    /// The last level holds at most this many lights.
    pub top_lights: usize,
    /// Stochastic band selection from this level on (issue 48, item 4): each of these levels'
    /// lights draws its band afresh each frame ([`Band::sampled`]), weight 1 inside it, so the
    /// estimate is the hierarchy's on average and its lists shorter. `None`: every band as it
    /// is. Spots are never sampled.
    pub sample_from: Option<usize>,
}

/// A light of a level: its position and its power (colour x intensity).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelLight {
    /// Where it is: a point light's position, or an aggregate's power-weighted mean.
    pub position: DVec3,
    /// Its power: a point light's colour x intensity, or the weighted sum of those gathered.
    pub power: DVec3,
}

/// The hierarchy of a set of lights.
#[derive(Clone, Debug)]
pub struct Hierarchy {
    /// What it was built with.
    pub params: HierarchyParams,
    /// The finest grid's spacing: `params.spacing`, doubled while the grid held more than
    /// `params.finest_nodes` times as many lights as there are point lights.
    pub h: f64,
    /// `levels[0]`: the point lights; `levels[l]`: the aggregates on the grid of spacing
    /// `h 2^(l-1)`, in the order of their nodes (z, then y, then x, ascending).
    pub levels: Vec<Vec<LevelLight>>,
    /// The spot lights, as they are.
    pub spots: Vec<Light>,
}

/// Levels at most (a level's grid doubles its spacing, so 2^24 h spans any scene).
const MAX_LEVELS: usize = 24;

fn power(light: &Light) -> DVec3 {
    light.color.as_dvec3() * f64::from(light.intensity)
}

/// The point lights as level 0's lights, and the spots as they are.
fn split(lights: &[Light]) -> (Vec<LevelLight>, Vec<Light>) {
    let points = lights
        .iter()
        .filter(|l| matches!(l.kind, LightKind::Point))
        .map(|l| LevelLight {
            position: l.position.as_dvec3(),
            power: power(l),
        })
        .collect();
    let spots = lights
        .iter()
        .filter(|l| matches!(l.kind, LightKind::Spot { .. }))
        .copied()
        .collect();
    (points, spots)
}

/// One level's lights: every light of the level below spread over the 8 nodes of its cell of
/// `spacing`, in the order of their nodes (z, then y, then x).
fn level(points: &[LevelLight], spacing: f64) -> Vec<LevelLight> {
    // Per node: the weights' sum (trilinear x power), the weighted position and the power.
    let mut nodes: BTreeMap<(i64, i64, i64), (f64, DVec3, DVec3)> = BTreeMap::new();
    for l in points {
        let u = l.position / spacing;
        let base = u.floor();
        let f = u - base;
        let scalar = l.power.x + l.power.y + l.power.z;
        for corner in 0..8 {
            let pick = |bit: usize, t: f64| if corner & bit != 0 { t } else { 1.0 - t };
            let w = pick(1, f.x) * pick(2, f.y) * pick(4, f.z);
            if w == 0.0 {
                continue;
            }
            let key = (
                base.z as i64 + i64::from(corner & 4 != 0),
                base.y as i64 + i64::from(corner & 2 != 0),
                base.x as i64 + i64::from(corner & 1 != 0),
            );
            let n = nodes.entry(key).or_insert((0.0, DVec3::ZERO, DVec3::ZERO));
            n.0 += w * scalar;
            n.1 += w * scalar * l.position;
            n.2 += w * l.power;
        }
    }
    nodes
        .into_values()
        .filter(|(weight, _, _)| *weight > 0.0)
        .map(|(weight, position, power)| LevelLight {
            position: position / weight,
            power,
        })
        .collect()
}

impl Hierarchy {
    /// The hierarchy of `lights` (their point lights aggregated, their spots kept).
    pub fn build(lights: &[Light], params: HierarchyParams) -> Hierarchy {
        let (points, spots) = split(lights);
        // The finest grid kept is the first with at most `finest_nodes` times as many lights
        // as there are point lights, as the authors' implementation skips finer ones (with a
        // quarter): `h` doubles until then (or until a grid is the last level's).
        let mut h = params.spacing;
        let mut first = level(&points, h);
        let mut doublings = 0;
        while first.len() as f64 > params.finest_nodes * points.len() as f64
            && first.len() > params.top_lights
            && doublings < MAX_LEVELS
        {
            h *= 2.0;
            doublings += 1;
            first = level(&points, h);
        }
        let mut levels = vec![points];
        if levels[0].len() > params.top_lights {
            levels.push(first);
        }
        while levels.last().unwrap().len() > params.top_lights && levels.len() < MAX_LEVELS {
            let spacing = h * f64::from(1u32 << (levels.len() - 1));
            let next = level(levels.last().unwrap(), spacing);
            // Grids coarser than the lights' spread stop shrinking (the lights' cells around a
            // grid line keep their 8 to 27 nodes): the level before is the last.
            if next.len() >= levels.last().unwrap().len() && levels.len() > 1 {
                break;
            }
            levels.push(next);
        }
        Hierarchy {
            params,
            h,
            levels,
            spots,
        }
    }

    /// The hierarchy of `lights` with the finest spacing `h` and `levels` levels (the point
    /// lights and `levels - 1` grids) given, as [`Hierarchy::build`] chose them for other
    /// lights: the GPU build's oracle, whose shape is fixed at its first frame.
    pub fn build_fixed(
        lights: &[Light],
        params: HierarchyParams,
        h: f64,
        levels: usize,
    ) -> Hierarchy {
        let (points, spots) = split(lights);
        let mut all = vec![points];
        while all.len() < levels.clamp(1, MAX_LEVELS) {
            let spacing = h * f64::from(1u32 << (all.len() - 1));
            all.push(level(all.last().unwrap(), spacing));
        }
        Hierarchy {
            params,
            h,
            levels: all,
            spots,
        }
    }

    /// `r_l = alpha h 2^l`, `h` the finest grid's spacing ([`Hierarchy::h`]).
    pub fn r(&self, level: usize) -> f64 {
        self.params.alpha * self.h * f64::from(1u32 << level)
    }

    /// Level `level`'s weight at distance `d` from one of its lights (as its [`Band`] has it).
    pub fn band(&self, level: usize, d: f64) -> f64 {
        let last = self.levels.len() - 1;
        if last == 0 {
            return 1.0;
        }
        let r = self.r(level);
        let rising = if level == 0 {
            1.0
        } else {
            let r_min = self.r(level - 1);
            if d <= r_min {
                return 0.0;
            }
            ((d - r_min) / r_min).min(1.0)
        };
        let falling = if level == last {
            1.0
        } else {
            (2.0 - d / r).clamp(0.0, 1.0)
        };
        rising.min(falling)
    }

    /// The sphere of level `level`'s lights: what they reach (`None`: unbounded, the last
    /// level) and the distance inside which they contribute nothing.
    pub fn sphere(&self, level: usize) -> (Option<f64>, f64) {
        let last = self.levels.len() - 1;
        let outer = (level < last).then(|| 2.0 * self.r(level));
        let inner = if level == 0 { 0.0 } else { self.r(level - 1) };
        (outer, inner)
    }

    /// The hierarchy's estimate at `x` of `sum f(light, d) power`, over every level's light
    /// with its weight (`f` the falloff and whatever the shading multiplies in), and the spots
    /// as they are (`spot` evaluates one).
    pub fn estimate(
        &self,
        x: DVec3,
        f: impl Fn(&LevelLight, f64) -> DVec3,
        spot: impl Fn(&Light) -> DVec3,
    ) -> DVec3 {
        let mut sum = DVec3::ZERO;
        for (level, lights) in self.levels.iter().enumerate() {
            for l in lights {
                let d = x.distance(l.position);
                let w = self.band(level, d);
                if w > 0.0 {
                    sum += w * f(l, d);
                }
            }
        }
        sum + self.spots.iter().map(spot).sum::<DVec3>()
    }

    /// Each level's total power.
    pub fn level_power(&self) -> Vec<DVec3> {
        self.levels
            .iter()
            .map(|l| l.iter().map(|l| l.power).sum())
            .collect()
    }
}

impl Hierarchy {
    /// Every light of every level and every spot as a light of the scene model, each with its
    /// band: point lights of colour `power` and intensity 1 whose radius is the band's reach,
    /// at most `reach`, then the spots as they are with radius `reach`. `reach` is where no
    /// surface lies farther from any light ([`reach`]): an unbounded band ends there with
    /// nothing lost, and every radius stays finite for culling.
    pub fn flatten(&self, reach: f32) -> (Vec<Light>, Vec<Band>) {
        let last = self.levels.len() - 1;
        let mut lights = Vec::new();
        let mut bands = Vec::new();
        for (level, ls) in self.levels.iter().enumerate() {
            let band = Band::new(
                if level == 0 { 0.0 } else { self.r(level - 1) },
                if level == last {
                    f64::INFINITY
                } else {
                    self.r(level)
                },
            );
            for l in ls {
                lights.push(Light::point(
                    l.position.as_vec3(),
                    (band.outer() as f32).min(reach),
                    l.power.as_vec3(),
                    1.0,
                ));
                bands.push(band);
            }
        }
        for s in &self.spots {
            lights.push(Light {
                radius: reach,
                ..*s
            });
            bands.push(Band::new(0.0, f64::INFINITY));
        }
        (lights, bands)
    }
}

/// A distance no surface point of `scene` lies from any of its lights or any aggregate of them
/// (which lie in the lights' convex hull): the diagonal of the box around its geometry and
/// lights, with a margin.
pub fn reach(scene: &crate::Scene) -> f32 {
    let b = scene
        .lights
        .iter()
        .fold(scene.bounds(), |b, l| b.union_point(l.position));
    (b.max - b.min).length() * 1.01 + 1.0
}

/// Outgoing radiance at `p` (unit normal `n`, towards the unit direction `v`) under the
/// hierarchy's estimate, in f64: the shading model of [`crate::light::shade`] over the
/// flattened lights, each light's falloff `1 / d^2` times its band's weight. The statement every
/// strategy and backend shading the hierarchy is tested against.
pub fn shade(
    p: DVec3,
    n: DVec3,
    v: DVec3,
    material: &Material,
    lights: &[Light],
    bands: &[Band],
) -> DVec3 {
    shade_with(p, n, v, material, lights, |k, _, d| {
        bands[k].weight(d) * falloff_infinite(d)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::falloff_infinite;
    use glam::Vec3;

    fn rng(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    fn lights(n: usize, extent: f64, seed: u64) -> Vec<Light> {
        let mut r = rng(seed);
        (0..n)
            .map(|_| {
                let p = Vec3::new(
                    (r() * extent) as f32,
                    (r() * extent * 0.3) as f32,
                    (r() * extent) as f32,
                );
                let c = Vec3::new(0.2 + r() as f32, 0.2 + r() as f32, 0.2 + r() as f32);
                Light::point(p, 1.0, c, (0.5 + 2.0 * r()) as f32)
            })
            .collect()
    }

    fn params(alpha: f64) -> HierarchyParams {
        HierarchyParams {
            alpha,
            spacing: 0.5,
            finest_nodes: 0.25,
            top_lights: 16,
            sample_from: None,
        }
    }

    /// The infinite-range sum of the lights' power times the inverse-square falloff.
    fn exact(lights: &[Light], x: DVec3) -> DVec3 {
        lights
            .iter()
            .map(|l| power(l) * falloff_infinite(x.distance(l.position.as_dvec3())))
            .sum()
    }

    fn estimate(h: &Hierarchy, x: DVec3) -> DVec3 {
        h.estimate(x, |l, d| l.power * falloff_infinite(d), |_| DVec3::ZERO)
    }

    #[test]
    fn every_level_holds_the_lights_whole_power() {
        let ls = lights(3000, 60.0, 1);
        let h = Hierarchy::build(&ls, params(2.0));
        assert!(h.levels.len() >= 4, "{} levels", h.levels.len());
        assert!(h.levels.last().unwrap().len() <= 16);
        let total: DVec3 = ls.iter().map(power).sum();
        for (l, p) in h.level_power().iter().enumerate() {
            assert!(
                (*p - total).abs().max_element() < 1e-9 * total.max_element(),
                "level {l}"
            );
        }
        // Coarser grids hold fewer lights (the finest may hold more than the point lights:
        // up to 8 nodes a light where the spacing is small against their spread).
        for w in h.levels[1..].windows(2) {
            assert!(w[1].len() < w[0].len());
        }
    }

    /// The fixed-shape build (the GPU's oracle) with `build`'s spacing and levels is `build`;
    /// with moved lights it keeps the shape and still holds the whole power at every level.
    #[test]
    fn a_fixed_shape_build_is_the_build_and_keeps_its_shape() {
        let ls = lights(2000, 40.0, 5);
        let h = Hierarchy::build(&ls, params(2.0));
        let f = Hierarchy::build_fixed(&ls, h.params, h.h, h.levels.len());
        assert_eq!(f.levels, h.levels);
        let moved: Vec<Light> = ls
            .iter()
            .map(|l| Light {
                position: l.position + glam::Vec3::new(3.0, -1.0, 0.5),
                ..*l
            })
            .collect();
        let m = Hierarchy::build_fixed(&moved, h.params, h.h, h.levels.len());
        assert_eq!(m.levels.len(), h.levels.len());
        let total: DVec3 = ls.iter().map(power).sum();
        for p in m.level_power() {
            assert!((p - total).abs().max_element() < 1e-9 * total.max_element());
        }
    }

    #[test]
    fn the_blending_weights_sum_to_one_at_every_distance() {
        let h = Hierarchy::build(&lights(3000, 60.0, 2), params(1.5));
        let n = h.levels.len();
        for k in 0..20_000 {
            let d = k as f64 * 0.01;
            let sum: f64 = (0..n).map(|l| h.band(l, d)).sum();
            assert!((sum - 1.0).abs() < 1e-12, "d {d}: {sum}");
            for l in 0..n {
                let (outer, inner) = h.sphere(l);
                if outer.is_some_and(|o| d >= o) || (l > 0 && d <= inner) {
                    assert_eq!(h.band(l, d), 0.0, "level {l} at {d} outside its sphere");
                }
            }
        }
    }

    #[test]
    fn a_single_light_is_exact_at_every_distance() {
        for p in [Vec3::new(0.3, 1.7, -2.2), Vec3::new(100.25, -3.0, 7.5)] {
            let ls = [Light::point(p, 1.0, Vec3::new(1.0, 0.5, 0.25), 3.0)];
            // Every level there may be.
            let pr = params(1.0);
            let h = Hierarchy::build_fixed(&ls, pr, pr.spacing, MAX_LEVELS);
            assert_eq!(h.levels.len(), MAX_LEVELS);
            for k in 0..400 {
                let d = 0.05 * 1.03f64.powi(k);
                let x = p.as_dvec3() + DVec3::new(0.6, -0.48, 0.64) * d;
                let (e, got) = (exact(&ls, x), estimate(&h, x));
                assert!(
                    (got - e).abs().max_element() <= 1e-9 * e.max_element(),
                    "at {d}: {got} against {e}"
                );
            }
        }
    }

    /// The flattened lights shade what the estimate sums, band for band, and their bands are
    /// the levels'; a scene of one point light and one spot shades as the lights do at
    /// infinite range.
    #[test]
    fn the_flattened_lights_shade_the_estimate() {
        use crate::light::{Range, shade as shade_lights};
        let ls = lights(1500, 30.0, 6);
        let h = Hierarchy::build(&ls, params(2.0));
        let (flat, bands) = h.flatten(1e6);
        assert_eq!(flat.len(), h.levels.iter().map(Vec::len).sum::<usize>());
        let mut k = 0;
        for (level, l) in h.levels.iter().enumerate() {
            for _ in l {
                for d in [0.0, 0.7, 1.3, 2.9, 6.1, 13.0, 40.0] {
                    assert_eq!(bands[k].weight(d), h.band(level, d), "level {level} at {d}");
                }
                let (outer, _) = h.sphere(level);
                assert_eq!(outer.unwrap_or(f64::INFINITY), bands[k].outer());
                k += 1;
            }
        }
        let material = Material::new(Vec3::new(0.7, 0.6, 0.5), 0.3);
        let mut r = rng(7);
        for _ in 0..50 {
            let p = DVec3::new(r() * 30.0, 0.0, r() * 30.0);
            let (n, v) = (DVec3::Y, DVec3::new(0.0, 0.8, 0.6));
            let lambert = shade(p, n, v, &material, &flat, &bands);
            let sum = h.estimate(
                p,
                |l, d| {
                    let to = (l.position - p) / d;
                    l.power
                        * falloff_infinite(d)
                        * crate::brdf::brdf_cos(
                            &material.brdf,
                            material.base_color.as_dvec3(),
                            n,
                            to,
                            v,
                        )
                },
                |_| DVec3::ZERO,
            ) + material.emissive.as_dvec3();
            // The flattened lights are the scene model's, in f32.
            assert!(
                (lambert - sum).abs().max_element() <= 1e-5 * sum.max_element(),
                "{lambert} against {sum}"
            );
        }
        let mut two = vec![Light::point(Vec3::new(1.0, 2.0, 3.0), 1.0, Vec3::ONE, 2.0)];
        two.push(Light {
            kind: LightKind::Spot {
                direction: Vec3::NEG_Y,
                inner_angle: 0.3,
                outer_angle: 0.6,
            },
            ..Light::point(Vec3::new(4.0, 3.0, 1.0), 1.0, Vec3::ONE, 5.0)
        });
        let h = Hierarchy::build(
            &two,
            HierarchyParams {
                top_lights: 0,
                sample_from: None,
                ..params(1.0)
            },
        );
        let (flat, bands) = h.flatten(1e6);
        for x in [0.5, 3.0, 9.0, 27.0, 81.0] {
            let p = DVec3::new(x, 0.0, 2.0);
            let (n, v) = (DVec3::Y, DVec3::Y);
            let want = shade_lights(p, n, v, &material, &two, Range::Infinite);
            let got = shade(p, n, v, &material, &flat, &bands);
            assert!(
                (got - want).abs().max_element() <= 1e-9 * want.max_element(),
                "{x}"
            );
        }
    }

    #[test]
    fn the_error_falls_as_alpha_grows() {
        let ls = lights(2000, 40.0, 4);
        let mut r = rng(5);
        let xs: Vec<DVec3> = (0..300)
            .map(|_| DVec3::new(r() * 40.0, r() * 12.0, r() * 40.0))
            .collect();
        let error = |alpha: f64| {
            let h = Hierarchy::build(&ls, params(alpha));
            xs.iter()
                .map(|&x| {
                    let (e, got) = (exact(&ls, x), estimate(&h, x));
                    ((got - e).abs() / e).element_sum() / 3.0
                })
                .sum::<f64>()
                / xs.len() as f64
        };
        // Below the papers' 1 as well.
        let errors: Vec<f64> = [0.5, 0.75, 1.0, 2.0, 4.0, 8.0, 16.0].map(error).to_vec();
        for w in errors.windows(2) {
            assert!(w[1] < w[0], "{errors:?}");
        }
        assert!(errors[6] < 1e-4 && errors[2] > 1e-3, "{errors:?}");
    }
}
