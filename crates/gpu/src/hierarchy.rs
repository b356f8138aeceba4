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
//!
//! Lights that never move (the scene's first [`HierarchyPlan::static_lights`]) are splatted
//! into level 1 once, when the build is made, and that table kept: each build copies it and
//! splats only the lights after them; their level-0 lights are written once. The sums are
//! integers, so it is the same hierarchy as a build of every light. The coarser levels are
//! made afresh each build, from level 1 (a node's light is its sums' centroid, not a sum).

use manylights_scene::{Light, LightKind};
use wgpu::util::DeviceExt;

use crate::layout::GpuLight;
use crate::pipeline::{self, UNIFORM, entry, storage};
use crate::shaders::{LIGHT, ShaderDef};
use crate::timing::{Category, GpuTimer, PassTiming};
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

mod plan;
pub use plan::{HierarchyPlan, Moving, NodeBox, Step};

const WORKGROUP: u32 = 256;

/// A pass that spreads at least this many items into the next level bins them into cells
/// first (the cells' three passes after it); fewer are each spread at once. On the H200 the
/// cells break even at about 50,000 items (the hall's 50,000 points: 0.066 against 0.064 ms;
/// the 47,025 of a million lights' level 2: 0.062 against 0.064) and win beyond (1M points:
/// 0.60 against 1.25 ms; 359,223 of level 1: 0.21 against 0.31).
pub const CELL_ITEMS: u32 = 65_536;
/// Words of a hash table slot (the shader's `SLOT_WORDS`).
const SLOT_WORDS: u64 = 16;

/// Whether `plan` can be built into `shaded` with `sums` on `ctx`'s adapter.
fn check_build(
    ctx: &GpuContext,
    plan: &HierarchyPlan,
    shaded: &GpuScene,
    sums: Sums,
) -> Result<(), GpuError> {
    if sums == Sums::Bits64 && !ctx.features.int64_atomic_add {
        return Err(GpuError::Unsupported(format!(
            "the hierarchy build's 64-bit sums need 64-bit atomic add on storage buffers \
             (wgpu feature SHADER_INT64_ATOMIC_ALL_OPS), which adapter {} does not offer; \
             Sums::Bits32 runs everywhere",
            ctx.info.name
        )));
    }
    if shaded.light_model().ranges != plan.light_model().ranges {
        return Err(GpuError::Unsupported(format!(
            "the hierarchy's build writes its lights with bands of ramp {} into a scene uploaded \
             for {:?}: upload the shaded scene with HierarchyPlan::light_model \
             (GpuScene::upload_with)",
            plan.params.ramp,
            shaded.light_model().ranges
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
    Ok(())
}

/// The shaded light each of `lights` becomes (the points pass's `target_index`): point lights
/// from the first, spots after every level's slots; then each light's direction bin (0 for a
/// point light, `manylights_scene::hierarchy::spot_bins`); one more entry, so the buffer is
/// never empty.
fn target_indices(plan: &HierarchyPlan, lights: &[Light]) -> Vec<u32> {
    let (mut next_point, mut next_spot) = (0u32, plan.shaded_count() as u32 - plan.spots);
    let (_, bins) = manylights_scene::hierarchy::spot_bins(lights, plan.params.spot_bins);
    lights
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
        .chain(bins)
        .chain(std::iter::once(0))
        .collect()
}

/// The direction bins' cones as the shader's `SpotBin`s (axis and cosines as a light of the
/// cone holds them, the flux), at least one.
fn bin_cones(plan: &HierarchyPlan) -> Vec<[f32; 8]> {
    let mut out: Vec<[f32; 8]> = plan
        .bins
        .iter()
        .map(|b| {
            let l = GpuLight::from(&b.light(glam::Vec3::ZERO, 1.0, glam::Vec3::ONE));
            let flux = manylights_scene::hierarchy::spots::spot_flux(
                l.cos_inner.into(),
                l.cos_outer.into(),
            );
            let a = l.direction;
            [
                a.x,
                a.y,
                a.z,
                l.cos_inner,
                l.cos_outer,
                flux as f32,
                0.0,
                0.0,
            ]
        })
        .collect();
    if out.is_empty() {
        out.push([0.0; 8]);
    }
    out
}

/// The build's bind group layout: its step, the source lights, the target indices and bins,
/// the shaded lights, the slots, the drop counters, the cells and the direction bins' cones
/// (`shaders/lights/hierarchy.wgsl`).
fn group_layout(d: &wgpu::Device) -> wgpu::BindGroupLayout {
    let c = wgpu::ShaderStages::COMPUTE;
    d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("lights.hierarchy"),
        entries: &[
            entry(0, c, UNIFORM),
            entry(1, c, storage(true)),
            entry(2, c, storage(true)),
            entry(3, c, storage(false)),
            entry(4, c, storage(false)),
            entry(5, c, storage(false)),
            entry(6, c, storage(false)),
            entry(7, c, storage(true)),
        ],
    })
}

/// A pass of the build: the points pass or a level's (`finalize`), its bind group and
/// dispatch, and where it bins its items into the next level's cells, the cells' passes.
struct Pass {
    finalize: bool,
    group: wgpu::BindGroup,
    groups: (u32, u32),
    cells: Option<CellPasses>,
}

/// The cells' passes after a pass that bins: the bytes of the cells' buffer it uses, and the
/// dispatches over the cells' table (`cells_room`), over its slots' corners (`cell_splat`, 8
/// threads a slot) and over the items (`fill`).
#[derive(Clone, Copy)]
struct CellPasses {
    bytes: u64,
    table: (u32, u32),
    corners: (u32, u32),
    items: (u32, u32),
}

impl CellPasses {
    /// Those of step `s`, where it bins (spread 2): a table of the next level's table's size (a
    /// cell is keyed by its lowest node), a cell slot an item and the lists; the dispatches in
    /// rows of the pass's own width (`item`).
    fn of(s: &Step) -> Option<Self> {
        (s.a[3] == 2).then(|| {
            let rows = |n: u32| (s.a[2] / WORKGROUP, n.div_ceil(s.a[2]).max(1));
            Self {
                bytes: 4 * (4 + 4 * u64::from(s.b[3]) + 2 * u64::from(s.a[1])),
                table: rows(s.b[3]),
                corners: rows(8 * s.b[3]),
                items: rows(s.a[1]),
            }
        })
    }
}

/// The build on the GPU: its buffers, pipelines and a bind group a pass.
pub struct GpuHierarchy {
    /// The plan it follows.
    pub plan: HierarchyPlan,
    source: wgpu::Buffer,
    slots: wgpu::Buffer,
    dropped: wgpu::Buffer,
    /// The cells of the next level's grid a pass bins its items into, their lists and each
    /// item's cell (the shader's `cell_word`), cleared before each pass that bins.
    cells: wgpu::Buffer,
    passes: Vec<Pass>,
    /// Each pass's parameters (`Step`), whose seed [`GpuHierarchy::set_seed`] writes.
    steps: Vec<wgpu::Buffer>,
    points: wgpu::ComputePipeline,
    finalize: wgpu::ComputePipeline,
    /// `cells_room`, `fill` and `cell_splat`.
    cell_pipelines: [wgpu::ComputePipeline; 3],
    sums: Sums,
    /// Level 1's table with the lights that never move splatted into it, where the build
    /// keeps it.
    kept: Option<Kept>,
}

/// Level 1's table as the lights that never move leave it: `lights` of them, `bytes` bytes.
struct Kept {
    lights: u32,
    slots: wgpu::Buffer,
    bytes: u64,
}

/// How many of `sources` lights (the first) the build of `plan` keeps the level-1 sums of: the
/// plan's lights that never move, where there is a level 1 and level 0's bands are not drawn
/// afresh each frame (the kept lights' level-0 lights are written once); else 0.
fn kept_lights(plan: &HierarchyPlan, sources: u32) -> u32 {
    if plan.levels < 2 || plan.params.sample_from == Some(0) {
        return 0;
    }
    plan.static_lights.min(sources)
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
        Self::with_cells(ctx, plan, lights, shaded, sums, CELL_ITEMS)
    }

    /// As [`GpuHierarchy::with_sums`], a pass that spreads at least `cell_items` items into
    /// the next level binning them into cells first ([`CELL_ITEMS`] by default; 0: every
    /// such pass, `u32::MAX`: none, each item spread at once). The same hierarchy either way.
    pub fn with_cells(
        ctx: &GpuContext,
        plan: HierarchyPlan,
        lights: &[Light],
        shaded: &GpuScene,
        sums: Sums,
        cell_items: u32,
    ) -> Result<Self, GpuError> {
        check_build(ctx, &plan, shaded, sums)?;
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
        let target = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lights.hierarchy.target"),
            contents: bytemuck::cast_slice(&target_indices(&plan, lights)),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let cones = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lights.hierarchy.spot_bins"),
            contents: bytemuck::cast_slice(&bin_cones(&plan)),
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
        let sources = lights.len() as u32;
        let max = ctx.limits.max_compute_workgroups_per_dimension;
        let grid = |items: u32| {
            let n = items.div_ceil(WORKGROUP).max(1);
            (n.min(max), n.div_ceil(max))
        };
        let kept = kept_lights(&plan, sources);
        let row = |items| grid(items).0 * WORKGROUP;
        let steps_of = plan.steps(sources, kept..sources, row, cell_items);
        let kept_step = (kept > 0).then(|| plan.steps(sources, 0..kept, row, cell_items)[0]);
        let cell_bytes = steps_of
            .iter()
            .chain(&kept_step)
            .filter_map(|s| CellPasses::of(s).map(|c| c.bytes))
            .max()
            .unwrap_or(0)
            .max(16);
        ctx.check_storage("hierarchy cell bytes", cell_bytes)?;
        let cells = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lights.hierarchy.cells"),
            size: cell_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
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
        let layout = group_layout(d);
        let module = sums.shader().create(d);
        let pl = pipeline::layout(d, "lights.hierarchy", &[&layout]);
        let points = pipeline::compute(d, &module, &pl, "points");
        let finalize = pipeline::compute(d, &module, &pl, "finalize");
        let cell_pipelines = ["cells_room", "fill", "cell_splat"]
            .map(|entry| pipeline::compute(d, &module, &pl, entry));
        let pass_of = |s: Step| {
            let params = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("lights.hierarchy.step"),
                contents: bytemuck::bytes_of(&s),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            });
            let group = pipeline::buffers_group(
                d,
                "lights.hierarchy",
                &layout,
                &[
                    &params,
                    &source,
                    &target,
                    &shaded.lights,
                    &slots,
                    &dropped,
                    &cells,
                    &cones,
                ],
            );
            (
                Pass {
                    finalize: s.a[0] == 1,
                    group,
                    groups: grid(s.a[1]),
                    cells: CellPasses::of(&s),
                },
                params,
            )
        };
        let (passes, steps) = steps_of.into_iter().map(pass_of).unzip();
        let kept_pass = kept_step.map(|s| pass_of(s).0);
        let mut built = Self {
            plan,
            source,
            slots,
            dropped,
            cells,
            passes,
            steps,
            points,
            finalize,
            cell_pipelines,
            sums,
            kept: None,
        };
        if let Some(pass) = kept_pass {
            built.keep(ctx, kept, &pass)?;
        }
        Ok(built)
    }

    /// Splats the `lights` lights that never move into level 1 (`pass`, the points pass over
    /// them; their level-0 lights written to the shaded lights) and keeps level 1's table as
    /// it is then: each build starts from it.
    fn keep(&mut self, ctx: &GpuContext, lights: u32, pass: &Pass) -> Result<(), GpuError> {
        let bytes = u64::from(self.plan.slots[0]) * SLOT_WORDS * 4;
        let slots = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lights.hierarchy.kept"),
            size: bytes,
            usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("lights.hierarchy.kept"),
            });
        encoder.clear_buffer(&self.slots, 0, None);
        self.record(&mut encoder, &mut GpuTimer::untimed(), 0, pass);
        encoder.copy_buffer_to_buffer(&self.slots, 0, &slots, 0, bytes);
        ctx.submit_and_wait(encoder, "lights.hierarchy.kept")?;
        self.kept = Some(Kept {
            lights,
            slots,
            bytes,
        });
        Ok(())
    }

    /// The lights whose level-1 sums the build keeps (`HierarchyPlan::static_lights`; 0: it
    /// splats every light each frame).
    pub fn kept_lights(&self) -> u32 {
        self.kept.as_ref().map_or(0, |k| k.lights)
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
    /// `lights.hierarchy.level1`, ...), each that spreads into a next level followed by the
    /// cells' passes that make that level from its items' cells
    /// (`lights.hierarchy.cells<l>`, `.fill<l>`, `.cell_splat<l>`, `l` the level binned).
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: &mut GpuTimer) {
        let outer = timer.set_category(Category::LightUpdate);
        match &self.kept {
            Some(k) => {
                encoder.copy_buffer_to_buffer(&k.slots, 0, &self.slots, 0, k.bytes);
                if self.slots.size() > k.bytes {
                    encoder.clear_buffer(&self.slots, k.bytes, None);
                }
            }
            None => encoder.clear_buffer(&self.slots, 0, None),
        }
        for (l, p) in self.passes.iter().enumerate() {
            self.record(encoder, timer, l, p);
        }
        timer.set_category(outer);
    }

    /// Records pass `p` of level `l` and, where it bins, the cells' passes after it.
    fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: &mut GpuTimer, l: usize, p: &Pass) {
        let (label, pipeline) = if p.finalize {
            (format!("lights.hierarchy.level{l}"), &self.finalize)
        } else {
            ("lights.hierarchy.points".to_string(), &self.points)
        };
        if let Some(c) = p.cells {
            encoder.clear_buffer(&self.cells, 0, Some(c.bytes));
        }
        pipeline::dispatch(encoder, timer, &label, pipeline, &[&p.group], p.groups);
        if let Some(c) = p.cells {
            let [room, fill, splat] = &self.cell_pipelines;
            for (name, pipeline, groups) in [
                ("cells", room, c.table),
                ("fill", fill, c.items),
                ("cell_splat", splat, c.corners),
            ] {
                let label = format!("lights.hierarchy.{name}{l}");
                pipeline::dispatch(encoder, timer, &label, pipeline, &[&p.group], groups);
            }
        }
    }

    /// Passes a build records: a pass a level (the points pass first) and the cells' three
    /// after each that spreads into a next level.
    pub fn pass_count(&self) -> u32 {
        self.passes
            .iter()
            .map(|p| if p.cells.is_some() { 4 } else { 1 })
            .sum()
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
            let outer = timer.set_category(Category::LightUpdate);
            timer.span_begin(&mut encoder, "lights.hierarchy");
            timer.set_category(outer);
            self.encode(&mut encoder, timer);
        }
        timer.span_end(&mut encoder);
        timer.resolve(&mut encoder);
        ctx.submit_and_wait(encoder, "lights.hierarchy repeated")
    }

    /// Builds the hierarchy now, in an encoder of its own: its passes' times where timed.
    pub fn build(&self, ctx: &GpuContext) -> Result<Option<Vec<PassTiming>>, GpuError> {
        let mut timer = GpuTimer::new(ctx, self.pass_count());
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
