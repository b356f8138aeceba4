//! Lights that change each frame in a run: a cell whose `lights.motion` is not `Static` moves
//! its generated lights before every frame it renders, by the GPU animation pass or by a host
//! upload (`light_update`), both from `manylights_gpu::motion`; a cell with `radius:
//! Hierarchy` builds the lighting grid hierarchy of its lights on the GPU before every frame
//! (`manylights_gpu::hierarchy`, after the lights moved). The frame index drives the motion, so
//! a rerun moves the lights the same way; the evaluation of every measured frame (the exact
//! oracle, accuracy) sees the lights where that frame had them.

use manylights_gpu::hierarchy::{GpuHierarchy, HierarchyPlan};
use manylights_gpu::motion::{LightMotion, UpdateCost};
use manylights_gpu::{GpuContext, GpuScene};
use manylights_scene::Scene;

use crate::LabError;
use crate::experiment::{Config, LightUpdate};

/// With `radius: Hierarchy`, the plan of the cell's lighting grid hierarchy and the scene it
/// shades: the scene's geometry with the plan's layout of lights in place of its own (points,
/// every level's table slots, spots), which the GPU build fills each frame; none otherwise.
pub(crate) fn hierarchy_plan(
    c: &Config,
    scene: &Scene,
) -> Result<Option<(HierarchyPlan, Scene)>, LabError> {
    let Some(params) = c.lights.radius.hierarchy_params() else {
        return Ok(None);
    };
    // A moving light goes at most its radius from home (manylights_scene::motion).
    let moving = if c.lights.motion.is_static() {
        0.0
    } else {
        scene.lights.iter().map(|l| l.radius).fold(0.0, f32::max)
    };
    HierarchyPlan::for_scene(scene, params, moving)
        .map(Some)
        .map_err(LabError::from)
}

/// The lights of a cell that change each frame, and how.
pub(crate) struct Movers {
    motion: Option<LightMotion>,
    update: LightUpdate,
    hierarchy: Option<GpuHierarchy>,
    /// With a hierarchy of moving lights: the light buffer of the lights as they are (the
    /// infinite-range reference's scene), where they are copied after each move.
    as_they_are: Option<wgpu::Buffer>,
}

impl Movers {
    /// The movers of `scene` (uploaded as `gpu_scene`, or as `hierarchy`'s lights), whose
    /// lights from `first` on are the generated ones; `None` where nothing changes.
    pub(crate) fn new(
        ctx: &GpuContext,
        c: &Config,
        (gpu_scene, scene, first): (&GpuScene, &Scene, usize),
        hierarchy: Option<GpuHierarchy>,
        as_they_are: Option<&GpuScene>,
    ) -> Result<Option<Self>, LabError> {
        let motion = if c.lights.motion.is_static() || first >= scene.lights.len() {
            None
        } else {
            let moving = &scene.lights[first..];
            Some(match &hierarchy {
                Some(h) => LightMotion::on_buffer(
                    ctx,
                    h.source(),
                    scene.lights.len() as u32,
                    moving,
                    first as u32,
                    c.lights.motion,
                ),
                None => LightMotion::new(ctx, gpu_scene, moving, first as u32, c.lights.motion),
            }?)
        };
        if motion.is_none() && hierarchy.is_none() {
            return Ok(None);
        }
        Ok(Some(Self {
            as_they_are: motion
                .as_ref()
                .and(hierarchy.as_ref())
                .and(as_they_are)
                .map(|s| s.lights.clone()),
            motion,
            update: c.light_update,
            hierarchy,
        }))
    }

    /// The lighting grid hierarchy built before each frame, if any.
    pub(crate) fn hierarchy(&self) -> Option<&GpuHierarchy> {
        self.hierarchy.as_ref()
    }

    /// Whether lights move (a hierarchy of static lights is built each frame all the same).
    pub(crate) fn moving(&self) -> bool {
        self.motion.is_some()
    }

    /// Moves the lights to where they are at frame `frame`, then builds the hierarchy.
    pub(crate) fn update(&mut self, ctx: &GpuContext, frame: u32) -> Result<UpdateCost, LabError> {
        let mut cost = match (&mut self.motion, self.update) {
            (Some(m), LightUpdate::Gpu) => m.animate(ctx, frame)?,
            (Some(m), LightUpdate::Upload) => m.upload(ctx, frame)?,
            (None, _) => UpdateCost::default(),
        };
        if let Some(h) = &self.hierarchy {
            // Sampled bands draw afresh each frame.
            h.set_seed(ctx, frame);
            if let Some(t) = h.build(ctx)? {
                cost.gpu.get_or_insert_with(Vec::new).extend(t);
            }
            if let Some(to) = &self.as_they_are {
                let mut e = ctx
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("lights.as_they_are"),
                    });
                e.copy_buffer_to_buffer(h.source(), 0, to, 0, h.source().size().min(to.size()));
                ctx.submit_and_wait(e, "lights.as_they_are")?;
            }
        }
        Ok(cost)
    }

    /// An error where the hierarchy dropped a splat (a node outside its level's box, or a full
    /// table): its estimate would have lost power.
    pub(crate) fn check(&self, ctx: &GpuContext) -> Result<(), LabError> {
        let Some(h) = &self.hierarchy else {
            return Ok(());
        };
        let (outside, full) = h.dropped(ctx)?;
        if outside + full > 0 {
            return Err(LabError::HierarchyDropped { outside, full });
        }
        Ok(())
    }
}
