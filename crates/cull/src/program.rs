//! A shader module and its pipeline layout, built once and shared by the pipelines of every
//! entry point of it (a strategy's, and the building blocks' whose passes live in its files).

use manylights_gpu::pipeline;
use manylights_gpu::shaders::ShaderDef;

use crate::shaders::{
    BOUNDS_SWAPS, FLOAT_SWAPS, create_over_samples, reads_depth, sample_constants,
};

/// What culling reads its depth from (`shaders/cull/common/depth_input.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum DepthInput {
    /// The depth buffer, of this many samples a pixel.
    Samples(u32),
    /// Lookup bounds (`manylights_gpu::lookup_bounds`), read as two samples a pixel.
    Bounds,
    /// An `R32Float` texture of depths, one sample a pixel (written by a compute pass).
    Float,
}

/// A compute pipeline and the code it runs: its shader and entry point, which a test checks a
/// step's declared reads and writes against (naga's use of each global by that entry point).
pub struct Kernel {
    /// The pipeline.
    pub pipeline: wgpu::ComputePipeline,
    /// Its shader's name (a [`ShaderDef`] of [`crate::shaders::SHADERS`]).
    pub shader: &'static str,
    /// Its entry point.
    pub entry: &'static str,
}

/// A compiled shader over bind group 0 (the scene) and one group 1.
pub(crate) struct Program {
    module: wgpu::ShaderModule,
    /// The shader's name.
    shader: &'static str,
    layout: wgpu::PipelineLayout,
    /// The override constants of its depth input (`DEPTH_SAMPLES` over MSAA), which every
    /// pipeline of it takes.
    depth_constants: Vec<(&'static str, f64)>,
}

impl Program {
    /// `def` compiled over `input`, over `scene_layout` and `group1`.
    pub fn new(
        d: &wgpu::Device,
        def: &ShaderDef,
        input: DepthInput,
        scene_layout: &wgpu::BindGroupLayout,
        group1: &wgpu::BindGroupLayout,
    ) -> Self {
        let (module, depth_constants) = match input {
            DepthInput::Samples(samples) if reads_depth(def) => (
                create_over_samples(d, def, samples, &[]),
                sample_constants(samples),
            ),
            // A module of passes that read no depth (tiled scatter's, the sorts').
            DepthInput::Samples(_) => (def.create(d), Vec::new()),
            DepthInput::Bounds => (def.create_swapped(d, BOUNDS_SWAPS), Vec::new()),
            DepthInput::Float => (def.create_swapped(d, FLOAT_SWAPS), Vec::new()),
        };
        Self {
            module,
            shader: def.name,
            layout: pipeline::layout(d, def.name, &[scene_layout, group1]),
            depth_constants,
        }
    }

    /// The pipeline of entry point `entry`.
    pub fn pipeline(&self, d: &wgpu::Device, entry: &'static str) -> Kernel {
        self.pipeline_with(d, entry, &[])
    }

    /// The pipelines of `entries`.
    pub fn pipelines<const N: usize>(
        &self,
        d: &wgpu::Device,
        entries: [&'static str; N],
    ) -> [Kernel; N] {
        entries.map(|e| self.pipeline(d, e))
    }

    /// The pipeline of `entry` with values of the shader's `override` constants (its depth
    /// input's besides).
    pub fn pipeline_with(
        &self,
        d: &wgpu::Device,
        entry: &'static str,
        constants: &[(&str, f64)],
    ) -> Kernel {
        let all: Vec<(&str, f64)> = constants
            .iter()
            .copied()
            .chain(self.depth_constants.iter().copied())
            .collect();
        let options = wgpu::PipelineCompilationOptions {
            constants: &all,
            ..Default::default()
        };
        Kernel {
            pipeline: pipeline::compute_with(d, &self.module, &self.layout, entry, &options),
            shader: self.shader,
            entry,
        }
    }
}
