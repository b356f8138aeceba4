//! The infinite-range reference as a compute pass (`shade.reference_infinite`,
//! `shaders/render/reference_infinite.wgsl`): every light with the un-windowed falloff at each
//! pixel's surface point, the point and normal the reference's raster pass stored
//! ([`crate::ReferenceRenderer::surfaces`]). The accuracy axis that a radius cut-off is measured
//! on: a reference that made the same cut-off could not see its cost.
//!
//! Its cost is pixels x lights (2 x 10^12 evaluations at 1080p and a million lights), so it is
//! chunked over lights: one dispatch adds at most [`DISPATCH_EVALUATIONS`] evaluations into each
//! pixel's running sum, kept with Kahan's compensated summation, and a submission holds at most
//! [`SUBMIT_EVALUATIONS`], so no command buffer runs long enough for a driver's watchdog.
//! The raster pass with the infinite-range flag (`ReferenceRenderer::render_infinite`) stays
//! the reference where a pixel has several surfaces: MSAA samples and transparent surfaces
//! blended over the opaque one.

use manylights_gpu::pipeline::{self, entry, storage};
use manylights_gpu::shaders::{BRDF, BVH, FRAME, LIGHT, SCENE, SHADING, ShaderDef};
use manylights_gpu::{GpuContext, GpuError, GpuScene, readback};
use wgpu::util::DeviceExt;

use crate::kinds::Shadows;
use crate::{HdrImage, ReferenceFrame};

/// The pass's shader.
pub const SHADER: ShaderDef = ShaderDef {
    name: "shade.reference_infinite",
    consts: &[],
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        BVH,
        BRDF,
        SHADING,
        manylights_gpu::shader_file!("render/reference_infinite.wgsl"),
    ],
};

/// Threads per workgroup (`WG` in the shader).
const WORKGROUP: u32 = 64;

/// Most light evaluations (pixels x lights) of one dispatch: about 2 ms on an H100.
pub const DISPATCH_EVALUATIONS: u64 = 1 << 30;

/// Most light evaluations of one submission.
pub const SUBMIT_EVALUATIONS: u64 = 1 << 34;

/// Host mirror of `InfiniteParams` in the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    first: u32,
    count: u32,
    pixels: u32,
    row: u32,
    seed: u32,
}

/// The compute reference's pipeline for one uploaded scene layout.
pub struct InfiniteReference {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    /// Lights a dispatch, where set ([`InfiniteReference::with_chunk`]); [`chunk_lights`]
    /// otherwise.
    chunk: Option<u32>,
    /// Whether each light's contribution is shadowed ([`InfiniteReference::with_shadows`]).
    shadows: Shadows,
    /// The shadowed sum's unbiased estimate's rays a pixel in expectation, where it is one
    /// ([`InfiniteReference::with_estimate`]); 0: every ray.
    estimate: u32,
}

/// What a shadowed evaluation costs against an unshadowed one, in the chunks' sizing: a
/// shadow ray through the BVH is some tens of light evaluations (so that a shadowed dispatch
/// runs about as long as an unshadowed one).
const SHADOW_RAY_COST: u64 = 64;

/// The lights of one dispatch over `pixels` pixels: [`DISPATCH_EVALUATIONS`] / pixels, a
/// multiple of the workgroup's batch, between 64 and 65,536.
pub fn chunk_lights(pixels: u64) -> u32 {
    let n = (DISPATCH_EVALUATIONS / pixels.max(1)).clamp(64, 65_536) as u32;
    n / WORKGROUP * WORKGROUP
}

impl InfiniteReference {
    /// Builds the pipeline.
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Self {
        Self::build(ctx, scene, Shadows::Off, 0)
    }

    /// The pass again with `shadows`: `Shadows::Exact`, a shadow ray for every light at every
    /// covered pixel (with the infinite-range falloff every light in front of a surface adds
    /// radiance), through the scene's BVH (`GpuScene::build_bvh`): the shadowed infinite-range
    /// reference, the light as it arrives. `Stochastic` shades as `Exact` ([`Shadows::truth`]).
    pub fn with_shadows(self, ctx: &GpuContext, scene: &GpuScene, shadows: Shadows) -> Self {
        let shadows = shadows.truth();
        if shadows == self.shadows && self.estimate == 0 {
            return self;
        }
        Self {
            chunk: self.chunk,
            ..Self::build(ctx, scene, shadows, 0)
        }
    }

    /// The pass again as an unbiased estimate of the shadowed infinite-range reference with
    /// `rays` shadow rays a pixel in expectation (at least 1), for views where a ray for every
    /// (pixel, light) pair takes too long: each light's unshadowed radiance c at a pixel casts
    /// its ray with probability q = min(1, rays luminance(c) / L), L the pixel's unshadowed
    /// luminance, and adds its shadowed radiance over q where it does (`ESTIMATE_RAYS`,
    /// shaders/render/reference_infinite.wgsl). Rendered by [`InfiniteReference::estimate`].
    pub fn with_estimate(self, ctx: &GpuContext, scene: &GpuScene, rays: u32) -> Self {
        assert!(rays >= 1, "an estimate casts at least one ray a pixel");
        Self {
            chunk: self.chunk,
            ..Self::build(ctx, scene, Shadows::Exact, rays)
        }
    }

    /// The estimate's rays a pixel in expectation (0: the pass is exact).
    pub fn estimate_rays(&self) -> u32 {
        self.estimate
    }

    fn build(ctx: &GpuContext, scene: &GpuScene, shadows: Shadows, estimate: u32) -> Self {
        let d = &ctx.device;
        let c = wgpu::ShaderStages::COMPUTE;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shade.reference_infinite"),
            entries: &[
                entry(
                    0,
                    c,
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(size_of::<Params>() as u64),
                    },
                ),
                entry(1, c, storage(true)),
                entry(2, c, storage(false)),
            ],
        });
        let module = SHADER.create(d);
        let mut constants = shadows.constants().to_vec();
        constants.push(("ESTIMATE_RAYS", f64::from(estimate)));
        let pipeline = pipeline::compute_with(
            d,
            &module,
            &pipeline::layout(d, "shade.reference_infinite", &[&scene.layout, &layout]),
            "reference_infinite",
            &wgpu::PipelineCompilationOptions {
                constants: &constants,
                ..Default::default()
            },
        );
        Self {
            pipeline,
            layout,
            chunk: None,
            shadows,
            estimate,
        }
    }

    /// The same pass with `lights` lights a dispatch (a positive multiple of 64), so that a
    /// small test image still spans many dispatches.
    pub fn with_chunk(mut self, lights: u32) -> Self {
        assert!(
            lights > 0 && lights.is_multiple_of(WORKGROUP),
            "a chunk is a positive multiple of {WORKGROUP} lights"
        );
        self.chunk = Some(lights);
        self
    }

    /// The infinite-range image at the surface points of `surfaces` (a single-sample
    /// reference frame of `scene`, whose frame uniform is still set for the same camera and
    /// resolution): alpha 1 where covered, 0 elsewhere.
    pub fn render(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        surfaces: &ReferenceFrame,
    ) -> Result<HdrImage, GpuError> {
        if self.estimate > 0 {
            return Err(GpuError::Unsupported(
                "the infinite-range reference's estimate renders with InfiniteReference::estimate \
                 (it needs the unshadowed image)"
                    .into(),
            ));
        }
        self.run(ctx, scene, surfaces, None)
    }

    /// One unbiased estimate of the shadowed infinite-range image (a pass built by
    /// [`InfiniteReference::with_estimate`]) at the surface points of `surfaces`, from
    /// `unshadowed`, the unshadowed infinite-range image of the same view
    /// ([`InfiniteReference::render`]), its draws seeded by `seed`: independent estimates take
    /// seeds of their own.
    pub fn estimate(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        surfaces: &ReferenceFrame,
        unshadowed: &HdrImage,
        seed: u32,
    ) -> Result<HdrImage, GpuError> {
        if self.estimate == 0 {
            return Err(GpuError::Unsupported(
                "InfiniteReference::estimate on an exact pass: build it with_estimate".into(),
            ));
        }
        let (w, h) = (surfaces.position.width, surfaces.position.height);
        if (unshadowed.width, unshadowed.height) != (w, h) {
            return Err(GpuError::Unsupported(format!(
                "the estimate's unshadowed image is {} x {}, its surfaces {w} x {h}",
                unshadowed.width, unshadowed.height
            )));
        }
        self.run(ctx, scene, surfaces, Some((unshadowed, seed)))
    }

    fn run(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        surfaces: &ReferenceFrame,
        seeded: Option<(&HdrImage, u32)>,
    ) -> Result<HdrImage, GpuError> {
        let (w, h) = (surfaces.position.width, surfaces.position.height);
        let pixels = u64::from(w) * u64::from(h);
        self.shadows
            .check_scene(scene, "the infinite-range reference")?;
        // A shadowed evaluation weighs as SHADOW_RAY_COST unshadowed ones in the chunks, an
        // estimate's too: a light whose share of the pixel is large casts its ray at every
        // estimate, so a chunk may cast a ray a light (and llvmpipe ends an invocation past
        // 65,535 loop iterations, the BVH's among them: crates/gpu/tests/loop_limit.rs).
        let cost = if self.shadows.casts() {
            SHADOW_RAY_COST
        } else {
            1
        };
        let bytes = pixels * 32;
        ctx.check_storage("infinite-range reference surface bytes", bytes)?;
        let d = &ctx.device;
        let surface: Vec<[f32; 4]> = surfaces
            .position
            .data
            .iter()
            .zip(&surfaces.normal.data)
            .flat_map(|(p, n)| [*p, *n])
            .collect();
        let surface_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("reference_infinite.surface"),
            contents: bytemuck::cast_slice(&surface),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let sums = sums_buffer(d, seeded.map(|(u, _)| u), bytes);
        let lights = scene.light_count;
        let chunk = self.chunk.unwrap_or_else(|| chunk_lights(pixels * cost));
        let chunks = lights.div_ceil(chunk).max(1);
        let groups_needed = u32::try_from(pixels.div_ceil(u64::from(WORKGROUP))).map_err(|_| {
            GpuError::OverLimit {
                what: "infinite-range reference pixels".into(),
                value: pixels,
                limit: u64::from(u32::MAX) * u64::from(WORKGROUP),
                limit_name: "u32 workgroups",
            }
        })?;
        let max = ctx.limits.max_compute_workgroups_per_dimension;
        let groups = (groups_needed.min(max), groups_needed.div_ceil(max));
        let stride = (size_of::<Params>() as u32)
            .next_multiple_of(ctx.limits.min_uniform_buffer_offset_alignment);
        let mut params = vec![0u8; (stride * chunks) as usize];
        for k in 0..chunks {
            let p = Params {
                first: k * chunk,
                count: chunk.min(lights - k * chunk),
                pixels: pixels as u32,
                row: groups.0 * WORKGROUP,
                seed: seeded.map_or(0, |(_, s)| s),
            };
            let at = (k * stride) as usize;
            params[at..at + size_of::<Params>()].copy_from_slice(bytemuck::bytes_of(&p));
        }
        let params_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("reference_infinite.params"),
            contents: &params,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let group = pipeline::group(
            d,
            "shade.reference_infinite",
            &self.layout,
            &[
                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &params_buf,
                    offset: 0,
                    size: wgpu::BufferSize::new(size_of::<Params>() as u64),
                }),
                surface_buf.as_entire_binding(),
                sums.as_entire_binding(),
            ],
        );
        let per_submit =
            (SUBMIT_EVALUATIONS / (pixels * cost * u64::from(chunk)).max(1)).clamp(1, 4096) as u32;
        let start = std::time::Instant::now();
        let mut k = 0;
        while k < chunks {
            let end = (k + per_submit).min(chunks);
            let mut encoder = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("shade.reference_infinite"),
            });
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("shade.reference_infinite"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &scene.bind_group, &[]);
                for c in k..end {
                    pass.set_bind_group(1, &group, &[c * stride]);
                    pass.dispatch_workgroups(groups.0, groups.1, 1);
                }
            }
            ctx.submit_and_wait(encoder, "shade.reference_infinite")?;
            k = end;
        }
        let raw = readback::read_buffer(ctx, &sums, 0, bytes)?;
        let texels: &[[f32; 4]] = bytemuck::cast_slice(&raw);
        tracing::debug!(
            lights,
            pixels,
            chunks,
            ms = start.elapsed().as_secs_f64() * 1e3,
            "infinite-range reference computed"
        );
        // The compensated sum: the running sum less what its additions lost.
        let data = texels
            .chunks_exact(2)
            .map(|s| {
                let c = |k: usize| (f64::from(s[0][k]) - f64::from(s[1][k])) as f32;
                [c(0), c(1), c(2), s[0][3]]
            })
            .collect();
        Ok(HdrImage {
            width: w,
            height: h,
            data,
        })
    }
}

/// The pass's running sums and their compensation, two texels a pixel (`bytes`): with the
/// estimate's `unshadowed` image, each pixel's unshadowed luminance seeded in its compensation
/// texel's w; a buffer the device zeroes otherwise.
fn sums_buffer(d: &wgpu::Device, unshadowed: Option<&HdrImage>, bytes: u64) -> wgpu::Buffer {
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    match unshadowed {
        Some(u) => {
            let seeds: Vec<[f32; 4]> = u
                .data
                .iter()
                .flat_map(|c| {
                    let l = manylights_scene::shadow_estimate::shading_luminance(
                        glam::Vec3::new(c[0], c[1], c[2]),
                    );
                    [[0.0; 4], [0.0, 0.0, 0.0, l]]
                })
                .collect();
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("reference_infinite.sums"),
                contents: bytemuck::cast_slice(&seeds),
                usage,
            })
        }
        None => d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("reference_infinite.sums"),
            size: bytes,
            usage,
            mapped_at_creation: false,
        }),
    }
}

/// The infinite-range image of the frame `scene` is set for (`camera` at `width` x `height`):
/// the compute pass over the surfaces of `windowed` (a reference frame rendered for the same
/// view; rendered here without lights where `None`) where a pixel has one surface, the raster
/// pass with the infinite-range flag where it has several (MSAA samples, transparent surfaces).
pub fn infinite_image(
    ctx: &GpuContext,
    (rr, inf): (&crate::ReferenceRenderer, &InfiniteReference),
    scene: &GpuScene,
    camera: &manylights_scene::Camera,
    (width, height): (u32, u32),
    windowed: Option<&ReferenceFrame>,
) -> Result<HdrImage, GpuError> {
    if rr.samples() > 1 || scene.has_transparent() {
        return Ok(rr.render_infinite(ctx, scene, camera, width, height)?.color);
    }
    match windowed {
        Some(frame) => inf.render(ctx, scene, frame),
        None => {
            let surfaces = rr.surfaces(ctx, scene, width, height)?;
            inf.render(ctx, scene, &surfaces)
        }
    }
}
