//! Stochastic light culling's ranges, drawn on the GPU each frame (`lights.stochastic`,
//! `shaders/lights/stochastic.wgsl`): for each light of a range of the scene's light buffer,
//! its range for the frame in `radius` and its alpha in `alpha`, as
//! [`manylights_scene::stochastic`], their oracle, says. Culling runs unchanged over the drawn
//! spheres; shading reads alpha (`light_attenuation` in `shaders/common/light.wgsl`).

use bytemuck::{Pod, Zeroable};
use manylights_scene::stochastic::{StochasticDraw, StochasticParams};
use wgpu::util::DeviceExt;

use crate::pipeline::{self, UNIFORM, entry, storage};
use crate::shaders::{LIGHT, ShaderDef};
use crate::timing::{Category, GpuTimer, PassTiming};
use crate::{GpuContext, GpuError, GpuScene, LightModel};

/// The pass.
pub const STOCHASTIC: ShaderDef = ShaderDef {
    name: "lights.stochastic",
    consts: &[],
    files: &[LIGHT, crate::shader_file!("lights/stochastic.wgsl")],
};

/// Threads per workgroup.
const WORKGROUP: u32 = 256;

/// Host mirror of `StochasticParams` in `shaders/lights/stochastic.wgsl` (its layout is
/// tested against naga's in tests/shaders.rs).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuStochasticParams {
    /// The first light drawn.
    pub first: u32,
    /// How many.
    pub count: u32,
    /// Threads in a row of the dispatch grid.
    pub row: u32,
    /// The seed of every draw.
    pub seed: u32,
    /// The frame drawn for.
    pub frame: u32,
    /// 1: alpha written as 0 (a deliberately biased estimate, for tests).
    pub biased: u32,
    /// The error bound.
    pub error: f32,
    /// The exposure of the error bound.
    pub exposure: f32,
    /// The error bound's scale (`StochasticParams::scale`: 1 for the light's own
    /// contribution).
    pub scale: f32,
    /// n of n x n interleaved pixel classes; 1: none.
    pub interleave: u32,
    /// 1: stratified draws over the strata buffer (`StochasticDraw::Stratified`); 0: one
    /// hash a light.
    pub stratified: u32,
    /// Padding to 16 bytes.
    pub _pad: u32,
}

/// The stochastic ranges of lights `first..first + count` of a scene's light buffer.
pub struct StochasticRanges {
    params: wgpu::Buffer,
    host: GpuStochasticParams,
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    groups: (u32, u32),
}

impl StochasticRanges {
    /// Draws for lights `first..first + count` of `scene` with `params`; `strata` holds each
    /// drawn light's stratum (`manylights_scene::stochastic::strata` of those lights), read
    /// by stratified draws.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        first: u32,
        count: u32,
        params: &StochasticParams,
        strata: &[u32],
    ) -> Result<Self, GpuError> {
        let stratified = params.interleave <= 1 && params.draw == StochasticDraw::Stratified;
        if stratified && strata.len() != count as usize {
            return Err(GpuError::OverLimit {
                what: "strata of stratified stochastic draws".into(),
                value: strata.len() as u64,
                limit: u64::from(count),
                limit_name: "the drawn lights (one stratum each)",
            });
        }
        if u64::from(first) + u64::from(count) > u64::from(scene.light_count) {
            return Err(GpuError::OverLimit {
                what: "lights with stochastic ranges".into(),
                value: u64::from(first) + u64::from(count),
                limit: u64::from(scene.light_count),
                limit_name: "the scene's light count",
            });
        }
        // The drawn lights carry alpha: the scene must have been uploaded for these draws, so
        // that shading reads it (LightModel::path).
        let wanted = LightModel::stochastic(first, params.interleave);
        if scene.light_model().ranges != wanted.ranges
            || u64::from(first) + u64::from(count) != u64::from(scene.light_count)
        {
            return Err(GpuError::Unsupported(format!(
                "stochastic ranges for lights {first}..{} with {} x {} pixel classes over a \
                 scene of {} lights uploaded for {:?}: upload it with \
                 LightModel::stochastic({first}, {}) (GpuScene::upload_with), which draws every \
                 light from the first drawn one on",
                u64::from(first) + u64::from(count),
                params.interleave.max(1),
                params.interleave.max(1),
                scene.light_count,
                scene.light_model().ranges,
                params.interleave.max(1),
            )));
        }
        let d = &ctx.device;
        let groups_needed = count.div_ceil(WORKGROUP).max(1);
        let max = ctx.limits.max_compute_workgroups_per_dimension;
        let groups = (groups_needed.min(max), groups_needed.div_ceil(max));
        let host = GpuStochasticParams {
            first,
            count,
            row: groups.0 * WORKGROUP,
            seed: params.seed,
            frame: 0,
            biased: 0,
            error: params.error,
            exposure: params.exposure,
            scale: params.scale,
            interleave: params.interleave.max(1),
            stratified: u32::from(stratified),
            _pad: 0,
        };
        let params_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lights.stochastic"),
            contents: bytemuck::bytes_of(&host),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let strata_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lights.stochastic strata"),
            contents: bytemuck::cast_slice(if stratified { strata } else { &[0u32] }),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let c = wgpu::ShaderStages::COMPUTE;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lights.stochastic"),
            entries: &[
                entry(0, c, UNIFORM),
                entry(1, c, storage(false)),
                entry(2, c, storage(true)),
            ],
        });
        let module = STOCHASTIC.create(d);
        let pipeline = pipeline::compute(
            d,
            &module,
            &pipeline::layout(d, "lights.stochastic", &[&layout]),
            "draw",
        );
        let group = pipeline::buffers_group(
            d,
            "lights.stochastic",
            &layout,
            &[&params_buf, &scene.lights, &strata_buf],
        );
        Ok(Self {
            params: params_buf,
            host,
            pipeline,
            group,
            groups,
        })
    }

    /// The same draws with alpha written as 0: each light shaded with the windowed falloff
    /// over its drawn range, Russian roulette without the reweighting. Biased on purpose: the
    /// unbiasedness test must fail on it.
    pub fn biased(mut self, ctx: &GpuContext) -> Self {
        self.host.biased = 1;
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&self.host));
        self
    }

    /// Draws every light's range for frame `frame` into the scene's light buffer; the pass's
    /// GPU time where timed.
    pub fn draw(&self, ctx: &GpuContext, frame: u32) -> Result<Option<Vec<PassTiming>>, GpuError> {
        ctx.queue.write_buffer(
            &self.params,
            std::mem::offset_of!(GpuStochasticParams, frame) as u64,
            bytemuck::bytes_of(&frame),
        );
        let mut timer = GpuTimer::new(ctx, 1);
        timer.set_category(Category::LightUpdate);
        // Not ctx.encoder: the draw is not part of the frame's encoding time.
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("lights.stochastic"),
            });
        pipeline::dispatch(
            &mut encoder,
            &mut timer,
            "lights.stochastic",
            &self.pipeline,
            &[&self.group],
            self.groups,
        );
        timer.resolve(&mut encoder);
        ctx.submit_and_wait(encoder, "lights.stochastic")?;
        timer.read(ctx)
    }
}
