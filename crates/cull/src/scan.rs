//! The portable GPU exclusive scan (`shaders/scan/scan.wgsl`), in place over a u32 buffer:
//! block scans of 1,024 elements, the block totals scanned recursively, then added back.
//! It assumes no subgroup size, so it runs on any adapter.

use manylights_gpu::shader_file;
use manylights_gpu::shaders::ShaderDef;
use manylights_gpu::timing::GpuTimer;
use manylights_gpu::{GpuContext, pipeline};

use crate::layout::{SCAN_BLOCK, SCAN_CONSTS, SCAN_MAX_GROUPS_X};

/// The scan shader.
pub const SHADER: ShaderDef = ShaderDef {
    name: "scan",
    consts: SCAN_CONSTS,
    files: &[shader_file!("scan/scan.wgsl")],
};

/// The block scan using subgroup operations (built only where the device has them).
pub const SUBGROUP_SHADER: ShaderDef = ShaderDef {
    name: "scan.subgroup",
    consts: SCAN_CONSTS,
    files: &[
        shader_file!("scan/scan.wgsl"),
        shader_file!("scan/scan_subgroup.wgsl"),
    ],
};

/// Which block scan to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScanPath {
    /// Workgroup memory only; assumes no subgroup size.
    Portable,
    /// Subgroup inclusive adds within subgroups, workgroup memory across them.
    Subgroup,
}

/// Scan pipelines.
pub struct Scan {
    layout: wgpu::BindGroupLayout,
    blocks: wgpu::ComputePipeline,
    add: wgpu::ComputePipeline,
    /// The path in use.
    pub path: ScanPath,
}

/// Workgroup counts (x, y) for `groups` workgroups laid out in rows of `SCAN_MAX_GROUPS_X`.
pub fn groups_2d(groups: u32, row: u32) -> (u32, u32) {
    if groups <= row {
        (groups, 1)
    } else {
        (row, groups.div_ceil(row))
    }
}

impl Scan {
    /// Builds the pipelines with the subgroup path where the device has subgroups.
    pub fn new(ctx: &GpuContext) -> Self {
        Self::with_path(
            ctx,
            if ctx.features.subgroups {
                ScanPath::Subgroup
            } else {
                ScanPath::Portable
            },
        )
        .expect("the subgroup path is chosen only where subgroups exist")
    }

    /// Builds the pipelines of one path; `None` for the subgroup path on a device without
    /// subgroups.
    pub fn with_path(ctx: &GpuContext, path: ScanPath) -> Option<Self> {
        if path == ScanPath::Subgroup && !ctx.features.subgroups {
            return None;
        }
        let d = &ctx.device;
        let c = wgpu::ShaderStages::COMPUTE;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scan"),
            entries: &[
                pipeline::entry(0, c, pipeline::UNIFORM),
                pipeline::entry(1, c, pipeline::storage(false)),
                pipeline::entry(2, c, pipeline::storage(false)),
            ],
        });
        let module = SHADER.create(d);
        let pl = pipeline::layout(d, "scan", &[&layout]);
        let blocks = match path {
            ScanPath::Subgroup => {
                pipeline::compute(d, &SUBGROUP_SHADER.create(d), &pl, "scan_blocks_subgroup")
            }
            ScanPath::Portable => pipeline::compute(d, &module, &pl, "scan_blocks"),
        };
        Some(Self {
            blocks,
            add: pipeline::compute(d, &module, &pl, "scan_add"),
            layout,
            path,
        })
    }

    /// Encodes an in-place exclusive scan of the first `n` u32 of `data`.
    pub fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        data: &wgpu::Buffer,
        n: u32,
        timer: &mut GpuTimer,
    ) {
        if n == 0 {
            return;
        }
        let blocks = n.div_ceil(SCAN_BLOCK);
        let sums = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scan.block_sums"),
            size: u64::from(blocks) * 4,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let params = pipeline::uniform_buffer(
            &ctx.device,
            "scan.params",
            bytemuck::cast_slice(&[n, 0, 0, 0]),
        );
        let group =
            pipeline::buffers_group(&ctx.device, "scan", &self.layout, &[&params, data, &sums]);
        let (gx, gy) = groups_2d(blocks, SCAN_MAX_GROUPS_X);
        pipeline::dispatch(
            encoder,
            timer,
            "scan.blocks",
            &self.blocks,
            &[&group],
            (gx, gy),
        );
        if blocks > 1 {
            self.encode(ctx, encoder, &sums, blocks, timer);
            pipeline::dispatch(encoder, timer, "scan.add", &self.add, &[&group], (gx, gy));
        }
    }
}

/// The CPU oracle: exclusive prefix sum (wrapping, as u32 on the GPU).
pub fn cpu(data: &[u32]) -> Vec<u32> {
    let mut acc = 0u32;
    data.iter()
        .map(|&x| {
            let out = acc;
            acc = acc.wrapping_add(x);
            out
        })
        .collect()
}
