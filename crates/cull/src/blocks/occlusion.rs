//! Culling by visibility (`cull.occlusion`, `shaders/cull/occlusion/occlusion_filter.wgsl`):
//! after a strategy's lists, each bin's list loses the lights one of the scene's occluders
//! hides from every point of the bin's cell, in place and in order, the dropped pairs counted
//! ([`crate::CullOutput::occluded`]). A cell is the tile's frustum widened by a pixel, between
//! the tile's depth bounds (tiled strategies) or its slice's boundaries (clusters); the test is
//! `occluder_hides` ([`crate::occlusion`]), conservative against the f64 one, so a dropped
//! light's shadow ray from any point of the cell is blocked: the lists keep every light the
//! shadowed exact set needs. Lists of a list a bin only: z-binning's are not.
//!
//! [`cell_corners`] is the cell in f64, the CPU twin's (tests compare the dropped pairs with
//! [`manylights_scene::occluders::hides`] over it).

use glam::{DMat4, DVec3, DVec4};
use manylights_gpu::GpuContext;
use manylights_gpu::pipeline::{self, UNIFORM, storage};
use manylights_gpu::shaders::ShaderDef;
use manylights_scene::occluders::Occluder;
use wgpu::util::DeviceExt;

use crate::Kernel;
use crate::culler::entry;
use crate::frame::Frame;
use crate::layout::{GROUPS_X, GpuCullParams, GpuTileDepth};

/// The most occluders the pass takes: a thread of its workgroup an occluder, each bin's
/// candidates in workgroup memory (`occlusion_filter.wgsl`).
pub const OCCLUDERS_MAX: usize = 64;
use crate::occlusion::GpuOccluder;
use crate::program::{DepthInput, Program};
use crate::record::{Buf, Step};
use crate::scan::groups_2d;
use crate::shaders::GEOMETRY;
use manylights_gpu::shaders::{FRAME, LIGHT, SCENE};

/// `cull.occlusion`'s shader.
pub const SHADER: ShaderDef = ShaderDef {
    name: "cull.occlusion",
    consts: crate::layout::CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        GEOMETRY,
        manylights_gpu::shader_file!("cull/occlusion/occluders.wgsl"),
        manylights_gpu::shader_file!("cull/occlusion/occlusion_filter.wgsl"),
    ],
};

/// The occluders of a scene on the GPU and the pass that drops the lights they hide.
pub struct Occlusion {
    kernel: Kernel,
    layout: wgpu::BindGroupLayout,
    occluders: wgpu::Buffer,
    params: wgpu::Buffer,
    count: u32,
}

impl Occlusion {
    /// The pass over `scene_layout` (the scene's group 0) and `occluders` (none: the pass does
    /// not run).
    pub fn new(
        ctx: &GpuContext,
        scene_layout: &wgpu::BindGroupLayout,
        occluders: &[Occluder],
    ) -> Self {
        let d = &ctx.device;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cull.occlusion.group1"),
            entries: &[
                entry(0, UNIFORM),
                entry(2, storage(true)),
                entry(6, storage(false)),
                entry(8, storage(true)),
                entry(7, storage(false)),
                entry(10, storage(false)),
                entry(12, storage(true)),
                entry(13, UNIFORM),
            ],
        });
        let program = Program::new(d, &SHADER, DepthInput::Samples(1), scene_layout, &layout);
        let (occluders, params, count) = Self::buffers(ctx, occluders);
        Self {
            kernel: program.pipeline(d, "occlusion_filter"),
            layout,
            occluders,
            params,
            count,
        }
    }

    /// Takes `occluders` in place of the pass's (its pipeline kept).
    pub fn set(&mut self, ctx: &GpuContext, occluders: &[Occluder]) {
        (self.occluders, self.params, self.count) = Self::buffers(ctx, occluders);
    }

    /// The occluders' buffer (a zeroed one where there is none) and the pass's uniform.
    fn buffers(ctx: &GpuContext, occluders: &[Occluder]) -> (wgpu::Buffer, wgpu::Buffer, u32) {
        let d = &ctx.device;
        let mut gpu: Vec<GpuOccluder> = occluders.iter().map(GpuOccluder::from).collect();
        let count = gpu.len() as u32;
        if gpu.is_empty() {
            gpu.push(bytemuck::Zeroable::zeroed());
        }
        let buffer = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("cull.occluders"),
            contents: bytemuck::cast_slice(&gpu),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let params = pipeline::uniform_buffer(
            d,
            "cull.occlusion.params",
            bytemuck::cast_slice(&[count, 0, 0, 0]),
        );
        (buffer, params, count)
    }

    /// The occluders.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// The pass's group over `f`'s buffers and the lists' `indices`.
    pub(crate) fn group(&self, f: &Frame<'_>, indices: &wgpu::Buffer) -> wgpu::BindGroup {
        let buffers = [
            (0, f.params_buf()),
            (2, &f.tile_depth),
            (6, f.ranges()),
            (8, f.occupancy()),
            (7, indices),
            (10, &f.stats),
            (12, &self.occluders),
            (13, &self.params),
        ];
        let entries: Vec<wgpu::BindGroupEntry<'_>> = buffers
            .iter()
            .map(|&(binding, b)| wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            })
            .collect();
        f.ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("cull.occlusion.group1"),
            layout: &self.layout,
            entries: &entries,
        })
    }

    /// `cull.occlusion` over `group` ([`Occlusion::group`]): a workgroup a bin.
    pub(crate) fn step<'a>(&'a self, f: &Frame<'_>, group: &'a wgpu::BindGroup) -> Step<'a> {
        Step::pass(
            "cull.occlusion",
            &self.kernel,
            group,
            groups_2d(f.params.bins, GROUPS_X),
            &[
                Buf::Lights,
                Buf::TileDepth,
                Buf::Occupancy,
                Buf::Ranges,
                Buf::Indices,
                Buf::Occluders,
            ],
            &[Buf::Ranges, Buf::Indices, Buf::Stats],
        )
    }
}

/// The view a culling run saw, as the cell corners need it: the frame's `clip_from_view` and
/// `world_from_view`, and the image's size.
#[derive(Clone, Copy, Debug)]
pub struct CellView {
    /// The projection.
    pub clip_from_view: DMat4,
    /// The inverse of the view matrix.
    pub world_from_view: DMat4,
    /// The image's size in pixels.
    pub size: (u32, u32),
}

/// The world-space corners of bin `bin`'s cell as `cull.occlusion` takes them (its tile's
/// frustum widened by a pixel, between `tile_depth`'s bounds with one slice, the cluster's
/// pixels' depth bounds in `occupancy` with the box test, or else the slice's boundaries,
/// widened by 1e-4 of their depth), or `None` where the bin has no covered pixel.
pub fn cell_corners(
    p: &GpuCullParams,
    view: &CellView,
    (tile_depth, occupancy): (&[GpuTileDepth], &[u32]),
    bin: u32,
) -> Option<[DVec3; 8]> {
    let tiles = p.tiles_x * p.tiles_y;
    let (t, s) = (bin % tiles, bin / tiles);
    let (mut d0, mut d1) = if p.slices <= 1 {
        let td = tile_depth[t as usize];
        if td.covered == 0 {
            return None;
        }
        (f64::from(td.dmin), f64::from(td.dmax))
    } else if p.flags & crate::layout::CULL_FLAG_TILE_BOX != 0 {
        if occupancy[bin as usize] == 0 {
            return None;
        }
        let near = occupancy[(p.bins + 2 * bin) as usize];
        let far = occupancy[(p.bins + 2 * bin + 1) as usize];
        (
            f64::from(crate::geometry::from_ordered_bits(!near)),
            f64::from(crate::geometry::from_ordered_bits(far)),
        )
    } else {
        let edge = |s| f64::from(crate::geometry::slice_edge(p, s));
        let d0 = if s > 0 { edge(s) } else { f64::from(p.near) };
        let d1 = if s + 1 < p.slices {
            edge(s + 1)
        } else {
            f64::from(p.far)
        };
        (d0, d1)
    };
    d0 *= 1.0 - 1e-4;
    d1 *= 1.0 + 1e-4;
    let (w, h) = (f64::from(view.size.0), f64::from(view.size.1));
    let (tx, ty) = (t % p.tiles_x, t / p.tiles_x);
    let px = |x: u32| f64::from((x * p.tile_size).min(view.size.0));
    let py = |y: u32| f64::from((y * p.tile_size).min(view.size.1));
    let x = [
        (px(tx) - 1.0) / w * 2.0 - 1.0,
        (px(tx + 1) + 1.0) / w * 2.0 - 1.0,
    ];
    let y = [
        1.0 - (py(ty + 1) + 1.0) / h * 2.0,
        1.0 - (py(ty) - 1.0) / h * 2.0,
    ];
    let m = view.clip_from_view;
    Some(std::array::from_fn(|c| {
        let (nx, ny, z) = (x[c & 1], y[(c >> 1) & 1], -[d0, d1][c >> 2]);
        // view_point in shaders/cull/common/geometry.wgsl, in f64.
        let wc = m.z_axis.w * z + m.w_axis.w;
        let v = DVec3::new(
            (nx * wc - m.z_axis.x * z - m.w_axis.x) / m.x_axis.x,
            (ny * wc - m.z_axis.y * z - m.w_axis.y) / m.y_axis.y,
            z,
        );
        (view.world_from_view * DVec4::from((v, 1.0))).truncate()
    }))
}
