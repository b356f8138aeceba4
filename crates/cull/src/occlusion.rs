//! Culling by visibility's occluder test on the GPU: the f32 twin of
//! [`manylights_scene::occluders::hides`] (`occluder_hides` in
//! `shaders/cull/occlusion/occluders.wgsl`), the occluders as the GPU reads them, and a pass
//! that answers a batch of (light, cell) queries against them ([`OccluderTest`]), the twin's
//! test against its f64 oracle. A list pass that drops hidden lights will build on it.

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};
use manylights_gpu::pipeline::{self, UNIFORM, entry, storage};
use manylights_gpu::shaders::ShaderDef;
use manylights_gpu::timing::GpuTimer;
use manylights_gpu::{GpuContext, GpuError};
use manylights_scene::occluders::Occluder;
use wgpu::util::DeviceExt;

/// The occluder test's shader: `occluder_hides` and its batch entry point.
pub const OCCLUDER_TEST: ShaderDef = ShaderDef {
    name: "occlusion.occluder_test",
    consts: &[],
    files: &[
        manylights_gpu::shader_file!("cull/occlusion/occluders.wgsl"),
        manylights_gpu::shader_file!("cull/occlusion/occluder_test.wgsl"),
    ],
};

/// Mirror of WGSL `Occluder` (`shaders/cull/occlusion/occluders.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuOccluder {
    /// Corners (xyz), the fourth unused for a triangle.
    pub corners: [[f32; 4]; 4],
    /// Unit normal (xyz) and the corner count (w).
    pub normal: [f32; 4],
}
const _: () = assert!(size_of::<GpuOccluder>() == 80);

impl From<&Occluder> for GpuOccluder {
    fn from(o: &Occluder) -> Self {
        let mut corners = [[0.0; 4]; 4];
        for (c, p) in corners.iter_mut().zip(&o.corners) {
            *c = p.as_vec3().extend(0.0).to_array();
        }
        Self {
            corners,
            normal: o.normal.as_vec3().extend(o.corners.len() as f32).to_array(),
        }
    }
}

/// The margin the f32 test spares beyond an occluder's plane and inside its edges (besides a
/// shadow ray's lift) for a light at `light` and a cell about `cell`: 1e-4 of the largest
/// coordinate's magnitude (at least 1 m), some hundred times f32's rounding of the test's
/// arithmetic, so that where it says hidden, the f64 test with no margin says so too.
pub fn margin(light: Vec3, cell: Vec3) -> f32 {
    1e-4 * light.abs().max_element().max(cell.abs().max_element()).max(1.0)
}

/// One query: a light, the eight corners of its cell, and the margin.
#[derive(Clone, Copy, Debug)]
pub struct Query {
    /// The light's position.
    pub light: Vec3,
    /// The cell's corners.
    pub cell: [Vec3; 8],
    /// The margin spared ([`margin`]).
    pub margin: f32,
}

impl Query {
    /// The query of `light` and `cell` with [`margin`] (at the cell's first corner).
    pub fn new(light: DVec3, cell: &[DVec3; 8]) -> Self {
        let cell = cell.map(|c| c.as_vec3());
        Self {
            light: light.as_vec3(),
            cell,
            margin: margin(light.as_vec3(), cell[0]),
        }
    }
}

/// The occluder test's pass over a batch of queries.
pub struct OccluderTest {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl OccluderTest {
    /// The pass's pipeline.
    pub fn new(ctx: &GpuContext) -> Self {
        let d = &ctx.device;
        let c = wgpu::ShaderStages::COMPUTE;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("occlusion.occluder_test"),
            entries: &[
                entry(0, c, storage(true)),
                entry(1, c, storage(true)),
                entry(2, c, storage(false)),
                entry(3, c, UNIFORM),
            ],
        });
        let module = OCCLUDER_TEST.create(d);
        let pipeline = pipeline::compute(
            d,
            &module,
            &pipeline::layout(d, "occlusion.occluder_test", &[&layout]),
            "occluder_test",
        );
        Self { pipeline, layout }
    }

    /// For each query, 1 + the index of the first of `occluders` that hides its light from its
    /// cell, or 0.
    pub fn run(
        &self,
        ctx: &GpuContext,
        occluders: &[GpuOccluder],
        queries: &[Query],
    ) -> Result<Vec<u32>, GpuError> {
        let n = queries.len() as u32;
        if n == 0 {
            return Ok(Vec::new());
        }
        let words: Vec<[f32; 4]> = queries
            .iter()
            .flat_map(|q| {
                std::iter::once(q.light.extend(q.margin).to_array())
                    .chain(q.cell.iter().map(|c| c.extend(0.0).to_array()))
            })
            .collect();
        ctx.check_storage("the occluder queries' bytes", 16 * words.len() as u64)?;
        let d = &ctx.device;
        let init = |label, contents: &[u8], usage| {
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let queries_buf = init(
            "occlusion.queries",
            bytemuck::cast_slice(&words),
            wgpu::BufferUsages::STORAGE,
        );
        let mut occ = occluders.to_vec();
        if occ.is_empty() {
            occ.push(Zeroable::zeroed());
        }
        let occluders_buf = init(
            "occlusion.occluders",
            bytemuck::cast_slice(&occ),
            wgpu::BufferUsages::STORAGE,
        );
        let out = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("occlusion.hidden"),
            size: 4 * u64::from(n),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let params = init(
            "occlusion.params",
            bytemuck::cast_slice(&[n, occluders.len() as u32, 0, 0]),
            wgpu::BufferUsages::UNIFORM,
        );
        let group = pipeline::buffers_group(
            d,
            "occlusion.occluder_test",
            &self.layout,
            &[&queries_buf, &occluders_buf, &out, &params],
        );
        let groups = n.div_ceil(64);
        if groups > ctx.limits.max_compute_workgroups_per_dimension {
            return Err(GpuError::OverLimit {
                what: "occluder queries' workgroups".into(),
                value: groups.into(),
                limit: ctx.limits.max_compute_workgroups_per_dimension.into(),
                limit_name: "max_compute_workgroups_per_dimension",
            });
        }
        let mut timer = GpuTimer::untimed();
        let mut encoder = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("occlusion.occluder_test"),
        });
        pipeline::dispatch(
            &mut encoder,
            &mut timer,
            "occlusion.occluder_test",
            &self.pipeline,
            &[&group],
            (groups, 1),
        );
        ctx.submit_and_wait(encoder, "occlusion.occluder_test")?;
        let bytes = manylights_gpu::readback::read_buffer(ctx, &out, 0, 4 * u64::from(n))?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}
