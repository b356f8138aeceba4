//! The BVH of a scene's opaque triangles that shadow rays traverse: built once a scene on the
//! CPU (obvhs's PLOC builder with reinsertion, leaves of up to 8 triangles), its nodes and
//! triangles laid out for the GPU and uploaded ([`GpuBvh`]), and walked in WGSL by an any-hit
//! shadow ray (`shaders/common/bvh.wgsl`, `bvh_blocked`: the first crossing ends it).
//! [`ShadowRays`] traces a batch of segments, one a thread (`shadow_rays.trace`): the
//! traversal's test against `manylights_scene::ray`, its f64 oracle, and the rate of shadow
//! rays a second. Glass and other transparent surfaces are left out: they cast no shadow.

use std::time::Duration;

use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec3A};
use manylights_scene::Scene;
use manylights_scene::ray::opaque_triangles;
use wgpu::util::DeviceExt;

use crate::pipeline::{self, UNIFORM, entry, storage};
use crate::shaders::{ShaderDef, WgslConst};
use crate::timing::{GpuTimer, PassTiming};
use crate::{GpuContext, GpuError};

/// The traversal stack's depth: a tree deeper than this less one is refused at its build.
pub const BVH_STACK: u32 = 64;

/// The shadow rays' pass over a batch of segments.
pub const SHADOW_RAYS: ShaderDef = ShaderDef {
    name: "shadow_rays.trace",
    consts: &[
        WgslConst::U32("BVH_GROUP", 1),
        WgslConst::U32("BVH_BINDING", 0),
    ],
    files: &[
        crate::shaders::BVH,
        crate::shader_file!("rays/shadow_rays.wgsl"),
    ],
};

/// Threads per workgroup of the shadow rays' pass.
const WORKGROUP: u32 = 64;

/// Host mirror of `BvhNode` in `shaders/common/bvh.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    /// The box's least corner.
    pub lo: [f32; 3],
    /// 0 for an inner node; a leaf's triangles.
    pub count: u32,
    /// The box's greatest corner.
    pub hi: [f32; 3],
    /// An inner node's first child (the second follows it), or a leaf's first triangle.
    pub first: u32,
}

/// Host mirror of `BvhTriangle`: the three corners, each `[x, y, z, 0]`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhTriangle {
    /// The first corner.
    pub v0: [f32; 4],
    /// The second.
    pub v1: [f32; 4],
    /// The third.
    pub v2: [f32; 4],
}

/// A scene's BVH as the GPU reads it: node 0 the root, the triangles in leaf order.
#[derive(Clone, Debug, Default)]
pub struct SceneBvh {
    /// The nodes.
    pub nodes: Vec<BvhNode>,
    /// The opaque triangles, in the order the leaves hold them.
    pub triangles: Vec<BvhTriangle>,
    /// The scene's index of each of `triangles` among its opaque ones
    /// (`manylights_scene::ray::opaque_triangles`).
    pub source: Vec<u32>,
    /// The tree's depth (the root alone: 1).
    pub depth: u32,
    /// The build's time on the CPU.
    pub build: Duration,
}

impl SceneBvh {
    /// The BVH of `scene`'s opaque triangles; an error where its tree is deeper than the
    /// traversal's stack holds.
    pub fn build(scene: &Scene) -> Result<Self, GpuError> {
        Self::of_triangles(&opaque_triangles(scene))
    }

    /// The BVH of `tris`, each its three corners.
    pub fn of_triangles(tris: &[[Vec3; 3]]) -> Result<Self, GpuError> {
        let start = std::time::Instant::now();
        if tris.is_empty() {
            // One leaf of one degenerate triangle (of no source), which no segment crosses.
            return Ok(Self {
                nodes: vec![BvhNode {
                    count: 1,
                    ..BvhNode::default()
                }],
                triangles: vec![BvhTriangle::default()],
                depth: 1,
                build: start.elapsed(),
                ..Self::default()
            });
        }
        let input: Vec<obvhs::triangle::Triangle> = tris
            .iter()
            .map(|t| obvhs::triangle::Triangle {
                v0: Vec3A::from(t[0]),
                v1: Vec3A::from(t[1]),
                v2: Vec3A::from(t[2]),
            })
            .collect();
        let bvh = obvhs::bvh2::builder::build_bvh2_from_tris(
            &input,
            obvhs::BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        let source = bvh.primitive_indices.clone();
        let triangles = source
            .iter()
            .map(|&i| {
                let [v0, v1, v2] = tris[i as usize].map(|c| [c.x, c.y, c.z, 0.0]);
                BvhTriangle { v0, v1, v2 }
            })
            .collect();
        let nodes: Vec<BvhNode> = bvh
            .nodes
            .iter()
            .map(|n| {
                let (lo, hi) = (Vec3::from(n.aabb.min), Vec3::from(n.aabb.max));
                // A few ulps of slack, so that the f32 box test keeps what the f32 triangle
                // test crosses (flat boxes of axis-aligned walls included).
                let slack = (lo.abs().max(hi.abs()) * 8.0 * f32::EPSILON) + Vec3::splat(1e-7);
                BvhNode {
                    lo: (lo - slack).to_array(),
                    count: n.prim_count,
                    hi: (hi + slack).to_array(),
                    first: n.first_index,
                }
            })
            .collect();
        let depth = depth_of(&nodes);
        if depth >= BVH_STACK {
            return Err(GpuError::OverCapacity {
                what: "the BVH's depth".into(),
                value: u64::from(depth),
                limit: u64::from(BVH_STACK - 1),
                why: "that the shadow rays' traversal stack holds (BVH_STACK)",
            });
        }
        Ok(Self {
            nodes,
            triangles,
            source,
            depth,
            build: start.elapsed(),
        })
    }
}

/// The depth of the tree under node 0.
fn depth_of(nodes: &[BvhNode]) -> u32 {
    let mut deepest = 0;
    let mut stack = vec![(0u32, 1u32)];
    while let Some((i, d)) = stack.pop() {
        deepest = deepest.max(d);
        let n = nodes[i as usize];
        if n.count == 0 {
            stack.push((n.first, d + 1));
            stack.push((n.first + 1, d + 1));
        }
    }
    deepest
}

/// A scene's BVH on the GPU: its nodes and triangles (bindings 0 and 1 of `BVH_GROUP`).
pub struct GpuBvh {
    /// The nodes.
    pub nodes: wgpu::Buffer,
    /// The triangles.
    pub triangles: wgpu::Buffer,
    /// How many triangles it holds.
    pub triangle_count: u32,
}

impl GpuBvh {
    /// Uploads `bvh`; an error where a buffer exceeds the device's storage bindings.
    pub fn upload(ctx: &GpuContext, bvh: &SceneBvh) -> Result<Self, GpuError> {
        let node_bytes = std::mem::size_of_val(bvh.nodes.as_slice()) as u64;
        let tri_bytes = std::mem::size_of_val(bvh.triangles.as_slice()) as u64;
        ctx.check_storage("the BVH's nodes' bytes", node_bytes)?;
        ctx.check_storage("the BVH's triangles' bytes", tri_bytes)?;
        let buffer = |label, bytes: &[u8]| {
            ctx.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: if bytes.is_empty() { &[0u8; 48] } else { bytes },
                    usage: wgpu::BufferUsages::STORAGE,
                })
        };
        Ok(Self {
            nodes: buffer("bvh.nodes", bytemuck::cast_slice(&bvh.nodes)),
            triangles: buffer("bvh.triangles", bytemuck::cast_slice(&bvh.triangles)),
            triangle_count: bvh.triangles.len() as u32,
        })
    }

    /// The bind group of its buffers under `layout` ([`GpuBvh::layout`]).
    pub fn group(&self, ctx: &GpuContext, layout: &wgpu::BindGroupLayout) -> wgpu::BindGroup {
        pipeline::buffers_group(&ctx.device, "bvh", layout, &[&self.nodes, &self.triangles])
    }

    /// The layout of its bind group, for the stages `stages`.
    pub fn layout(ctx: &GpuContext, stages: wgpu::ShaderStages) -> wgpu::BindGroupLayout {
        ctx.device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("bvh"),
                entries: &[
                    entry(0, stages, storage(true)),
                    entry(1, stages, storage(true)),
                ],
            })
    }
}

/// What one batch of shadow rays gave.
#[derive(Clone, Debug)]
pub struct Traced {
    /// Whether each segment is blocked.
    pub blocked: Vec<bool>,
    /// The pass's GPU time, where timed.
    pub gpu: Option<Vec<PassTiming>>,
}

/// The shadow rays' pass: segments, one a thread, through a [`GpuBvh`].
pub struct ShadowRays {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    bvh_layout: wgpu::BindGroupLayout,
}

impl ShadowRays {
    /// The pass's pipeline.
    pub fn new(ctx: &GpuContext) -> Self {
        let d = &ctx.device;
        let c = wgpu::ShaderStages::COMPUTE;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadow_rays.trace"),
            entries: &[
                entry(0, c, storage(true)),
                entry(1, c, storage(false)),
                entry(2, c, UNIFORM),
            ],
        });
        let bvh_layout = GpuBvh::layout(ctx, c);
        let module = SHADOW_RAYS.create(d);
        let pipeline = pipeline::compute(
            d,
            &module,
            &pipeline::layout(d, "shadow_rays.trace", &[&layout, &bvh_layout]),
            "trace",
        );
        Self {
            pipeline,
            layout,
            bvh_layout,
        }
    }

    /// Traces the segments `rays` (from, to) through `bvh`.
    pub fn trace(
        &self,
        ctx: &GpuContext,
        bvh: &GpuBvh,
        rays: &[(Vec3, Vec3)],
    ) -> Result<Traced, GpuError> {
        let n = rays.len() as u32;
        if n == 0 {
            return Ok(Traced {
                blocked: Vec::new(),
                gpu: None,
            });
        }
        let ends: Vec<[f32; 4]> = rays
            .iter()
            .flat_map(|(a, b)| [a.extend(0.0).to_array(), b.extend(0.0).to_array()])
            .collect();
        ctx.check_storage("the shadow rays' bytes", 32 * u64::from(n))?;
        let d = &ctx.device;
        let rays_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("shadow_rays.rays"),
            contents: bytemuck::cast_slice(&ends),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let out = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shadow_rays.blocked"),
            size: 4 * u64::from(n),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let needed = n.div_ceil(WORKGROUP);
        let max = ctx.limits.max_compute_workgroups_per_dimension;
        let groups = (needed.min(max), needed.div_ceil(max));
        let params = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("shadow_rays.params"),
            contents: bytemuck::cast_slice(&[n, groups.0 * WORKGROUP, 0, 0]),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let group = pipeline::buffers_group(
            d,
            "shadow_rays.trace",
            &self.layout,
            &[&rays_buf, &out, &params],
        );
        let bvh_group = bvh.group(ctx, &self.bvh_layout);
        let mut timer = GpuTimer::new(ctx, 1);
        let mut encoder = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("shadow_rays"),
        });
        pipeline::dispatch(
            &mut encoder,
            &mut timer,
            "shadow_rays.trace",
            &self.pipeline,
            &[&group, &bvh_group],
            groups,
        );
        timer.resolve(&mut encoder);
        ctx.submit_and_wait(encoder, "shadow_rays.trace")?;
        let bytes = crate::readback::read_buffer(ctx, &out, 0, 4 * u64::from(n))?;
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes);
        Ok(Traced {
            blocked: words.into_iter().map(|w| w != 0).collect(),
            gpu: timer.read(ctx)?,
        })
    }
}
