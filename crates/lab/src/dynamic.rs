//! Moving lights in a run: a cell whose `lights.motion` is not `Static` moves its generated
//! lights before every frame it renders, by the GPU animation pass or by a host upload
//! (`light_update`), both from `manylights_gpu::motion`. The frame index drives the motion, so
//! a rerun moves the lights the same way; the evaluation of every measured frame (the exact
//! oracle, accuracy) sees the lights where that frame had them.

use manylights_gpu::motion::{LightMotion, UpdateCost};
use manylights_gpu::{GpuContext, GpuScene};
use manylights_scene::Scene;

use crate::LabError;
use crate::experiment::{Config, LightUpdate};

/// The moving lights of a cell and how they reach the GPU.
pub(crate) struct Movers {
    motion: LightMotion,
    update: LightUpdate,
}

impl Movers {
    /// The movers of `scene` (uploaded as `gpu_scene`), whose lights from `first` on are the
    /// generated ones; `None` where they do not move.
    pub(crate) fn new(
        ctx: &GpuContext,
        c: &Config,
        gpu_scene: &GpuScene,
        scene: &Scene,
        first: usize,
    ) -> Result<Option<Self>, LabError> {
        if c.lights.motion.is_static() || first >= scene.lights.len() {
            return Ok(None);
        }
        let motion = LightMotion::new(
            ctx,
            gpu_scene,
            &scene.lights[first..],
            first as u32,
            c.lights.motion,
        )
        .map_err(|e| LabError::Other(e.to_string()))?;
        Ok(Some(Self {
            motion,
            update: c.light_update,
        }))
    }

    /// Moves the lights to where they are at frame `frame`.
    pub(crate) fn update(&mut self, ctx: &GpuContext, frame: u32) -> Result<UpdateCost, LabError> {
        match self.update {
            LightUpdate::Gpu => self.motion.animate(ctx, frame),
            LightUpdate::Upload => self.motion.upload(ctx, frame),
        }
        .map_err(|e| LabError::Other(e.to_string()))
    }
}
