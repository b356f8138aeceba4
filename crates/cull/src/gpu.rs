//! The GPU side: pipelines of every culling pass, and their orchestration for one frame.

use manylights_gpu::shaders::{FRAME, LIGHT, ShaderDef, ShaderFile};
use manylights_gpu::timing::GpuTimer;
use manylights_gpu::{GpuContext, GpuError, GpuScene, readback, shader_file};
use wgpu::util::DeviceExt;

use crate::layout::{CULL_CONSTS, GROUPS_X, GpuCullParams, GpuTileDepth};
use crate::scan::{Scan, groups_2d};
use crate::{CullError, Strategy};

const COMMON: ShaderFile = shader_file!("cull/common.wgsl");
const LISTS: ShaderFile = shader_file!("cull/lists.wgsl");
const LOOKUP: ShaderFile = shader_file!("cull/lookup.wgsl");

/// `cull.depth_bounds`.
pub const DEPTH_BOUNDS: ShaderDef = ShaderDef {
    name: "cull.depth_bounds",
    consts: CULL_CONSTS,
    files: &[FRAME, LIGHT, COMMON, shader_file!("cull/depth_bounds.wgsl")],
};
/// `cull.tiled_gather` (also `cull.depth_mask`, with its flag) and `cull.finalize`.
pub const TILED_GATHER: ShaderDef = ShaderDef {
    name: "cull.tiled_gather",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        COMMON,
        LISTS,
        shader_file!("cull/tiled_gather.wgsl"),
    ],
};
/// `cull.clustered` and `cull.occupancy`.
pub const CLUSTERED: ShaderDef = ShaderDef {
    name: "cull.clustered",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        COMMON,
        LISTS,
        shader_file!("cull/clustered.wgsl"),
    ],
};
/// `cull.lights_per_pixel`: the shared lookup, per pixel.
pub const LIGHTS_PER_PIXEL: ShaderDef = ShaderDef {
    name: "cull.lights_per_pixel",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        COMMON,
        LOOKUP,
        shader_file!("cull/lights_per_pixel.wgsl"),
    ],
};

/// Every shader of this crate.
pub const SHADERS: &[ShaderDef] = &[
    DEPTH_BOUNDS,
    TILED_GATHER,
    CLUSTERED,
    LIGHTS_PER_PIXEL,
    crate::scan::SHADER,
];

/// Light lists read back to the host.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BinLists {
    /// (offset, count) per bin.
    pub ranges: Vec<[u32; 2]>,
    /// Light indices.
    pub indices: Vec<u32>,
}

impl BinLists {
    /// The lights of bin `b`.
    pub fn list(&self, b: usize) -> &[u32] {
        let [o, c] = self.ranges[b];
        &self.indices[o as usize..(o + c) as usize]
    }

    /// The lights of bin `b`, sorted.
    pub fn sorted(&self, b: usize) -> Vec<u32> {
        let mut v = self.list(b).to_vec();
        v.sort_unstable();
        v
    }
}

/// The lists of one frame on the GPU, ready for shading.
pub struct CullOutput {
    /// The parameters they were built with.
    pub params: GpuCullParams,
    /// The `CullParams` uniform.
    pub params_buf: wgpu::Buffer,
    /// `bin_ranges`.
    pub ranges: wgpu::Buffer,
    /// `light_indices` (at least one element).
    pub indices: wgpu::Buffer,
    /// Total list entries.
    pub total: u32,
    /// Per-tile depth data (tiled strategies).
    pub tile_depth: wgpu::Buffer,
    /// Cluster occupancy (clusters with `skip_empty`).
    pub occupancy: wgpu::Buffer,
}

impl CullOutput {
    /// Bytes of the lists: ranges plus indices.
    pub fn list_bytes(&self) -> u64 {
        u64::from(self.params.bins) * 8 + u64::from(self.total) * 4
    }

    /// Reads the lists back.
    pub fn read(&self, ctx: &GpuContext) -> Result<BinLists, GpuError> {
        let ranges = readback::read_buffer(ctx, &self.ranges, 0, u64::from(self.params.bins) * 8)?;
        let indices = if self.total > 0 {
            readback::read_buffer(ctx, &self.indices, 0, u64::from(self.total) * 4)?
        } else {
            Vec::new()
        };
        Ok(BinLists {
            ranges: bytemuck::pod_collect_to_vec(&ranges),
            indices: bytemuck::pod_collect_to_vec(&indices),
        })
    }

    /// Reads the per-tile depth data back (meaningful for tiled strategies).
    pub fn read_tile_depth(&self, ctx: &GpuContext) -> Result<Vec<GpuTileDepth>, GpuError> {
        let n = u64::from(self.params.tiles_x * self.params.tiles_y);
        Ok(bytemuck::pod_collect_to_vec(&readback::read_buffer(
            ctx,
            &self.tile_depth,
            0,
            n * 16,
        )?))
    }

    /// Reads the cluster occupancy back (meaningful with `skip_empty`).
    pub fn read_occupancy(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        Ok(bytemuck::pod_collect_to_vec(&readback::read_buffer(
            ctx,
            &self.occupancy,
            0,
            u64::from(self.params.bins) * 4,
        )?))
    }
}

/// Pipelines of every culling pass.
pub struct Culler {
    layout: wgpu::BindGroupLayout,
    /// Layout of group 1 for list consumers (shading, `cull.lights_per_pixel`): 0 params,
    /// 1 ranges, 2 indices, 3 depth, 4 a per-pixel output.
    pub lists_layout: wgpu::BindGroupLayout,
    depth_bounds: wgpu::ComputePipeline,
    gather_count: wgpu::ComputePipeline,
    gather_fill: wgpu::ComputePipeline,
    clustered_count: wgpu::ComputePipeline,
    clustered_fill: wgpu::ComputePipeline,
    occupancy: wgpu::ComputePipeline,
    finalize: wgpu::ComputePipeline,
    lights_per_pixel: wgpu::ComputePipeline,
    scan: Scan,
}

fn entry(binding: u32, ty: wgpu::BindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE | wgpu::ShaderStages::FRAGMENT,
        ty,
        count: None,
    }
}

fn storage(read_only: bool) -> wgpu::BindingType {
    wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Storage { read_only },
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

const UNIFORM: wgpu::BindingType = wgpu::BindingType::Buffer {
    ty: wgpu::BufferBindingType::Uniform,
    has_dynamic_offset: false,
    min_binding_size: None,
};
const DEPTH: wgpu::BindingType = wgpu::BindingType::Texture {
    sample_type: wgpu::TextureSampleType::Depth,
    view_dimension: wgpu::TextureViewDimension::D2,
    multisampled: false,
};

/// Compute pipelines for the entry points of one shader, over group 0 (the scene) and `group1`.
fn pipelines<const N: usize>(
    d: &wgpu::Device,
    def: &ShaderDef,
    scene_layout: &wgpu::BindGroupLayout,
    group1: &wgpu::BindGroupLayout,
    entries: [&str; N],
) -> [wgpu::ComputePipeline; N] {
    let module = def.create(d);
    let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(def.name),
        bind_group_layouts: &[Some(scene_layout), Some(group1)],
        immediate_size: 0,
    });
    entries.map(|e| {
        d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(e),
            layout: Some(&pl),
            module: &module,
            entry_point: Some(e),
            compilation_options: Default::default(),
            cache: None,
        })
    })
}

impl Culler {
    /// Builds every pipeline for scenes laid out as [`GpuScene`].
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Self {
        let d = &ctx.device;
        let mut entries = vec![entry(0, UNIFORM), entry(1, DEPTH)];
        entries.extend((2..=8).map(|b| entry(b, storage(false))));
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cull.group1"),
            entries: &entries,
        });
        let lists_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lists.group1"),
            entries: &[
                entry(0, UNIFORM),
                entry(1, storage(true)),
                entry(2, storage(true)),
                entry(3, DEPTH),
                entry(4, storage(false)),
            ],
        });
        let scene_layout = &scene.layout;
        let [depth_bounds] = pipelines(d, &DEPTH_BOUNDS, scene_layout, &layout, ["depth_bounds"]);
        let [gather_count, gather_fill, finalize] = pipelines(
            d,
            &TILED_GATHER,
            scene_layout,
            &layout,
            ["gather_count", "gather_fill", "finalize"],
        );
        let [clustered_count, clustered_fill, occupancy] = pipelines(
            d,
            &CLUSTERED,
            scene_layout,
            &layout,
            ["clustered_count", "clustered_fill", "cluster_occupancy"],
        );
        let [lights_per_pixel] = pipelines(
            d,
            &LIGHTS_PER_PIXEL,
            scene_layout,
            &lists_layout,
            ["lights_per_pixel"],
        );
        Self {
            layout,
            lists_layout,
            depth_bounds,
            gather_count,
            gather_fill,
            clustered_count,
            clustered_fill,
            occupancy,
            finalize,
            lights_per_pixel,
            scan: Scan::new(ctx),
        }
    }

    /// Runs `strategy` over the depth buffer `depth` of `scene` (whose frame uniform is set for
    /// the depth buffer's size), with the camera's near and far distances and the relative
    /// `slack`. Two submissions: counts and scan, then (with the list sized exactly from the
    /// total) fill and finalize.
    #[expect(
        clippy::too_many_arguments,
        reason = "one frame's inputs, each distinct"
    )]
    pub fn run(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::Texture,
        strategy: &Strategy,
        near: f32,
        far: f32,
        slack: f32,
        timer: &mut GpuTimer,
    ) -> Result<CullOutput, CullError> {
        strategy.validate()?;
        let (w, h) = (depth.width(), depth.height());
        let params = strategy.params(w, h, scene.light_count, near, far, slack);
        let d = &ctx.device;
        let tiles = u64::from(params.tiles_x * params.tiles_y);
        let bins = u64::from(params.bins);
        ctx.check_storage("cull bins", bins * 8)?;
        let buf = |label, size: u64, extra| {
            d.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(4),
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST
                    | extra,
                mapped_at_creation: false,
            })
        };
        let params_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("cull.params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let tile_depth = buf("cull.tile_depth", tiles * 16, wgpu::BufferUsages::empty());
        let counts = buf(
            "cull.bin_counts",
            (bins + 1) * 4,
            wgpu::BufferUsages::empty(),
        );
        let offsets = buf(
            "cull.bin_offsets",
            (bins + 1) * 4,
            wgpu::BufferUsages::empty(),
        );
        let cursors = buf("cull.bin_cursors", bins * 4, wgpu::BufferUsages::empty());
        let ranges = buf("cull.bin_ranges", bins * 8, wgpu::BufferUsages::empty());
        let occupancy = buf("cull.occupancy", bins * 4, wgpu::BufferUsages::empty());
        let depth_view = depth.create_view(&wgpu::TextureViewDescriptor {
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        });
        fn b(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: buffer.as_entire_binding(),
            }
        }
        let group = |indices: &wgpu::Buffer| {
            d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("cull.group1"),
                layout: &self.layout,
                entries: &[
                    b(0, &params_buf),
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&depth_view),
                    },
                    b(2, &tile_depth),
                    b(3, &counts),
                    b(4, &offsets),
                    b(5, &cursors),
                    b(6, &ranges),
                    b(7, indices),
                    b(8, &occupancy),
                ],
            })
        };
        let placeholder = buf(
            "cull.light_indices.placeholder",
            4,
            wgpu::BufferUsages::empty(),
        );
        let group_a = group(&placeholder);
        let light_groups = groups_2d(scene.light_count.div_ceil(64), GROUPS_X);
        let name = strategy.name();
        let is_clustered = matches!(strategy, Strategy::Clustered { .. });
        let (count_pipe, fill_pipe) = if is_clustered {
            (&self.clustered_count, &self.clustered_fill)
        } else {
            (&self.gather_count, &self.gather_fill)
        };
        let dispatch_main = |pass: &mut wgpu::ComputePass<'_>| {
            if is_clustered {
                pass.dispatch_workgroups(light_groups.0, light_groups.1, 1);
            } else {
                pass.dispatch_workgroups(params.tiles_x, params.tiles_y, 1);
            }
        };

        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("cull.count"),
        });
        enc.clear_buffer(&counts, 0, None);
        enc.clear_buffer(&cursors, 0, None);
        enc.clear_buffer(&occupancy, 0, None);
        {
            let mut compute =
                |enc: &mut wgpu::CommandEncoder,
                 label: &str,
                 pipe: &wgpu::ComputePipeline,
                 g: &wgpu::BindGroup,
                 f: &dyn Fn(&mut wgpu::ComputePass<'_>)| {
                    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some(label),
                        timestamp_writes: timer.compute_pass(label),
                    });
                    pass.set_pipeline(pipe);
                    pass.set_bind_group(0, &scene.bind_group, &[]);
                    pass.set_bind_group(1, g, &[]);
                    f(&mut pass);
                };
            if is_clustered {
                if params.flags & crate::layout::CULL_FLAG_SKIP_EMPTY != 0 {
                    compute(
                        &mut enc,
                        "cull.occupancy",
                        &self.occupancy,
                        &group_a,
                        &|p| p.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1),
                    );
                }
            } else {
                compute(
                    &mut enc,
                    "cull.depth_bounds",
                    &self.depth_bounds,
                    &group_a,
                    &|p| p.dispatch_workgroups(params.tiles_x, params.tiles_y, 1),
                );
            }
            compute(
                &mut enc,
                &format!("cull.{name}.count"),
                count_pipe,
                &group_a,
                &dispatch_main,
            );
        }
        enc.copy_buffer_to_buffer(&counts, 0, &offsets, 0, (bins + 1) * 4);
        self.scan
            .encode(ctx, &mut enc, &offsets, params.bins + 1, timer);
        ctx.submit_and_wait(enc, "culling: count and scan")?;
        let total_bytes = readback::read_buffer(ctx, &offsets, bins * 4, 4)?;
        let total = u32::from_le_bytes(total_bytes[..4].try_into().expect("4 bytes"));
        ctx.check_storage("light list entries", u64::from(total) * 4)?;

        let indices = buf(
            "cull.light_indices",
            u64::from(total) * 4,
            wgpu::BufferUsages::empty(),
        );
        let group_b = group(&indices);
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("cull.fill"),
        });
        let bin_groups = groups_2d(params.bins.div_ceil(64), GROUPS_X);
        {
            let mut compute =
                |enc: &mut wgpu::CommandEncoder,
                 label: &str,
                 pipe: &wgpu::ComputePipeline,
                 f: &dyn Fn(&mut wgpu::ComputePass<'_>)| {
                    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some(label),
                        timestamp_writes: timer.compute_pass(label),
                    });
                    pass.set_pipeline(pipe);
                    pass.set_bind_group(0, &scene.bind_group, &[]);
                    pass.set_bind_group(1, &group_b, &[]);
                    f(&mut pass);
                };
            compute(
                &mut enc,
                &format!("cull.{name}.fill"),
                fill_pipe,
                &dispatch_main,
            );
            compute(&mut enc, "cull.finalize", &self.finalize, &|p| {
                p.dispatch_workgroups(bin_groups.0, bin_groups.1, 1)
            });
        }
        timer.resolve(&mut enc);
        ctx.submit_and_wait(enc, "culling: fill")?;
        Ok(CullOutput {
            params,
            params_buf,
            ranges,
            indices,
            total,
            tile_depth,
            occupancy,
        })
    }

    /// The length of the list each pixel reads through the shared lookup (0 for background).
    pub fn lights_per_pixel(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::Texture,
        lists: &CullOutput,
    ) -> Result<Vec<u32>, GpuError> {
        let (w, h) = (depth.width(), depth.height());
        let d = &ctx.device;
        let out = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("cull.lights_per_pixel"),
            size: u64::from(w * h) * 4,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let view = depth.create_view(&wgpu::TextureViewDescriptor {
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        });
        let group = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lists.group1"),
            layout: &self.lists_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: lists.params_buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: lists.ranges.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: lists.indices.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: out.as_entire_binding(),
                },
            ],
        });
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("cull.lights_per_pixel"),
        });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("cull.lights_per_pixel"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.lights_per_pixel);
            pass.set_bind_group(0, &scene.bind_group, &[]);
            pass.set_bind_group(1, &group, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        ctx.submit_and_wait(enc, "lights per pixel")?;
        Ok(bytemuck::pod_collect_to_vec(&readback::read_buffer(
            ctx,
            &out,
            0,
            u64::from(w * h) * 4,
        )?))
    }
}
