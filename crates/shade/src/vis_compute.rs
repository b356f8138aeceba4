//! The visibility buffer rasterised in compute: the visibility backend's pass by default
//! ([`crate::VisibilityPass::Compute`]; the raster pass `shade.visibility` with MSAA, glass, or
//! without 64-bit atomics). `shade.visibility_compute` keeps each pixel's nearest opaque
//! triangle in a 64-bit key by atomic max (a thread a triangle, clipped against the near plane;
//! large ones set up once, their 64 x 64 blocks (`Tiling`) numbered by one workgroup's scan and
//! taken a workgroup a block); coverage as the hardware's (vertices snapped to 1/256 pixel,
//! exact 64-bit edge functions, the top-left rule). `shade.visibility_resolve` writes the ids
//! (as `shade.visibility` does: the triangle's index plus one, 0 for none) and NDC depths
//! (`R32Float`, which culling, over the culler's float-depth pipelines, and the lighting read);
//! `shade.visibility_depth` copies those depths into a depth buffer outside the timed frame,
//! for the exact oracle. It needs 64-bit atomic max on storage buffers
//! (`SHADER_INT64_ATOMIC_MIN_MAX`; lavapipe and NVIDIA have it). Tested against the hardware
//! pass's ids and depths (tests/shade/visibility.rs).

use manylights_gpu::pipeline::{self, UNIFORM, storage};
use manylights_gpu::shader_file;
use manylights_gpu::shaders::FRAME;
use manylights_gpu::shaders::ShaderDef;
use manylights_gpu::timing::{Category, GpuTimer};

use crate::frame_plan::{self, FramePass, Recording, Resource, Work};
use manylights_gpu::{GpuContext, GpuError, GpuScene, readback};

/// `shade.visibility_compute`.
pub const VISIBILITY_COMPUTE: ShaderDef = ShaderDef {
    name: "shade.visibility_compute",
    consts: &[],
    files: &[FRAME, shader_file!("render/visibility_compute.wgsl")],
};

/// `shade.visibility_resolve`.
pub const VISIBILITY_RESOLVE: ShaderDef = ShaderDef {
    name: "shade.visibility_resolve",
    consts: &[],
    files: &[FRAME, shader_file!("render/visibility_resolve.wgsl")],
};

/// `shade.visibility_depth`: the pass's depths into a depth buffer (untimed, for the oracle).
pub const VISIBILITY_DEPTH: ShaderDef = ShaderDef {
    name: "shade.visibility_depth",
    consts: &[],
    files: &[shader_file!("render/visibility_depth.wgsl")],
};

/// Workgroups of the blocks' pass; each takes an equal share of the queued blocks, a run of
/// consecutive ones.
const BLOCK_GROUPS: u32 = 2048;

/// How the compute visibility pass shares out its triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tiling {
    /// A large triangle's blocks' side, pixels (a workgroup a block): a power of two of at most
    /// 256 (a thread takes a column of a block).
    pub block: u32,
    /// The largest bounding box, pixels, that a triangle's own thread rasterises.
    pub small: u32,
}

impl Default for Tiling {
    fn default() -> Self {
        // The fastest tiling of those timed (frame.visibility; docs/bench/HISTORY.md, "The
        // compute rasteriser's tiling"): smaller blocks cost more in a block's bisection and
        // set-up than their pixels save, larger small triangles more in a thread's loop.
        Self {
            block: 64,
            small: 256,
        }
    }
}

/// The pipelines of the compute visibility pass.
pub struct ComputeVisibility {
    layout: wgpu::BindGroupLayout,
    resolve_layout: wgpu::BindGroupLayout,
    triangles: wgpu::ComputePipeline,
    scan: wgpu::ComputePipeline,
    blocks: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    depth_layout: wgpu::BindGroupLayout,
    depth: wgpu::RenderPipeline,
}

/// A frame's compute visibility buffers.
pub struct ComputeTargets {
    size: (u32, u32),
    keys: wgpu::Buffer,
    counts: wgpu::Buffer,
    group: wgpu::BindGroup,
    resolve_group: wgpu::BindGroup,
    depth_group: wgpu::BindGroup,
    /// Each pixel's triangle id (`R32Uint`).
    pub ids: wgpu::Texture,
    /// Each pixel's NDC depth (`R32Float`, 1 where nothing is drawn).
    pub depth: wgpu::Texture,
}

impl ComputeTargets {
    /// Bytes of its buffers a frame: a 64-bit key, an id and a depth a pixel.
    pub fn bytes(&self) -> u64 {
        let (w, h) = self.size;
        u64::from(w) * u64::from(h) * (8 + 4 + 4)
    }
}

/// What the compute visibility pass wrote, read back: ids and depths a pixel (rows from the top),
/// the large triangles queued for the blocks' pass, and those dropped past the queue (none: it
/// holds both parts of every triangle; the count guards the queue's bound).
pub struct ComputeFrame {
    /// Triangle ids (index plus one, 0 for none).
    pub ids: Vec<u32>,
    /// NDC depths (1 for none).
    pub depth: Vec<f32>,
    /// Large triangles (clipped parts) queued for `vis_blocks`.
    pub queued: u32,
    /// Large triangles dropped past the queue.
    pub dropped: u32,
}

impl ComputeVisibility {
    /// The pipelines for scenes laid out as `scene`; an error where the device lacks 64-bit
    /// atomic max.
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Result<Self, GpuError> {
        Self::with_tiling(ctx, scene, Tiling::default())
    }

    /// [`ComputeVisibility::new`] with the blocks and the small triangles' bound of `tiling`.
    pub fn with_tiling(
        ctx: &GpuContext,
        scene: &GpuScene,
        tiling: Tiling,
    ) -> Result<Self, GpuError> {
        if !ctx.features.int64_atomics {
            return Err(GpuError::Unsupported(format!(
                "the compute visibility pass needs 64-bit atomic max on storage buffers (wgpu \
                 feature SHADER_INT64_ATOMIC_MIN_MAX), which adapter {} does not offer",
                ctx.info.name
            )));
        }
        if !tiling.block.is_power_of_two() || tiling.block > 256 {
            return Err(GpuError::Unsupported(format!(
                "compute visibility block side {}: a power of two of at most 256 pixels",
                tiling.block
            )));
        }
        let d = &ctx.device;
        let c = wgpu::ShaderStages::COMPUTE;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shade.visibility_compute"),
            entries: &[
                pipeline::entry(0, c, storage(true)),
                pipeline::entry(1, c, storage(true)),
                pipeline::entry(2, c, storage(false)),
                pipeline::entry(3, c, storage(false)),
                pipeline::entry(4, c, storage(false)),
                pipeline::entry(5, c, UNIFORM),
                pipeline::entry(6, c, storage(false)),
            ],
        });
        let storage_texture = |format| wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format,
            view_dimension: wgpu::TextureViewDimension::D2,
        };
        let resolve_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shade.visibility_resolve"),
            entries: &[
                pipeline::entry(0, c, storage(true)),
                pipeline::entry(1, c, storage_texture(wgpu::TextureFormat::R32Uint)),
                pipeline::entry(2, c, storage_texture(wgpu::TextureFormat::R32Float)),
            ],
        });
        let module = VISIBILITY_COMPUTE.create(d);
        let pl = pipeline::layout(d, "shade.visibility_compute", &[&scene.layout, &layout]);
        let resolve_module = VISIBILITY_RESOLVE.create(d);
        let rpl = pipeline::layout(
            d,
            "shade.visibility_resolve",
            &[&scene.layout, &resolve_layout],
        );
        let constants = [
            ("VC_BLOCK", f64::from(tiling.block)),
            ("VC_SMALL", f64::from(tiling.small)),
        ];
        let options = wgpu::PipelineCompilationOptions {
            constants: &constants,
            ..Default::default()
        };
        let compute = |entry| pipeline::compute_with(d, &module, &pl, entry, &options);
        let depth_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shade.visibility_depth"),
            entries: &[pipeline::entry(
                0,
                wgpu::ShaderStages::FRAGMENT,
                wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
            )],
        });
        Ok(Self {
            depth: depth_pipeline(d, &depth_layout),
            depth_layout,
            triangles: compute("vis_triangles"),
            scan: compute("vis_scan"),
            blocks: compute("vis_blocks"),
            resolve: pipeline::compute(d, &resolve_module, &rpl, "vis_resolve"),
            layout,
            resolve_layout,
        })
    }

    /// Whether a `width` x `height` frame of `scene` fits the device's storage bindings: the
    /// keys (8 bytes a pixel) and the queue (two entries of 64 bytes a triangle).
    pub fn check(ctx: &GpuContext, scene: &GpuScene, (w, h): (u32, u32)) -> Result<(), GpuError> {
        ctx.check_storage("its keys' bytes", u64::from(w) * u64::from(h) * 8)?;
        ctx.check_storage("its queue's bytes", queue_capacity(scene) * 64)
    }

    /// Buffers for a `width` x `height` frame of `scene`.
    pub fn targets(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        (w, h): (u32, u32),
    ) -> ComputeTargets {
        let d = &ctx.device;
        let buf = |label, size: u64, usage| {
            d.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let rw = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC;
        let keys = buf(
            "visibility_compute.keys",
            u64::from(w) * u64::from(h) * 8,
            rw,
        );
        let counts = buf("visibility_compute.counts", 8, rw);
        // Two entries a triangle (its near-plane parts) of 64 bytes: the queue cannot overflow.
        let capacity = queue_capacity(scene);
        let queue = buf("visibility_compute.queue", capacity * 64, rw);
        let first = buf("visibility_compute.first", (capacity + 1) * 4, rw);
        let params = pipeline::uniform_buffer(
            d,
            "visibility_compute.params",
            bytemuck::cast_slice(&[
                scene.opaque_index_count / 3,
                capacity as u32,
                BLOCK_GROUPS,
                0,
            ]),
        );
        let group = pipeline::group(
            d,
            "shade.visibility_compute",
            &self.layout,
            &[
                scene.vertices.as_entire_binding(),
                scene.indices.as_entire_binding(),
                keys.as_entire_binding(),
                counts.as_entire_binding(),
                queue.as_entire_binding(),
                params.as_entire_binding(),
                first.as_entire_binding(),
            ],
        );
        let usage = wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let ids = pipeline::texture_2d(
            d,
            "visibility_compute.ids",
            (w, h),
            wgpu::TextureFormat::R32Uint,
            usage,
        );
        let depth = pipeline::texture_2d(
            d,
            "visibility_compute.depth",
            (w, h),
            wgpu::TextureFormat::R32Float,
            usage,
        );
        let resolve_group = pipeline::group(
            d,
            "shade.visibility_resolve",
            &self.resolve_layout,
            &[
                keys.as_entire_binding(),
                wgpu::BindingResource::TextureView(&ids.create_view(&Default::default())),
                wgpu::BindingResource::TextureView(&depth.create_view(&Default::default())),
            ],
        );
        let depth_group = pipeline::group(
            d,
            "shade.visibility_depth",
            &self.depth_layout,
            &[wgpu::BindingResource::TextureView(
                &depth.create_view(&Default::default()),
            )],
        );
        ComputeTargets {
            size: (w, h),
            depth_group,
            keys,
            counts,
            group,
            resolve_group,
            ids,
            depth,
        }
    }

    /// The pass over `t` (the scene's frame uniform set for its size) as a frame's entries:
    /// clears, the triangles, the large ones' blocks, the resolve, timed as
    /// `shade.visibility_compute.*`.
    pub(crate) fn plan<'a>(
        &'a self,
        scene: &'a GpuScene,
        t: &'a ComputeTargets,
    ) -> Vec<FramePass<'a>> {
        use Resource::{ComputeDepth, Scene, Surfaces};
        let triangles = scene.opaque_index_count / 3;
        let (w, h) = t.size;
        let pass =
            |name, pipeline, groups, grid: (u32, u32), reads: &[Resource], writes: &[Resource]| {
                FramePass::new(
                    name,
                    Category::Prepass,
                    Work::Dispatch {
                        pipeline,
                        groups,
                        grid: [grid.0, grid.1, 1],
                    },
                    reads,
                    writes,
                )
            };
        let g = || vec![&scene.bind_group, &t.group];
        let clear = |buffer| {
            FramePass::new(
                "clear",
                Category::Prepass,
                Work::Clear(buffer),
                &[],
                &[ComputeDepth],
            )
        };
        vec![
            clear(&t.keys),
            clear(&t.counts),
            pass(
                "shade.visibility_compute.triangles",
                &self.triangles,
                g(),
                (triangles.div_ceil(64).max(1), 1),
                &[Scene, ComputeDepth],
                &[ComputeDepth],
            ),
            pass(
                "shade.visibility_compute.scan",
                &self.scan,
                g(),
                (1, 1),
                &[ComputeDepth],
                &[ComputeDepth],
            ),
            pass(
                "shade.visibility_compute.blocks",
                &self.blocks,
                g(),
                (BLOCK_GROUPS, 1),
                &[Scene, ComputeDepth],
                &[ComputeDepth],
            ),
            pass(
                "shade.visibility_compute.resolve",
                &self.resolve,
                vec![&scene.bind_group, &t.resolve_group],
                (w.div_ceil(8), h.div_ceil(8)),
                &[Scene, ComputeDepth],
                &[ComputeDepth, Surfaces],
            ),
        ]
    }

    /// Encodes the passes of its plan over `t`, timed by `timer`.
    pub fn encode(
        &self,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        scene: &GpuScene,
        t: &ComputeTargets,
    ) {
        let plan = self.plan(scene, t);
        frame_plan::record(enc, timer, scene, &plan, Recording::Frame);
    }

    /// Encodes `shade.visibility_depth`: the depths of `t` (after the passes of its plan)
    /// into `depth`, a single-sample `Depth32Float` view of its size, untimed.
    pub fn encode_depth(
        &self,
        enc: &mut wgpu::CommandEncoder,
        t: &ComputeTargets,
        depth: &wgpu::TextureView,
    ) {
        let mut pass =
            manylights_gpu::prepass::begin_depth_pass(enc, "shade.visibility_depth", depth, None);
        pass.set_pipeline(&self.depth);
        pass.set_bind_group(0, &t.depth_group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// One frame of the pass, read back.
    pub fn run(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        t: &ComputeTargets,
    ) -> Result<ComputeFrame, GpuError> {
        let mut enc = ctx.encoder("visibility_compute");
        self.encode(&mut enc, &mut GpuTimer::untimed(), scene, t);
        ctx.submit_and_wait(enc, "compute visibility")?;
        let ids = readback::read_texture(ctx, &t.ids, wgpu::TextureAspect::All)?;
        let depth = readback::read_texture(ctx, &t.depth, wgpu::TextureAspect::All)?;
        let counts = readback::read_buffer(ctx, &t.counts, 0, 8)?;
        let counts: &[u32] = bytemuck::cast_slice(&counts);
        Ok(ComputeFrame {
            ids: bytemuck::cast_slice(&ids).to_vec(),
            depth: bytemuck::cast_slice(&depth).to_vec(),
            queued: counts[0],
            dropped: counts[1],
        })
    }
}

/// `shade.visibility_depth`'s pipeline: a triangle over the target writing every fragment's
/// depth (compare `Always`).
fn depth_pipeline(d: &wgpu::Device, layout: &wgpu::BindGroupLayout) -> wgpu::RenderPipeline {
    let module = VISIBILITY_DEPTH.create(d);
    let pl = pipeline::layout(d, "shade.visibility_depth", &[layout]);
    d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("shade.visibility_depth"),
        layout: Some(&pl),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vis_depth_vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: manylights_gpu::prepass::DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("vis_depth_fs"),
            compilation_options: Default::default(),
            targets: &[],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// Queue entries a frame of `scene` may need: two a triangle (its near-plane parts), so that it
/// cannot overflow.
fn queue_capacity(scene: &GpuScene) -> u64 {
    2 * u64::from((scene.opaque_index_count / 3).max(1))
}
