//! The lighting grid hierarchy built on the GPU every frame (`shaders/lights/hierarchy.wgsl`,
//! its passes timed as `lights.hierarchy.*`), from the scene's lights as they are in a buffer of
//! their own ([`GpuHierarchy::source`]: moving lights move there) into the shaded scene's light
//! buffer. Its oracle is `manylights_scene::hierarchy::Hierarchy::build_fixed`.
//!
//! The hierarchy's shape is fixed when it is planned ([`HierarchyPlan::new`]), from the lights
//! at that time: the finest spacing `h` and the number of levels, as
//! `Hierarchy::build` chooses them, and each level's box of grid nodes and hash table. The
//! shaded lights are laid out as `[point lights | level 1's slots | ... | spots]`: a slot with
//! no node that frame is a dead light (no power, radius 0, far from the scene), so the light
//! count stays fixed while the lights move. Splats that find no room (a node outside its
//! level's box, a full table) are counted ([`GpuHierarchy::dropped`]), never silent.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use manylights_scene::hierarchy::{Hierarchy, HierarchyParams};
use manylights_scene::{Light, LightKind, Scene};
use wgpu::util::DeviceExt;

use crate::layout::GpuLight;
use crate::pipeline::{self, UNIFORM, entry, storage};
use crate::shaders::{LIGHT, ShaderDef};
use crate::timing::{GpuTimer, PassTiming};
use crate::{GpuContext, GpuError, GpuScene};

/// The build's passes, its sums in 32-bit atomics ([`Sums::Bits32`]).
pub const HIERARCHY: ShaderDef = ShaderDef {
    name: "lights.hierarchy",
    consts: &[],
    files: &[
        LIGHT,
        crate::shader_file!("lights/hierarchy_sums32.wgsl"),
        crate::shader_file!("lights/hierarchy.wgsl"),
    ],
};

/// The build's passes, its sums in 64-bit atomics ([`Sums::Bits64`]).
pub const HIERARCHY64: ShaderDef = ShaderDef {
    name: "lights.hierarchy",
    consts: &[],
    files: &[
        LIGHT,
        crate::shader_file!("lights/hierarchy_sums64.wgsl"),
        crate::shader_file!("lights/hierarchy.wgsl"),
    ],
};

/// How the build's hash-table slots hold their 64-bit fixed-point sums: the same integers
/// either way, so the same hierarchy, but for the last rounding when a sum is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sums {
    /// Two 32-bit atomics a sum, the carry by hand (`shaders/lights/hierarchy_sums32.wgsl`):
    /// every adapter.
    Bits32,
    /// One 64-bit atomic a sum (`shaders/lights/hierarchy_sums64.wgsl`): adapters with
    /// `SHADER_INT64_ATOMIC_ALL_OPS` (lavapipe and NVIDIA's Vulkan driver have it).
    Bits64,
}

impl Sums {
    /// The fastest the adapter offers: 64-bit atomics where it has them.
    pub fn for_context(ctx: &GpuContext) -> Self {
        if ctx.features.int64_atomic_add {
            Self::Bits64
        } else {
            Self::Bits32
        }
    }

    /// Its shader.
    pub fn shader(self) -> &'static ShaderDef {
        match self {
            Self::Bits32 => &HIERARCHY,
            Self::Bits64 => &HIERARCHY64,
        }
    }

    /// As `render`/`cull` print it.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Bits32 => "two 32-bit atomics a sum",
            Self::Bits64 => "one 64-bit atomic a sum",
        }
    }
}

const WORKGROUP: u32 = 256;
/// Words of a hash table slot (the shader's `SLOT_WORDS`).
const SLOT_WORDS: u64 = 16;

/// Host mirror of `Step` in `shaders/lights/hierarchy.wgsl` (one dispatch's parameters).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Step {
    /// Mode (0 points, 1 finalize), items, threads a dispatch row, splat.
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
    /// Where an unbounded band ends (`manylights_scene::hierarchy::reach`).
    pub reach: f32,
    /// Where dead lights sit.
    pub far: Vec3,
    /// The sums' scale: 2^52 over the point lights' total power (the channels' sum).
    pub scale: f32,
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
            let nodes = u64::from(dims.x) * u64::from(dims.y) * u64::from(dims.z);
            if nodes >= u64::from(u32::MAX) {
                return Err(GpuError::OverLimit {
                    what: format!(
                        "hierarchy level {l}'s grid nodes ({} x {} x {} at {spacing} m)",
                        dims.x, dims.y, dims.z
                    ),
                    value: nodes,
                    limit: u64::from(u32::MAX) - 1,
                    limit_name: "a 32-bit node key (raise the spacing)",
                });
            }
            grids.push(NodeBox {
                spacing,
                first: lo.to_array(),
                dims: dims.to_array(),
            });
            slots.push((level.len() as f64 * slack.max(1.25)).ceil() as u32 + 64);
        }
        let total: f64 = hier.levels[0]
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
            reach,
            far: region.1 + Vec3::splat(2.0 * reach),
            scale: if total > 0.0 {
                (2f64.powi(52) / total) as f32
            } else {
                1.0
            },
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
    /// [`HierarchyPlan::placeholder`]'s lights, which the build fills. `moving`: the farthest
    /// any light goes from where it is now (0 where none moves); the grids' boxes, the
    /// unbounded bands' reach and the tables' room cover that too. The last level holds at
    /// most `params.top_lights` lights.
    pub fn for_scene(
        scene: &Scene,
        params: HierarchyParams,
        moving: f32,
    ) -> Result<(Self, Scene), GpuError> {
        let margin = 1.0 + moving.max(0.0);
        let b = scene
            .lights
            .iter()
            .fold(scene.bounds(), |b, l| b.union_point(l.position));
        let (plan, _) = Self::new(
            &scene.lights,
            params,
            (b.min - margin, b.max + margin),
            manylights_scene::hierarchy::reach(scene) + 2.0 * (margin - 1.0),
            if moving > 0.0 { 2.0 } else { 1.25 },
        )?;
        let shaded = Scene {
            lights: plan.placeholder(&scene.lights),
            ..scene.clone()
        };
        Ok((plan, shaded))
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

    /// Each dispatch's parameters, in order (the points pass, then a finalize pass a level).
    fn steps(&self, sources: u32, row: impl Fn(u32) -> u32) -> Vec<Step> {
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
                let splat = u32::from(l + 1 < self.levels);
                let items = if l == 0 { sources } else { self.slots[l - 1] };
                let (next_base, next_slots) = if splat == 1 {
                    (slot_base(l + 1), self.slots[l])
                } else {
                    (0, 0)
                };
                let (r, inner) = self.band(l);
                let (d, e) = grid(l + 1);
                let (g, h) = if l == 0 { ([0; 4], [0; 4]) } else { grid(l) };
                Step {
                    a: [u32::from(l > 0), items, row(items), splat],
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
                }
            })
            .collect()
    }
}

/// The build on the GPU: its buffers, pipelines and a bind group a pass.
pub struct GpuHierarchy {
    /// The plan it follows.
    pub plan: HierarchyPlan,
    source: wgpu::Buffer,
    slots: wgpu::Buffer,
    dropped: wgpu::Buffer,
    passes: Vec<(bool, wgpu::BindGroup, (u32, u32))>,
    /// Each pass's parameters (`Step`), whose seed [`GpuHierarchy::set_seed`] writes.
    steps: Vec<wgpu::Buffer>,
    points: wgpu::ComputePipeline,
    finalize: wgpu::ComputePipeline,
    sums: Sums,
}

impl GpuHierarchy {
    /// The build of `plan` from `lights` (the scene's lights, at home) into `shaded`, whose
    /// lights must be `plan.placeholder(lights)`, its sums as the adapter does them fastest
    /// ([`Sums::for_context`]).
    pub fn new(
        ctx: &GpuContext,
        plan: HierarchyPlan,
        lights: &[Light],
        shaded: &GpuScene,
    ) -> Result<Self, GpuError> {
        Self::with_sums(ctx, plan, lights, shaded, Sums::for_context(ctx))
    }

    /// As [`GpuHierarchy::new`], its sums held as `sums` says; [`Sums::Bits64`] needs
    /// `SHADER_INT64_ATOMIC_ALL_OPS` (`Negotiated::int64_atomic_add`).
    pub fn with_sums(
        ctx: &GpuContext,
        plan: HierarchyPlan,
        lights: &[Light],
        shaded: &GpuScene,
        sums: Sums,
    ) -> Result<Self, GpuError> {
        if sums == Sums::Bits64 && !ctx.features.int64_atomic_add {
            return Err(GpuError::Unsupported(format!(
                "the hierarchy build's 64-bit sums need 64-bit atomic add on storage buffers \
                 (wgpu feature SHADER_INT64_ATOMIC_ALL_OPS), which adapter {} does not offer; \
                 Sums::Bits32 runs everywhere",
                ctx.info.name
            )));
        }
        if u64::from(shaded.light_count) != plan.shaded_count() {
            return Err(GpuError::OverLimit {
                what: "the shaded scene's lights".into(),
                value: shaded.light_count.into(),
                limit: plan.shaded_count(),
                limit_name: "the hierarchy's layout (HierarchyPlan::placeholder)",
            });
        }
        let d = &ctx.device;
        let total_slots: u64 = plan.slots.iter().map(|&s| u64::from(s)).sum();
        let slot_bytes = (total_slots * SLOT_WORDS * 4).max(16);
        ctx.check_storage("hierarchy slot bytes", slot_bytes)?;
        let gpu: Vec<GpuLight> = lights.iter().map(GpuLight::from).collect();
        let source = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lights.hierarchy.source"),
            contents: if gpu.is_empty() {
                &[0u8; 64]
            } else {
                bytemuck::cast_slice(&gpu)
            },
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
        });
        let (mut next_point, mut next_spot) = (0u32, plan.shaded_count() as u32 - plan.spots);
        let target: Vec<u32> = lights
            .iter()
            .map(|l| {
                let slot = if matches!(l.kind, LightKind::Spot { .. }) {
                    &mut next_spot
                } else {
                    &mut next_point
                };
                *slot += 1;
                *slot - 1
            })
            .chain(std::iter::once(0))
            .collect();
        let target = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lights.hierarchy.target"),
            contents: bytemuck::cast_slice(&target),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let slots = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lights.hierarchy.slots"),
            size: slot_bytes,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let dropped = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lights.hierarchy.dropped"),
            size: 8,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let c = wgpu::ShaderStages::COMPUTE;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lights.hierarchy"),
            entries: &[
                entry(0, c, UNIFORM),
                entry(1, c, storage(true)),
                entry(2, c, storage(true)),
                entry(3, c, storage(false)),
                entry(4, c, storage(false)),
                entry(5, c, storage(false)),
            ],
        });
        let module = sums.shader().create(d);
        let pl = pipeline::layout(d, "lights.hierarchy", &[&layout]);
        let points = pipeline::compute(d, &module, &pl, "points");
        let finalize = pipeline::compute(d, &module, &pl, "finalize");
        let max = ctx.limits.max_compute_workgroups_per_dimension;
        let grid = |items: u32| {
            let n = items.div_ceil(WORKGROUP).max(1);
            (n.min(max), n.div_ceil(max))
        };
        let sources = lights.len() as u32;
        let mut steps = Vec::new();
        let passes = plan
            .steps(sources, |items| grid(items).0 * WORKGROUP)
            .into_iter()
            .map(|s| {
                let params = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("lights.hierarchy.step"),
                    contents: bytemuck::bytes_of(&s),
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                });
                let group = pipeline::buffers_group(
                    d,
                    "lights.hierarchy",
                    &layout,
                    &[&params, &source, &target, &shaded.lights, &slots, &dropped],
                );
                steps.push(params);
                (s.a[0] == 1, group, grid(s.a[1]))
            })
            .collect();
        // Point lights and aggregates shade on the short path unless a spot is among them, with
        // the bands' ramps in the frame.
        shaded.set_band_ramp(ctx, plan.params.ramp as f32);
        shaded.mark_band_points(ctx);
        Ok(Self {
            plan,
            source,
            slots,
            dropped,
            passes,
            steps,
            points,
            finalize,
            sums,
        })
    }

    /// How its sums are held.
    pub fn sums(&self) -> Sums {
        self.sums
    }

    /// The seed of the next builds' draws (`HierarchyParams::sample_from`: the sampled
    /// levels' bands; `manylights_scene::hierarchy::band_xi`): a frame's index, so that each
    /// frame draws afresh. No effect without sampled levels.
    pub fn set_seed(&self, ctx: &GpuContext, seed: u32) {
        let at = std::mem::offset_of!(Step, s) as u64;
        for b in &self.steps {
            ctx.queue.write_buffer(b, at, &seed.to_le_bytes());
        }
    }

    /// The lights the hierarchy is built from, as `GpuLight`s in the scene's order: what a
    /// moving-light pass moves.
    pub fn source(&self) -> &wgpu::Buffer {
        &self.source
    }

    /// Records the build: the tables cleared, then a pass a level (`lights.hierarchy.points`,
    /// `lights.hierarchy.level1`, ...).
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: &mut GpuTimer) {
        encoder.clear_buffer(&self.slots, 0, None);
        for (l, (finalize, group, groups)) in self.passes.iter().enumerate() {
            let (label, pipeline) = if *finalize {
                (format!("lights.hierarchy.level{l}"), &self.finalize)
            } else {
                ("lights.hierarchy.points".to_string(), &self.points)
            };
            pipeline::dispatch(encoder, timer, &label, pipeline, &[group], *groups);
        }
    }

    /// Passes a build records (the points pass and a pass a level above it).
    pub fn pass_count(&self) -> u32 {
        self.passes.len() as u32
    }

    /// Records `runs` builds back to back in one submission, each in a span of `timer`: the
    /// build in steady state (every build of static lights leaves the same hierarchy).
    pub fn build_repeated(
        &self,
        ctx: &GpuContext,
        runs: u32,
        timer: &mut GpuTimer,
    ) -> Result<(), GpuError> {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("lights.hierarchy_repeated"),
            });
        for _ in 0..runs {
            timer.span_begin(&mut encoder, "lights.hierarchy");
            self.encode(&mut encoder, timer);
        }
        timer.span_end(&mut encoder);
        timer.resolve(&mut encoder);
        ctx.submit_and_wait(encoder, "lights.hierarchy repeated")
    }

    /// Builds the hierarchy now, in an encoder of its own: its passes' times where timed.
    pub fn build(&self, ctx: &GpuContext) -> Result<Option<Vec<PassTiming>>, GpuError> {
        let mut timer = GpuTimer::new(ctx, self.passes.len() as u32);
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("lights.hierarchy"),
            });
        self.encode(&mut encoder, &mut timer);
        timer.resolve(&mut encoder);
        ctx.submit_and_wait(encoder, "lights.hierarchy")?;
        timer.read(ctx)
    }

    /// The key of every hash-table slot after the last build, level 1's slots first (a level's
    /// `t`-th slot is its `t`-th shaded light, [`HierarchyPlan::level_range`]): 0 for an empty
    /// slot, else 1 plus the node's index in its level's box. What a sampled aggregate's band is
    /// drawn from (`manylights_scene::hierarchy::node_draw`).
    pub fn slot_keys(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        let slots: u64 = self.plan.slots.iter().map(|&s| u64::from(s)).sum();
        let b = crate::readback::read_buffer(ctx, &self.slots, 0, slots * SLOT_WORDS * 4)?;
        let w: &[u32] = bytemuck::cast_slice(&b);
        Ok(w.iter().step_by(SLOT_WORDS as usize).copied().collect())
    }

    /// Splats dropped since the build was made: (nodes outside their level's box, splats into
    /// a full table).
    pub fn dropped(&self, ctx: &GpuContext) -> Result<(u64, u64), GpuError> {
        let b = crate::readback::read_buffer(ctx, &self.dropped, 0, 8)?;
        let w: &[u32] = bytemuck::cast_slice(&b);
        Ok((w[0].into(), w[1].into()))
    }
}
