//! The lighting grid hierarchy (C. Yuksel and C. Yuksel, "Lighting Grid Hierarchy for
//! Self-illuminating Explosions", TOG 36(4), 2017; D. Lin and C. Yuksel, "Real-Time Rendering
//! with Lighting Grid Hierarchy", I3D 2019), in f64: the oracle of the hierarchy light model.
//! A shading point takes the lights near it as they are and far ones from coarse
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
//! Spot lights are level 0's lights too (with its band) and are aggregated with their flux
//! ([`spots`]): by default into the point lights' nodes (an aggregate emits what its spots do,
//! spread over every direction), or, with direction bins, into nodes of their own bin in every
//! level's grid (a node keyed by its bin and its place), shaded as spots of the bin's cone, so
//! that a lone spot stays exact at every distance. Either way a spot far away is lit through
//! its level's aggregate as a point light is.

use std::collections::BTreeMap;

use glam::DVec3;

use crate::Material;
use crate::light::{Light, LightKind, falloff_infinite, shade_with};

mod band;
pub mod spots;
pub use band::{Band, band_xi, node_draw};
pub use spots::{SpotBin, spot_bins};

/// The most lights the last level holds by default: what the experiments' and the command
/// line's hierarchies are built with.
pub const TOP_LIGHTS: usize = 64;

/// How much farther, in its grid's units, each level takes over from the one below than the
/// level below did, by default ([`HierarchyParams::growth`]; the papers' bands: 1).
pub const GROWTH: f64 = 1.0;

/// How far each band's ramps run by default ([`HierarchyParams::ramp`]): from a level's `r` to
/// twice it, the papers' bands.
pub const RAMP: f64 = 2.0;

/// The spots' direction bins by default ([`HierarchyParams::spot_bins`]): none, every spot
/// spread into the point lights' nodes with its flux (an isotropic far field at a point
/// light's cost; bins multiply the aggregates, [`spots`]).
pub const SPOT_BINS: u32 = 0;

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
    /// `r_l = alpha h (2 growth)^l`: each level's band ends `growth` times farther in its
    /// grid's units than the level below's ([`GROWTH`], 1, the papers' bands; at least 1, so
    /// that a level is whole before the next rises). Above 1 a level's weight stays 1 from
    /// `2 r_(l-1)` to `r_l`, and the coarse levels, whose aggregates carry the most power, are
    /// taken from farther in their grids' units (crates/scene/examples/band_schedule.rs).
    pub growth: f64,
    /// Each level hands over to the next from `r_l` to `ramp r_l` ([`RAMP`], 2, the papers';
    /// in (1, 2]): narrower ramps shade fewer lights of both levels and lose the blend's
    /// smoothing (crates/scene/examples/band_schedule.rs).
    pub ramp: f64,
    /// The last level holds at most this many lights.
    pub top_lights: usize,
    /// Stochastic band selection from this level on: each of these levels'
    /// lights draws its band afresh each frame ([`Band::sampled`]), weight 1 inside it, so the
    /// estimate is the hierarchy's on average and its lists shorter. `None`: every band as it
    /// is. Spots and their aggregates are sampled as the point lights and theirs are.
    pub sample_from: Option<usize>,
    /// The spots' direction bins: 0 ([`SPOT_BINS`], the default), none: every spot spreads
    /// into the point lights' nodes with its flux; `n >= 1`: the cells along each side of
    /// an octahedral map of their axes, each bin's aggregates spots of its cone. More bins
    /// keep narrower cones and put more aggregates in every level.
    pub spot_bins: u32,
}

impl HierarchyParams {
    /// `r_l = alpha h (2 growth)^l` for the finest spacing `h`.
    pub fn r(&self, h: f64, level: usize) -> f64 {
        self.alpha * h * (2.0 * self.growth).powi(level as i32)
    }
}

/// A light of a level: its position, its power (colour x intensity) and its direction bin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelLight {
    /// Where it is: a point light's position, or an aggregate's power-weighted mean.
    pub position: DVec3,
    /// Its power: a point light's colour x intensity, or the weighted sum of those gathered
    /// (a spot's scaled to its bin's cone, [`spots::binned_power`]).
    pub power: DVec3,
    /// 0: a point light or an aggregate of them; `b >= 1`: an aggregate of the spots of
    /// direction bin `b` ([`Hierarchy::bins`]`[b - 1]`), shaded with its cone.
    pub bin: u32,
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
    /// `h 2^(l-1)`, in the order of their bins and then of their nodes (z, then y, then x,
    /// ascending).
    pub levels: Vec<Vec<LevelLight>>,
    /// The spot lights, as they are: level 0's too, after its point lights.
    pub spots: Vec<Light>,
    /// The spots' direction bins ([`spots`]): the cones of their aggregates.
    pub bins: Vec<SpotBin>,
}

/// Levels at most (a level's grid doubles its spacing, so 2^24 h spans any scene).
const MAX_LEVELS: usize = 24;

fn power(light: &Light) -> DVec3 {
    light.color.as_dvec3() * f64::from(light.intensity)
}

/// Level 0 split: the point lights as level 0's lights, the spots as they are, the spots'
/// bins, and what level 1 gathers (the point lights, then every spot with its bin and its
/// power scaled to the bin's cone).
struct Split {
    points: Vec<LevelLight>,
    spots: Vec<Light>,
    bins: Vec<SpotBin>,
    gathered: Vec<LevelLight>,
}

fn split(lights: &[Light], spot_bins: u32) -> Split {
    let points: Vec<LevelLight> = lights
        .iter()
        .filter(|l| matches!(l.kind, LightKind::Point))
        .map(|l| LevelLight {
            position: l.position.as_dvec3(),
            power: power(l),
            bin: 0,
        })
        .collect();
    let (bins, of) = spots::spot_bins(lights, spot_bins);
    let mut gathered = points.clone();
    let mut spots = Vec::new();
    for (l, &b) in lights.iter().zip(&of) {
        if matches!(l.kind, LightKind::Spot { .. }) {
            spots.push(*l);
            gathered.push(LevelLight {
                position: l.position.as_dvec3(),
                power: spots::binned_power(l, b.checked_sub(1).map(|b| &bins[b as usize])),
                bin: b,
            });
        }
    }
    Split {
        points,
        spots,
        bins,
        gathered,
    }
}

/// One level's lights: every light of the level below spread over the 8 nodes of its cell of
/// `spacing` in its bin, in the order of their bins and nodes (z, then y, then x).
fn level(points: &[LevelLight], spacing: f64) -> Vec<LevelLight> {
    // Per node: the weights' sum (trilinear x power), the weighted position and the power.
    let mut nodes: BTreeMap<(u32, i64, i64, i64), (f64, DVec3, DVec3)> = BTreeMap::new();
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
                l.bin,
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
        .into_iter()
        .filter(|(_, (weight, _, _))| *weight > 0.0)
        .map(|((bin, ..), (weight, position, power))| LevelLight {
            position: position / weight,
            power,
            bin,
        })
        .collect()
}

/// The nodes `lights` spread into on the grid of `spacing`, counted by place over every bin:
/// [`level`]'s lights where every light is of one bin.
fn node_count(lights: &[LevelLight], spacing: f64) -> usize {
    let one: Vec<LevelLight> = lights.iter().map(|l| LevelLight { bin: 0, ..*l }).collect();
    level(&one, spacing).len()
}

impl Hierarchy {
    /// The hierarchy of `lights` (their point lights aggregated, their spots by direction).
    pub fn build(lights: &[Light], params: HierarchyParams) -> Hierarchy {
        let Split {
            points,
            spots,
            bins,
            gathered,
        } = split(lights, params.spot_bins);
        // The finest grid kept is the first with at most `finest_nodes` times as many nodes
        // as level 0 has lights, as the authors' implementation skips finer ones (with a
        // quarter): `h` doubles until then (or until a grid is the last level's). Nodes are
        // counted by place, over every bin (a grid's spots of many bins hold one place each
        // in its count, so the bins do not make the grids coarser).
        let mut h = params.spacing;
        let mut first = node_count(&gathered, h);
        let mut doublings = 0;
        while first as f64 > params.finest_nodes * gathered.len() as f64
            && first > params.top_lights
            && doublings < MAX_LEVELS
        {
            h *= 2.0;
            doublings += 1;
            first = node_count(&gathered, h);
        }
        let mut levels = vec![points];
        // Each level's places: level 0's lights, then each grid's nodes by place.
        let mut places = vec![gathered.len()];
        if gathered.len() > params.top_lights {
            levels.push(level(&gathered, h));
            places.push(first);
        }
        while *places.last().unwrap() > params.top_lights && levels.len() < MAX_LEVELS {
            let spacing = h * f64::from(1u32 << (levels.len() - 1));
            let below = levels.last().unwrap();
            let next = node_count(below, spacing);
            // Grids coarser than the lights' spread stop shrinking (the lights' cells around a
            // grid line keep their 8 to 27 nodes): the level before is the last.
            if next >= *places.last().unwrap() && levels.len() > 1 {
                break;
            }
            levels.push(level(below, spacing));
            places.push(next);
        }
        Hierarchy {
            params,
            h,
            levels,
            spots,
            bins,
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
        let Split {
            points,
            spots,
            bins,
            gathered,
        } = split(lights, params.spot_bins);
        let mut all = vec![points];
        while all.len() < levels.clamp(1, MAX_LEVELS) {
            let spacing = h * f64::from(1u32 << (all.len() - 1));
            let below = if all.len() == 1 {
                &gathered
            } else {
                all.last().unwrap()
            };
            all.push(level(below, spacing));
        }
        Hierarchy {
            params,
            h,
            levels: all,
            spots,
            bins,
        }
    }

    /// `r_l = alpha h (2 growth)^l`, `h` the finest grid's spacing ([`Hierarchy::h`]).
    pub fn r(&self, level: usize) -> f64 {
        self.params.r(self.h, level)
    }

    /// Level `level`'s band: from `r_(l-1)` (0 for level 0) to `r_l` (infinite for the last
    /// level), with the parameters' ramps.
    pub fn level_band(&self, level: usize) -> Band {
        let last = self.levels.len() - 1;
        Band::with_ramp(
            if level == 0 { 0.0 } else { self.r(level - 1) },
            if level == last {
                f64::INFINITY
            } else {
                self.r(level)
            },
            self.params.ramp,
        )
    }

    /// Level `level`'s weight at distance `d` from one of its lights (its [`Band`]'s).
    pub fn band(&self, level: usize, d: f64) -> f64 {
        self.level_band(level).weight(d)
    }

    /// The sphere of level `level`'s lights: what they reach (`None`: unbounded, the last
    /// level) and the distance inside which they contribute nothing.
    pub fn sphere(&self, level: usize) -> (Option<f64>, f64) {
        let band = self.level_band(level);
        (band.r.is_finite().then(|| band.outer()), band.inner)
    }

    /// The hierarchy's estimate at `x` of `sum f(light, d) power`, over every level's light
    /// with its weight and, for a spot aggregate, its bin's cone toward `x` (`f` the falloff
    /// and whatever the shading multiplies in), and the spots as they are (`spot` evaluates
    /// one, cone included) with level 0's weight.
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
                    let cone = match l.bin {
                        0 => 1.0,
                        b => self.bins[b as usize - 1]
                            .light(l.position.as_vec3(), 1.0, glam::Vec3::ONE)
                            .cone_toward((l.position - x).normalize_or_zero()),
                    };
                    sum += w * cone * f(l, d);
                }
            }
        }
        for s in &self.spots {
            sum += self.band(0, x.distance(s.position.as_dvec3())) * spot(s);
        }
        sum
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
    /// band: lights of colour `power` and intensity 1 whose radius is the band's reach, at
    /// most `reach` (point lights, and spots of their bin's cone for the spots' aggregates),
    /// then the spots as they are with level 0's band and radius. `reach` is where no surface
    /// lies farther from any light ([`reach`]): an unbounded band ends there with nothing
    /// lost, and every radius stays finite for culling.
    pub fn flatten(&self, reach: f32) -> (Vec<Light>, Vec<Band>) {
        let mut lights = Vec::new();
        let mut bands = Vec::new();
        for (level, ls) in self.levels.iter().enumerate() {
            let band = self.level_band(level);
            let radius = (band.outer() as f32).min(reach);
            for l in ls {
                let (position, power) = (l.position.as_vec3(), l.power.as_vec3());
                lights.push(match l.bin {
                    0 => Light::point(position, radius, power, 1.0),
                    b => self.bins[b as usize - 1].light(position, radius, power),
                });
                bands.push(band);
            }
        }
        let band = self.level_band(0);
        for s in &self.spots {
            lights.push(Light {
                radius: (band.outer() as f32).min(reach),
                ..*s
            });
            bands.push(band);
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
mod tests;
