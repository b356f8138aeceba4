//! The hierarchy's plan: its fixed shape (`HierarchyPlan`: each level's grid box and hash table,
//! the shaded lights' layout) and each build dispatch's parameters (`Step`).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use manylights_scene::hierarchy::{Hierarchy, HierarchyParams, SpotBin};
use manylights_scene::{Light, LightKind, Motion, Scene};

use crate::GpuError;

/// Host mirror of `Step` in `shaders/lights/hierarchy.wgsl` (one dispatch's parameters).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Step {
    /// Mode (0 points, 1 finalize), items, threads a dispatch row, spread (0 none, 1 each item
    /// at once, 2 binned into cells first: [`crate::hierarchy::CELL_ITEMS`]).
    pub a: [u32; 4],
    /// First slot read, first shaded light written, the next level's first slot and slots.
    pub b: [u32; 4],
    /// The level's band r and inner distance, reach, scale.
    pub c: [f32; 4],
    /// The next level's first node and spacing (bits).
    pub d: [i32; 4],
    /// The next level's nodes along each axis.
    pub e: [u32; 4],
    /// This level's first node and spacing (bits).
    pub g: [i32; 4],
    /// This level's nodes along each axis.
    pub h: [u32; 4],
    /// Where dead lights sit; w: infinity.
    pub far: [f32; 4],
    /// The frame's seed, 1 where this level's bands are sampled, the level, the bands' ramp
    /// (bits).
    pub s: [u32; 4],
    /// The points pass: its first source light (its items are the lights from there on) and
    /// the source lights in all (where their direction bins start in the target indices).
    pub o: [u32; 4],
}

/// How the lights a hierarchy is planned for move ([`HierarchyPlan::for_scene`]): the scene's
/// lights from index `first` on, over frames `0..frames`.
#[derive(Clone, Copy, Debug)]
pub struct Moving<'a> {
    /// Their motion.
    pub motion: &'a Motion,
    /// The first light that moves.
    pub first: usize,
    /// The frames they are rendered at.
    pub frames: u32,
    /// The moving lights' anchor normals where the motion reads them (`Motion::uses_anchors`;
    /// else empty: up).
    pub anchors: &'a [glam::Vec3],
}

impl Moving<'_> {
    /// `lights` where the motion puts them at `frame` (as `manylights_gpu::motion` moves them).
    fn lights_at(&self, lights: &[Light], frame: u32) -> Vec<Light> {
        lights
            .iter()
            .enumerate()
            .map(|(i, l)| {
                if i < self.first {
                    *l
                } else {
                    let anchor = self
                        .anchors
                        .get(i - self.first)
                        .copied()
                        .unwrap_or(glam::Vec3::Y);
                    Light {
                        position: self
                            .motion
                            .position_on(i as u32, l.position, l.radius, anchor, frame),
                        ..*l
                    }
                }
            })
            .collect()
    }
}

/// A level's table for `nodes` nodes: `slack` times as many slots (at least 1.25) and 64 more.
fn table_slots(nodes: usize, slack: f64) -> u32 {
    (nodes as f64 * slack.max(1.25)).ceil() as u32 + 64
}

/// A level's grid: its spacing and the box of nodes its table keys.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeBox {
    /// Spacing, metres.
    pub spacing: f32,
    /// The box's first node (integer multiples of the spacing).
    pub first: [i32; 3],
    /// Nodes along each axis.
    pub dims: [u32; 3],
}

/// The hierarchy's fixed shape and the shaded lights' layout.
#[derive(Clone, Debug)]
pub struct HierarchyPlan {
    /// What it is built with.
    pub params: HierarchyParams,
    /// The finest grid's spacing.
    pub h: f64,
    /// Levels (the point lights and the grids).
    pub levels: usize,
    /// Level `l >= 1`'s grid, `grids[l - 1]`.
    pub grids: Vec<NodeBox>,
    /// Level `l >= 1`'s slots (its table's size).
    pub slots: Vec<u32>,
    /// Point lights and spots among the lights.
    pub points: u32,
    /// Spots.
    pub spots: u32,
    /// The spots' direction bins (`Hierarchy::bins`): the cones of their aggregates, fixed
    /// with the plan (motion does not turn a spot).
    pub bins: Vec<SpotBin>,
    /// Where an unbounded band ends (`manylights_scene::hierarchy::reach`).
    pub reach: f32,
    /// Where dead lights sit.
    pub far: Vec3,
    /// The sums' scale: 2^52 over the total power level 1 gathers (the channels' sum: the
    /// point lights' and the spots' scaled to their bins' cones).
    pub scale: f32,
    /// The lights that never move, the scene's first ones (`Moving::first`; all of them where
    /// none moves): the build splats them into level 1 once and keeps those sums, and each
    /// frame's build starts from them and splats only the lights after them
    /// (`crate::hierarchy::GpuHierarchy`). 0 from [`HierarchyPlan::new`]: every light may move.
    pub static_lights: u32,
}

impl HierarchyPlan {
    /// The shape of the hierarchy of `lights` (as `Hierarchy::build` chooses it), its grids'
    /// boxes covering `region` (min, max: where the lights may be, moving ones included), and
    /// tables of `slack` times each level's lights now (at least 1.25; more where lights move).
    pub fn new(
        lights: &[Light],
        params: HierarchyParams,
        region: (Vec3, Vec3),
        reach: f32,
        slack: f64,
    ) -> Result<(Self, Hierarchy), GpuError> {
        let hier = Hierarchy::build(lights, params);
        let mut grids = Vec::new();
        let mut slots = Vec::new();
        for (l, level) in hier.levels.iter().enumerate().skip(1) {
            let spacing = (hier.h * f64::from(1u32 << (l - 1))) as f32;
            let lo = (region.0 / spacing).floor().as_ivec3() - 1;
            let hi = (region.1 / spacing).floor().as_ivec3() + 2;
            let dims = (hi - lo + 1).as_uvec3();
            // A node's key: its index in the box, plus the box's size times its direction bin.
            let nodes = u64::from(dims.x)
                * u64::from(dims.y)
                * u64::from(dims.z)
                * (hier.bins.len() as u64 + 1);
            if nodes >= u64::from(u32::MAX) {
                return Err(GpuError::OverLimit {
                    what: format!(
                        "hierarchy level {l}'s grid nodes ({} x {} x {} at {spacing} m, times \
                         {} direction bins and the point lights')",
                        dims.x,
                        dims.y,
                        dims.z,
                        hier.bins.len()
                    ),
                    value: nodes,
                    limit: u64::from(u32::MAX) - 1,
                    limit_name: "a 32-bit node key (raise the spacing or lower spot_bins)",
                });
            }
            grids.push(NodeBox {
                spacing,
                first: lo.to_array(),
                dims: dims.to_array(),
            });
            slots.push(table_slots(level.len(), slack));
        }
        // What level 1 gathers: its lights' power (a level's whole power, each level's the same).
        let total: f64 = hier
            .levels
            .get(1)
            .unwrap_or(&hier.levels[0])
            .iter()
            .map(|l| l.power.x + l.power.y + l.power.z)
            .sum();
        let plan = Self {
            params,
            h: hier.h,
            levels: hier.levels.len(),
            grids,
            slots,
            points: hier.levels[0].len() as u32,
            spots: hier.spots.len() as u32,
            bins: hier.bins.clone(),
            reach,
            far: region.1 + Vec3::splat(2.0 * reach),
            scale: if total > 0.0 {
                (2f64.powi(52) / total) as f32
            } else {
                1.0
            },
            static_lights: 0,
        };
        Ok((plan, hier))
    }

    /// The shaded lights: points, every level's slots, spots.
    pub fn shaded_count(&self) -> u64 {
        u64::from(self.points)
            + self.slots.iter().map(|&s| u64::from(s)).sum::<u64>()
            + u64::from(self.spots)
    }

    /// Level `level`'s first shaded light and how many it has (slots, for `level >= 1`).
    pub fn level_range(&self, level: usize) -> (u32, u32) {
        if level == 0 {
            return (0, self.points);
        }
        let before: u32 = self.slots[..level - 1].iter().sum();
        (self.points + before, self.slots[level - 1])
    }

    /// The band of level `level`: (r, inner), r infinite for the last level.
    fn band(&self, level: usize) -> (f32, f32) {
        let r = |l: usize| self.params.r(self.h, l) as f32;
        let outer = if level + 1 == self.levels {
            f32::INFINITY
        } else {
            r(level)
        };
        (outer, if level == 0 { 0.0 } else { r(level - 1) })
    }

    /// The plan for `scene`'s lights and the scene to upload in their place: its geometry with
    /// [`HierarchyPlan::placeholder`]'s lights, which the build fills. `moving`: how the
    /// scene's lights from index `first` on move and over how many frames (`None`: they stay
    /// home); the grids' boxes and the unbounded bands' reach cover the farthest any goes from
    /// home (its radius, `manylights_scene::motion`), and each level's table is sized to the
    /// most nodes that level holds at any of those frames (the CPU build of the lights where
    /// the motion puts them), with a quarter more room and 64 slots. The last level holds at
    /// most `params.top_lights` lights.
    pub fn for_scene(
        scene: &Scene,
        params: HierarchyParams,
        moving: Option<Moving<'_>>,
    ) -> Result<(Self, Scene), GpuError> {
        let moving = moving.filter(|m| !m.motion.is_static() && m.frames > 0);
        let farthest = moving.map_or(0.0, |m| {
            scene.lights[m.first.min(scene.lights.len())..]
                .iter()
                .map(|l| l.radius)
                .fold(0.0, f32::max)
        });
        let margin = 1.0 + farthest;
        let b = scene
            .lights
            .iter()
            .fold(scene.bounds(), |b, l| b.union_point(l.position));
        let (mut plan, home) = Self::new(
            &scene.lights,
            params,
            (b.min - margin, b.max + margin),
            manylights_scene::hierarchy::reach(scene) + 2.0 * farthest,
            1.25,
        )?;
        if let Some(m) = moving {
            let mut most: Vec<usize> = home.levels.iter().map(Vec::len).collect();
            for frame in 0..m.frames {
                let moved = m.lights_at(&scene.lights, frame);
                let at = Hierarchy::build_fixed(&moved, params, plan.h, plan.levels);
                for (most, level) in most.iter_mut().zip(&at.levels) {
                    *most = (*most).max(level.len());
                }
            }
            for (slots, &nodes) in plan.slots.iter_mut().zip(&most[1..]) {
                *slots = (*slots).max(table_slots(nodes, 1.25));
            }
        }
        let n = scene.lights.len();
        plan.static_lights = moving.map_or(n, |m| m.first.min(n)) as u32;
        let shaded = Scene {
            lights: plan.placeholder(&scene.lights),
            ..scene.clone()
        };
        Ok((plan, shaded))
    }

    /// The light model to upload the shaded scene with ([`crate::GpuScene::upload_with`]):
    /// the hierarchy's bands over its ramp.
    pub fn light_model(&self) -> crate::LightModel {
        crate::LightModel::hierarchy(self.params.ramp as f32)
    }

    /// Lights to upload as the shaded scene's before the first build: dead point lights in
    /// every slot of the layout, the spots as they are.
    pub fn placeholder(&self, lights: &[Light]) -> Vec<Light> {
        let dead = Light::point(self.far, 0.0, Vec3::ZERO, 0.0);
        let mut out = vec![dead; (self.shaded_count() - u64::from(self.spots)) as usize];
        out.extend(
            lights
                .iter()
                .filter(|l| matches!(l.kind, LightKind::Spot { .. }))
                .map(|l| Light {
                    radius: self.reach,
                    ..*l
                }),
        );
        out
    }

    /// Each dispatch's parameters, in order (the points pass over source lights `points` of
    /// `sources`, then a finalize pass a level); a pass that spreads at least `cell_items`
    /// items into the next level bins them into cells first (spread 2), a smaller one spreads
    /// each at once (1), the last level none (0).
    pub(super) fn steps(
        &self,
        sources: u32,
        points: std::ops::Range<u32>,
        row: impl Fn(u32) -> u32,
        cell_items: u32,
    ) -> Vec<Step> {
        let slot_base = |l: usize| -> u32 { self.slots[..l - 1].iter().sum() };
        let grid = |l: usize| {
            self.grids
                .get(l.wrapping_sub(1))
                .map_or(([0; 4], [0; 4]), |g| {
                    (
                        [
                            g.first[0],
                            g.first[1],
                            g.first[2],
                            g.spacing.to_bits() as i32,
                        ],
                        [g.dims[0], g.dims[1], g.dims[2], 0],
                    )
                })
        };
        let far = [self.far.x, self.far.y, self.far.z, f32::INFINITY];
        (0..self.levels)
            .map(|l| {
                let items = if l == 0 {
                    points.len() as u32
                } else {
                    self.slots[l - 1]
                };
                let spread = match (l + 1 < self.levels, items >= cell_items) {
                    (false, _) => 0,
                    (true, false) => 1,
                    (true, true) => 2,
                };
                let (next_base, next_slots) = if spread > 0 {
                    (slot_base(l + 1), self.slots[l])
                } else {
                    (0, 0)
                };
                let (r, inner) = self.band(l);
                let (d, e) = grid(l + 1);
                let (g, h) = if l == 0 { ([0; 4], [0; 4]) } else { grid(l) };
                Step {
                    a: [u32::from(l > 0), items, row(items), spread],
                    b: [
                        if l == 0 { 0 } else { slot_base(l) },
                        self.level_range(l).0,
                        next_base,
                        next_slots,
                    ],
                    c: [r, inner, self.reach, self.scale],
                    d,
                    e,
                    g,
                    h,
                    far,
                    s: [
                        0,
                        u32::from(self.params.sample_from.is_some_and(|f| l >= f)),
                        l as u32,
                        (self.params.ramp as f32).to_bits(),
                    ],
                    o: [if l == 0 { points.start } else { 0 }, sources, 0, 0],
                }
            })
            .collect()
    }
}
