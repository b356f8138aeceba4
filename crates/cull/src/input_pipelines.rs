//! Every culling pipeline over one depth input (a depth buffer of some samples, lookup bounds,
//! or a float depth a compute pass wrote): the culling group's layout, whose binding 1 is that
//! input, and the strategies' and building blocks' pipelines compiled over it (tiled
//! scatter's, the clusters' and z-binning's at their first run). A [`crate::Culler`] holds one
//! for its own input and builds one for a float depth at the first run over one.

use std::sync::OnceLock;

use manylights_gpu::GpuContext;
use manylights_gpu::pipeline::{UNIFORM, depth_texture, storage};
use manylights_gpu::shaders::ShaderDef;

use crate::blocks::lists::Lists;
use crate::blocks::tile_depth::TileDepth;
use crate::blocks::tile_lines::TileLines;
use crate::blocks::tile_masks::TileMasks;
use crate::culler::entry;
use crate::program::{DepthInput, Program};
use crate::shaders::{
    CLUSTERED, DEPTH_BOUNDS, TILED_GATHER, TILED_GATHER_SUBGROUP, TILED_SCATTER, ZBIN, ZBIN_SCATTER,
};
use crate::strategies::{clustered, tiled_gather, tiled_scatter, zbin};

/// The culling pipelines over one depth input.
pub(crate) struct InputPipelines {
    /// What binding 1 of the culling group reads.
    pub input: DepthInput,
    /// The culling group's layout (group 1 of every culling pass).
    pub layout: wgpu::BindGroupLayout,
    /// Whether gather's scans use subgroup operations.
    pub gather_subgroups: bool,
    pub tile_depth: TileDepth,
    pub tile_lines: TileLines,
    pub tile_masks: TileMasks,
    pub lists: Lists,
    pub gather: tiled_gather::Pipelines,
    /// Built at the strategy's first run ([`InputPipelines::scatter`], `clustered`, `zbin`): the
    /// clusters' pipelines are half of all culling's, and a renderer that never runs a strategy
    /// need not build it (on a software rasteriser building every pipeline took 3 s, 2 of them
    /// the clusters').
    scatter: OnceLock<tiled_scatter::Pipelines>,
    clustered: OnceLock<clustered::Pipelines>,
    zbin: OnceLock<zbin::Pipelines>,
    /// What the pipelines built at first use are built over.
    device: wgpu::Device,
    scene_layout: wgpu::BindGroupLayout,
}

impl InputPipelines {
    /// The pipelines over `input` for scenes of group 0 `scene_layout`, gather's scans over
    /// subgroups where `subgroups` asks and the device's subgroups fit them.
    pub fn new(
        ctx: &GpuContext,
        scene_layout: &wgpu::BindGroupLayout,
        input: DepthInput,
        subgroups: bool,
    ) -> Self {
        let d = &ctx.device;
        let depth = match input {
            DepthInput::Samples(samples) => depth_texture(samples),
            DepthInput::Bounds | DepthInput::Float => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
        };
        let mut entries = vec![entry(0, UNIFORM), entry(1, depth)];
        entries.extend((2..=11).map(|b| entry(b, storage(false))));
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cull.group1"),
            entries: &entries,
        });
        let program = |def| Program::new(d, def, input, scene_layout, &layout);
        let depth = program(&DEPTH_BOUNDS);
        let gather_subgroups = subgroups && crate::culler::gather_subgroups_fit(ctx);
        // One module for all of gather's pipelines, and the blocks' whose passes it holds.
        let gather = program(if gather_subgroups {
            &TILED_GATHER_SUBGROUP
        } else {
            &TILED_GATHER
        });
        Self {
            input,
            tile_depth: TileDepth::new(ctx, &depth),
            tile_lines: TileLines::new(d, &depth, &gather),
            tile_masks: TileMasks::new(d, &gather),
            lists: Lists::new(d, &gather),
            gather: tiled_gather::Pipelines::new(d, &gather),
            gather_subgroups,
            scatter: OnceLock::new(),
            clustered: OnceLock::new(),
            zbin: OnceLock::new(),
            device: d.clone(),
            scene_layout: scene_layout.clone(),
            layout,
        }
    }

    /// A program of `def` over this input and layouts.
    fn program(&self, def: &ShaderDef) -> Program {
        Program::new(
            &self.device,
            def,
            self.input,
            &self.scene_layout,
            &self.layout,
        )
    }

    /// Tiled scatter's pipelines, built at their first use.
    pub fn scatter(&self) -> &tiled_scatter::Pipelines {
        self.scatter.get_or_init(|| {
            tiled_scatter::Pipelines::new(&self.device, &self.program(&TILED_SCATTER))
        })
    }

    /// The clusters' pipelines, built at their first use.
    pub fn clustered(&self) -> &clustered::Pipelines {
        self.clustered
            .get_or_init(|| clustered::Pipelines::new(&self.device, &self.program(&CLUSTERED)))
    }

    /// Z-binning's pipelines, built at their first use.
    pub fn zbin(&self) -> &zbin::Pipelines {
        self.zbin.get_or_init(|| {
            zbin::Pipelines::new(
                &self.device,
                &self.program(&ZBIN),
                &self.program(&ZBIN_SCATTER),
            )
        })
    }
}
