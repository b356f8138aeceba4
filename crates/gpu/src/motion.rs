//! Moving lights each frame, two ways: a compute pass that moves them on the GPU
//! ([`LightMotion::animate`], `shaders/lights/motion.wgsl`, timed as `lights.animate`), or the
//! host computing every moving light and uploading all of them ([`LightMotion::upload`]:
//! computed into a host copy kept from frame to frame, written into a mapped staging buffer,
//! then copied into the scene's light buffer, the copy timed as `lights.upload` where the
//! device writes timestamps between passes). Both put each light where
//! [`manylights_scene::motion`], their oracle, says.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use manylights_scene::motion::{
    MOTION_GLIDE, MOTION_NOISE, MOTION_ORBIT, MOTION_STATIC, frame_time,
};
use manylights_scene::{Light, Motion};
use wgpu::util::DeviceExt;

use crate::layout::GpuLight;
use crate::pipeline::{self, UNIFORM, entry, storage};
use crate::shaders::{LIGHT, ShaderDef, WgslConst};
use crate::timing::{Category, GpuTimer, PassTiming};
use crate::{GpuContext, GpuError, GpuScene};

/// The animation pass.
pub const MOTION: ShaderDef = ShaderDef {
    name: "lights.animate",
    consts: &[
        WgslConst::U32("MOTION_STATIC", MOTION_STATIC),
        WgslConst::U32("MOTION_ORBIT", MOTION_ORBIT),
        WgslConst::U32("MOTION_NOISE", MOTION_NOISE),
        WgslConst::U32("MOTION_GLIDE", MOTION_GLIDE),
    ],
    files: &[LIGHT, crate::shader_file!("lights/motion.wgsl")],
};

/// Threads per workgroup of the animation pass.
const WORKGROUP: u32 = 256;

/// Host mirror of `MotionParams` in `shaders/lights/motion.wgsl` (its layout is tested
/// against naga's in tests/shaders.rs).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct MotionParams {
    /// `MOTION_STATIC`, `MOTION_ORBIT` or `MOTION_NOISE`.
    pub kind: u32,
    /// The first moving light.
    pub first: u32,
    /// How many move.
    pub count: u32,
    /// Threads in a row of the dispatch grid.
    pub row: u32,
    /// World units per second.
    pub speed: f32,
    /// Seconds (`frame_time`).
    pub time: f32,
    /// A glide's circle radius, world units (`Motion::extent`).
    pub extent: f32,
    /// Padding to 16 bytes.
    pub _pad: u32,
}

/// A storage buffer of `data` (one unused vec4 where it is empty: a binding is never empty).
fn vec4_buffer(d: &wgpu::Device, label: &str, data: &[[f32; 4]]) -> wgpu::Buffer {
    d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: if data.is_empty() {
            &[0u8; 16]
        } else {
            bytemuck::cast_slice(data)
        },
        usage: wgpu::BufferUsages::STORAGE,
    })
}

/// What one light update cost.
#[derive(Clone, Debug, Default)]
pub struct UpdateCost {
    /// The GPU's part (`lights.animate`, or the copy `lights.upload`), where it was timed.
    pub gpu: Option<Vec<PassTiming>>,
    /// Host milliseconds: computing the lights and writing them into the staging buffer
    /// (uploads only).
    pub host_ms: Option<f64>,
}

/// The moving lights of a scene: lights `first..first + home.len()` of its light buffer.
pub struct LightMotion {
    motion: Motion,
    first: u32,
    /// The moving lights at home, as the GPU holds them.
    home: Vec<GpuLight>,
    /// Their anchor normals where the motion reads them (`Motion::uses_anchors`), else empty.
    anchors: Vec<Vec3>,
    params: wgpu::Buffer,
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    groups: (u32, u32),
    /// The scene's light buffer.
    lights: wgpu::Buffer,
    /// The staging buffer of uploads, mapped for writing while it waits for the next one.
    staging: Option<wgpu::Buffer>,
    /// The host's copy of the moving lights that uploads write (empty until the first).
    host: Vec<GpuLight>,
}

impl LightMotion {
    /// `lights` are the scene's lights from index `first` on, at home (as uploaded), that move
    /// with `motion`; `anchors` their anchor normals (`LightSpec::anchors`), one a light where
    /// the motion reads them (`Motion::uses_anchors`; empty otherwise: an error for a glide).
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        lights: &[Light],
        anchors: &[Vec3],
        first: u32,
        motion: Motion,
    ) -> Result<Self, GpuError> {
        Self::on_buffer(
            ctx,
            &scene.lights,
            scene.light_count,
            lights,
            anchors,
            first,
            motion,
        )
    }

    /// [`LightMotion::new`] for a buffer of `light_count` lights other than a scene's (the
    /// lights a hierarchy is built from, `crate::hierarchy::GpuHierarchy::source`).
    pub fn on_buffer(
        ctx: &GpuContext,
        buffer: &wgpu::Buffer,
        light_count: u32,
        lights: &[Light],
        anchors: &[Vec3],
        first: u32,
        motion: Motion,
    ) -> Result<Self, GpuError> {
        let count = lights.len() as u32;
        let anchors: Vec<Vec3> = if motion.uses_anchors() {
            if anchors.len() != lights.len() {
                return Err(GpuError::Unsupported(format!(
                    "lights.motion {motion:?} moves lights across their surfaces and needs one \
                     anchor normal a moving light (LightSpec::anchors): {} for {} lights",
                    anchors.len(),
                    lights.len()
                )));
            }
            anchors.to_vec()
        } else {
            Vec::new()
        };
        if u64::from(first) + u64::from(count) > u64::from(light_count) {
            return Err(GpuError::OverLimit {
                what: "moving lights".into(),
                value: u64::from(first) + u64::from(count),
                limit: u64::from(light_count),
                limit_name: "the scene's light count",
            });
        }
        let d = &ctx.device;
        let home_xyzr: Vec<[f32; 4]> = lights
            .iter()
            .map(|l| [l.position.x, l.position.y, l.position.z, l.radius])
            .collect();
        let home_buf = vec4_buffer(d, "lights.home", &home_xyzr);
        let anchor_xyz: Vec<[f32; 4]> = anchors.iter().map(|n| [n.x, n.y, n.z, 0.0]).collect();
        let anchor_buf = vec4_buffer(d, "lights.anchors", &anchor_xyz);
        let groups_needed = count.div_ceil(WORKGROUP).max(1);
        let max = ctx.limits.max_compute_workgroups_per_dimension;
        let groups = (groups_needed.min(max), groups_needed.div_ceil(max));
        let params = MotionParams {
            kind: motion.kind(),
            first,
            count,
            row: groups.0 * WORKGROUP,
            speed: motion.speed(),
            time: 0.0,
            extent: motion.extent(),
            _pad: 0,
        };
        let params_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lights.motion"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let c = wgpu::ShaderStages::COMPUTE;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lights.animate"),
            entries: &[
                entry(0, c, UNIFORM),
                entry(1, c, storage(true)),
                entry(2, c, storage(false)),
                entry(3, c, storage(true)),
            ],
        });
        let module = MOTION.create(d);
        let pipeline = pipeline::compute(
            d,
            &module,
            &pipeline::layout(d, "lights.animate", &[&layout]),
            "animate",
        );
        let group = pipeline::buffers_group(
            d,
            "lights.animate",
            &layout,
            &[&params_buf, &home_buf, buffer, &anchor_buf],
        );
        Ok(Self {
            motion,
            first,
            home: lights.iter().map(GpuLight::from).collect(),
            anchors,
            params: params_buf,
            pipeline,
            group,
            groups,
            lights: buffer.clone(),
            staging: None,
            host: Vec::new(),
        })
    }

    /// Moves the lights to where they are at frame `frame` with the animation pass.
    pub fn animate(&self, ctx: &GpuContext, frame: u32) -> Result<UpdateCost, GpuError> {
        let time = frame_time(frame);
        ctx.queue.write_buffer(
            &self.params,
            std::mem::offset_of!(MotionParams, time) as u64,
            bytemuck::bytes_of(&time),
        );
        let mut timer = GpuTimer::new(ctx, 1);
        timer.set_category(Category::LightUpdate);
        let mut encoder = encoder(ctx, "lights.animate");
        pipeline::dispatch(
            &mut encoder,
            &mut timer,
            "lights.animate",
            &self.pipeline,
            &[&self.group],
            self.groups,
        );
        timer.resolve(&mut encoder);
        ctx.submit_and_wait(encoder, "lights.animate")?;
        Ok(UpdateCost {
            gpu: timer.read(ctx)?,
            host_ms: None,
        })
    }

    /// The moving lights as the GPU holds them at frame `frame`, computed on the host (on
    /// every core): what [`LightMotion::upload`] writes.
    pub fn at_frame(&self, frame: u32) -> Vec<GpuLight> {
        let mut out = self.home.clone();
        self.fill(&mut out, frame);
        out
    }

    /// Writes the moving lights at frame `frame` into `out` (as long as the moving lights),
    /// a chunk a core.
    fn fill(&self, out: &mut [GpuLight], frame: u32) {
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let chunk = out.len().div_ceil(threads).max(4096);
        let (motion, first, anchors) = (self.motion, self.first, &self.anchors);
        std::thread::scope(|s| {
            for (c, (lights, home)) in out
                .chunks_mut(chunk)
                .zip(self.home.chunks(chunk))
                .enumerate()
            {
                s.spawn(move || {
                    for (j, (l, h)) in lights.iter_mut().zip(home).enumerate() {
                        let k = c * chunk + j;
                        let index = first + k as u32;
                        let anchor = anchors.get(k).copied().unwrap_or(Vec3::Y);
                        *l = GpuLight {
                            position: motion
                                .position_on(index, h.position, h.radius, anchor, frame),
                            ..*h
                        };
                    }
                });
            }
        });
    }

    /// Moves the lights to where they are at frame `frame` by computing them on the host and
    /// uploading all of them: the host's time (waiting for the staging buffer, computing,
    /// writing it) and the GPU copy's, where timed.
    pub fn upload(&mut self, ctx: &GpuContext, frame: u32) -> Result<UpdateCost, GpuError> {
        let bytes = (self.home.len() * size_of::<GpuLight>()) as u64;
        if bytes == 0 {
            return Ok(UpdateCost::default());
        }
        let start = std::time::Instant::now();
        let staging = match self.staging.take() {
            Some(b) => {
                crate::readback::map(ctx, &b, wgpu::MapMode::Write)?;
                b
            }
            None => ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("lights.upload"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_WRITE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: true,
            }),
        };
        let mapped = start.elapsed();
        // The host's copy of the lights, kept from frame to frame: a fresh allocation each
        // frame spent most of an upload faulting its pages in (a million lights: 64 MB).
        let mut lights = std::mem::take(&mut self.host);
        if lights.len() != self.home.len() {
            lights = self.home.clone();
        }
        self.fill(&mut lights, frame);
        let computed = start.elapsed();
        staging
            .get_mapped_range_mut(..)
            .map_err(|e| GpuError::Readback(e.to_string()))?
            .copy_from_slice(bytemuck::cast_slice(&lights));
        staging.unmap();
        let host_ms = start.elapsed().as_secs_f64() * 1e3;
        let count = lights.len();
        self.host = lights;
        tracing::debug!(
            lights = count,
            map_ms = mapped.as_secs_f64() * 1e3,
            compute_ms = (computed - mapped).as_secs_f64() * 1e3,
            write_ms = host_ms - computed.as_secs_f64() * 1e3,
            "lights uploaded"
        );
        let mut timer = GpuTimer::spans(ctx, 1);
        let mut encoder = encoder(ctx, "lights.upload");
        if let Some(t) = &mut timer {
            t.set_category(Category::LightUpdate);
            t.span_begin(&mut encoder, "lights.upload");
        }
        encoder.copy_buffer_to_buffer(
            &staging,
            0,
            &self.lights,
            u64::from(self.first) * size_of::<GpuLight>() as u64,
            bytes,
        );
        if let Some(t) = &mut timer {
            t.span_end(&mut encoder);
            t.resolve(&mut encoder);
        }
        ctx.submit_and_wait(encoder, "lights.upload")?;
        self.staging = Some(staging);
        Ok(UpdateCost {
            gpu: match &timer {
                Some(t) => t.read(ctx)?,
                None => None,
            },
            host_ms: Some(host_ms),
        })
    }
}

/// An encoder outside the frame's (whose recording time is the frame's `cpu_ms_encode`).
fn encoder(ctx: &GpuContext, label: &str) -> wgpu::CommandEncoder {
    ctx.device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
}
