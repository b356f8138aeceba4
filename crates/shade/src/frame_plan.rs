//! A backend's frame as data: the passes before culling (the geometry: a depth prepass, a
//! G-buffer or visibility buffer, the lookup bounds) and the passes after it (the shading over
//! the lists) as [`FramePass`]es, each with its name, category, work and the resources it reads
//! and writes, and [`record`], the one function that encodes, labels and times them, as
//! culling's `Step`s and `Recorder` are for its own passes.
//!
//! `Renderer::geometry_plan` and `ShadePass::plan` make the two halves; a frame is the first,
//! the culling run ([`cull_info`]), then the second. A pass between culling and shading (one
//! that reads the lists and writes what the shading reads) is one more entry at the head of
//! `ShadePass::plan`. What a frame ran is [`crate::ShadeOutput::passes`], which a test checks:
//! every resource a pass reads is an input or written by an earlier pass.

use manylights_gpu::GpuScene;
use manylights_gpu::lookup_bounds::{BoundsTargets, LookupBounds};
use manylights_gpu::pipeline;
use manylights_gpu::prepass::DepthPrepass;
use manylights_gpu::timing::{Category, GpuTimer};

use crate::raster::Draw;
use crate::vis_compute::{ComputeTargets, ComputeVisibility};

/// A resource of a frame, by role.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Resource {
    /// The scene's triangles, materials and frame uniform (an input).
    Scene,
    /// The scene's lights (an input).
    Lights,
    /// The depth buffer.
    Depth,
    /// Forward with MSAA: each pixel's range of sample depths, kept by its prepass.
    DepthRanges,
    /// The depth culling reads where the renderer has lookup bounds (MSAA, glass): each
    /// pixel's nearest and farthest depth a list is looked up at.
    LookupBounds,
    /// A deferred backend's surfaces: the G-buffer, or the visibility buffer's triangle ids.
    Surfaces,
    /// The compute rasteriser's depth and triangle keys (`R32Float` depth: what its frame
    /// culls and lights over).
    ComputeDepth,
    /// The light lists (culling's output).
    Lists,
    /// Deferred with MSAA over glass: the glass's own contribution and transmittance, a layer
    /// the lighting composites.
    GlassLayer,
    /// The lit image.
    Color,
}

impl Resource {
    /// Inputs of every frame: read, never written by its passes.
    pub const INPUTS: [Resource; 2] = [Resource::Scene, Resource::Lights];
}

/// Whether a pass is recorded only in a frame that is checked, untimed: the depth buffer the
/// compute rasteriser's frame gives the oracle, naive forward's lookup bounds for a culler that
/// measures its lights. Repeated geometry ([`crate::Renderer::geometry_repeated`]) leaves them out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// Part of the frame, timed.
    Frame,
    /// For the checks that follow the frame, untimed.
    Checks,
}

/// How a pass is recorded.
pub(crate) enum Work<'a> {
    /// A raster pass drawing the scene ([`crate::raster::draw`]).
    Draw(Draw<'a>),
    /// A compute pass over `groups` (bind groups 0, 1, ... in order).
    Dispatch {
        pipeline: &'a wgpu::ComputePipeline,
        groups: Vec<&'a wgpu::BindGroup>,
        grid: [u32; 3],
    },
    /// Zeroes a buffer (a transfer, untimed).
    Clear(&'a wgpu::Buffer),
    /// The depth prepass into `depth`.
    DepthPrepass {
        prepass: &'a DepthPrepass,
        depth: &'a wgpu::TextureView,
    },
    /// Forward with MSAA: the prepass that also keeps each pixel's depth ranges.
    RangesPrepass {
        bounds: &'a LookupBounds,
        depth: &'a wgpu::TextureView,
        targets: &'a BoundsTargets,
    },
    /// The lookup bounds (after the glass's nearest and farthest depth, where there is glass);
    /// over the depth ranges with `ranges`.
    LookupBounds {
        bounds: &'a LookupBounds,
        targets: &'a BoundsTargets,
        ranges: bool,
    },
    /// The compute rasteriser's depths into a depth buffer.
    ComputeDepth {
        vis: &'a ComputeVisibility,
        targets: &'a ComputeTargets,
        depth: &'a wgpu::TextureView,
    },
}

/// One pass of a frame.
pub struct FramePass<'a> {
    /// Profiler scope and result column, such as `shade.gbuffer` (a step of several passes,
    /// such as the lookup bounds, is named as its main one).
    pub name: &'static str,
    /// The part of the frame its GPU time counts in.
    pub category: Category,
    /// Resources it reads (inputs, or written by an earlier pass).
    pub reads: Vec<Resource>,
    /// Resources it writes.
    pub writes: Vec<Resource>,
    /// Whether it is part of the timed frame.
    pub role: Role,
    pub(crate) work: Work<'a>,
}

impl<'a> FramePass<'a> {
    /// A pass of the timed frame.
    pub(crate) fn new(
        name: &'static str,
        category: Category,
        work: Work<'a>,
        reads: &[Resource],
        writes: &[Resource],
    ) -> Self {
        Self {
            name,
            category,
            reads: reads.to_vec(),
            writes: writes.to_vec(),
            role: Role::Frame,
            work,
        }
    }

    /// The same pass, recorded for the checks only.
    pub(crate) fn for_checks(self) -> Self {
        Self {
            role: Role::Checks,
            ..self
        }
    }

    /// What it is called, reads and writes.
    pub fn info(&self) -> PassInfo {
        PassInfo {
            name: self.name,
            category: self.category,
            reads: self.reads.clone(),
            writes: self.writes.clone(),
            role: self.role,
        }
    }

    /// Whether its GPU time is measured (a compute or raster pass of the timed frame).
    pub(crate) fn timed(&self) -> bool {
        self.role == Role::Frame && !matches!(self.work, Work::Clear(_))
    }
}

/// A pass as [`crate::ShadeOutput::passes`] lists it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PassInfo {
    /// Its name (`cull` for the culling run).
    pub name: &'static str,
    /// Its category.
    pub category: Category,
    /// Resources it reads.
    pub reads: Vec<Resource>,
    /// Resources it writes.
    pub writes: Vec<Resource>,
    /// Whether it is part of the timed frame.
    pub role: Role,
}

/// The culling run between a frame's geometry and its shading, over `depth` (the depth buffer,
/// the lookup bounds or the compute rasteriser's depth).
pub fn cull_info(depth: Resource) -> PassInfo {
    PassInfo {
        name: "cull",
        category: Category::Cull,
        reads: vec![depth, Resource::Lights, Resource::Scene],
        writes: vec![Resource::Lists],
        role: Role::Frame,
    }
}

/// Which passes of a plan [`record`] encodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Recording {
    /// Every pass: a frame that is read back and checked.
    Frame,
    /// The timed frame's passes alone: a repetition timed back to back.
    Repeat,
}

/// Encodes `passes` in order into `enc`: the one place a frame's passes are recorded, labelled
/// and timed, each in its entry's category (the checks' passes untimed, and left out of a
/// [`Recording::Repeat`]).
pub(crate) fn record(
    enc: &mut wgpu::CommandEncoder,
    timer: &mut GpuTimer,
    scene: &GpuScene,
    passes: &[FramePass<'_>],
    recording: Recording,
) {
    let mut untimed = GpuTimer::untimed();
    for p in passes {
        let timer = match (p.role, recording) {
            (Role::Frame, _) => &mut *timer,
            (Role::Checks, Recording::Frame) => &mut untimed,
            (Role::Checks, Recording::Repeat) => continue,
        };
        let outer = timer.set_category(p.category);
        encode(enc, timer, scene, p);
        timer.set_category(outer);
    }
}

fn encode(
    enc: &mut wgpu::CommandEncoder,
    timer: &mut GpuTimer,
    scene: &GpuScene,
    p: &FramePass<'_>,
) {
    match &p.work {
        Work::Draw(d) => crate::raster::draw(enc, timer, p.name, scene, d),
        Work::Dispatch {
            pipeline,
            groups,
            grid,
        } => pipeline::dispatch_3d(enc, timer, p.name, pipeline, groups, *grid),
        Work::Clear(buffer) => enc.clear_buffer(buffer, 0, None),
        Work::DepthPrepass { prepass, depth } => prepass.encode(enc, scene, depth, timer),
        Work::RangesPrepass {
            bounds,
            depth,
            targets,
        } => bounds.encode_prepass(enc, scene, depth, targets, timer),
        Work::LookupBounds {
            bounds,
            targets,
            ranges,
        } => bounds.encode_bounds(enc, scene, targets, *ranges, timer),
        Work::ComputeDepth {
            vis,
            targets,
            depth,
        } => vis.encode_depth(enc, targets, depth),
    }
}

/// Passes of `passes` that write timestamps: room for a frame's timer.
pub(crate) fn timed_passes(passes: &[FramePass<'_>]) -> u32 {
    passes.iter().filter(|p| p.timed()).count() as u32
}
