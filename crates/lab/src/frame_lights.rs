//! What a cell does to its lights before each frame it renders, in this order, as an
//! application's frame does: a cell whose `lights.motion` is not `Static` moves its generated
//! lights (by the GPU animation pass or a host upload, `light_update`, both from
//! `manylights_gpu::motion`); a cell with `radius: Hierarchy` builds the lighting grid hierarchy
//! of its lights on the GPU (`manylights_gpu::hierarchy`, static lights too: an application
//! rebuilds it each frame); a cell with `radius: Stochastic` draws its lights' ranges
//! (`crate::noise::Draws`). The frame index drives all three, so a rerun does the same; the
//! check of every measured frame (the exact oracle, accuracy) sees the lights as that frame had
//! them.

use manylights_gpu::hierarchy::{GpuHierarchy, HierarchyPlan, Moving};
use manylights_gpu::motion::{LightMotion, UpdateCost};
use manylights_gpu::{GpuContext, GpuScene};
use manylights_scene::{RadiusRule, Scene};

use crate::LabError;
use crate::experiment::{Config, LightUpdate};
use crate::noise::Draws;

/// With `radius: Hierarchy`, the plan of the cell's lighting grid hierarchy and the scene it
/// shades: the scene's geometry with the plan's layout of lights in place of its own (points,
/// every level's table slots, spots), which the GPU build fills each frame; none otherwise.
/// Moving lights (the scene's generated ones from `first` on, `moving_from`) are planned for
/// where they are at every frame the cell renders; the lights before them never move, and the
/// build keeps their level-1 sums (`HierarchyPlan::static_lights`).
pub(crate) fn hierarchy_plan(
    c: &Config,
    scene: &Scene,
    first: usize,
) -> Result<Option<(HierarchyPlan, Scene)>, LabError> {
    let Some(params) = c.lights.radius.hierarchy_params() else {
        return Ok(None);
    };
    let anchors = anchors(c, scene)?;
    let moving = Moving {
        motion: &c.lights.motion,
        first: moving_from(c, scene, first),
        frames: c.warmup + c.frames,
        anchors: &anchors,
    };
    HierarchyPlan::for_scene(scene, params, Some(moving))
        .map(Some)
        .map_err(LabError::from)
}

/// The first of the scene's lights that moves, where its generated lights start at `first`:
/// the last `LightSpec::moving_count` of them move (all of them by default).
fn moving_from(c: &Config, scene: &Scene, first: usize) -> usize {
    first_moving(&c.lights, scene.lights.len(), first)
}

/// The first of `lights` lights that `spec` moves, its generated ones from `first` on.
fn first_moving(spec: &manylights_scene::LightSpec, lights: usize, first: usize) -> usize {
    let generated = lights.saturating_sub(first);
    lights - (spec.moving_count() as usize).min(generated)
}

/// The anchor normals of the cell's moving lights where its motion reads them
/// (`Motion::Glide`: `LightSpec::anchors` over the scene's geometry, the last
/// `LightSpec::moving_count`), else none.
fn anchors(c: &Config, scene: &Scene) -> Result<Vec<glam::Vec3>, LabError> {
    if c.lights.motion.uses_anchors() {
        let all = c.lights.anchors(scene)?;
        let moving = (c.lights.moving_count() as usize).min(all.len());
        Ok(all[all.len() - moving..].to_vec())
    } else {
        Ok(Vec::new())
    }
}

/// A cell's moving lights.
struct Motion {
    motion: LightMotion,
    update: LightUpdate,
    /// With a hierarchy: the light buffer of the lights as they are (the infinite-range
    /// reference's scene), where they are copied after each move.
    as_they_are: Option<wgpu::Buffer>,
}

/// A cell's lights as they change before each frame.
pub(crate) struct FrameLights {
    motion: Option<Motion>,
    hierarchy: Option<GpuHierarchy>,
    draws: Option<Draws>,
    /// Whether the hierarchy samples its bands (drawn afresh each frame).
    sampled_bands: bool,
}

/// The scene a cell's lights are part of: `scene` uploaded as `gpu_scene` (or as the hierarchy's
/// lights), its lights from `first` on the generated ones.
pub(crate) struct LightsOf<'a> {
    pub(crate) scene: &'a Scene,
    pub(crate) gpu_scene: &'a GpuScene,
    pub(crate) first: usize,
    /// With a hierarchy and accuracy measured, the lights as they are.
    pub(crate) as_they_are: Option<&'a GpuScene>,
}

impl FrameLights {
    /// The lights of `of` as cell `c` changes them, over `hierarchy` (its build).
    pub(crate) fn new(
        ctx: &GpuContext,
        c: &Config,
        of: &LightsOf<'_>,
        hierarchy: Option<GpuHierarchy>,
    ) -> Result<Self, LabError> {
        let (scene, first) = (of.scene, moving_from(c, of.scene, of.first));
        let motion = if c.lights.motion.is_static() || first >= scene.lights.len() {
            None
        } else {
            let moving = &scene.lights[first..];
            let anchors = anchors(c, scene)?;
            let motion = match &hierarchy {
                Some(h) => LightMotion::on_buffer(
                    ctx,
                    h.source(),
                    scene.lights.len() as u32,
                    moving,
                    &anchors,
                    first as u32,
                    c.lights.motion,
                ),
                None => LightMotion::new(
                    ctx,
                    of.gpu_scene,
                    moving,
                    &anchors,
                    first as u32,
                    c.lights.motion,
                ),
            }?;
            Some(Motion {
                motion,
                update: c.light_update,
                as_they_are: hierarchy
                    .as_ref()
                    .and(of.as_they_are)
                    .map(|s| s.lights.clone()),
            })
        };
        Ok(Self {
            motion,
            hierarchy,
            draws: Draws::new(ctx, c, of.gpu_scene, scene, of.first)?,
            sampled_bands: matches!(
                c.lights.radius,
                RadiusRule::Hierarchy {
                    sample_from: Some(_),
                    ..
                }
            ),
        })
    }

    /// The lighting grid hierarchy built before each frame, if any.
    pub(crate) fn hierarchy(&self) -> Option<&GpuHierarchy> {
        self.hierarchy.as_ref()
    }

    /// The stochastic ranges drawn before each frame, if any.
    pub(crate) fn draws(&self) -> Option<&Draws> {
        self.draws.as_ref()
    }

    /// Whether lights move.
    pub(crate) fn moving(&self) -> bool {
        self.motion.is_some()
    }

    /// Before frame `frame`: moves the lights to where they are then, builds the hierarchy over
    /// them, draws the stochastic ranges; the GPU's part timed in that order.
    pub(crate) fn before_frame(
        &mut self,
        ctx: &GpuContext,
        frame: u32,
    ) -> Result<UpdateCost, LabError> {
        let mut cost = self.move_and_build(ctx, frame)?;
        if let Some(d) = &self.draws
            && let Some(t) = d.draw(ctx, frame)?
        {
            cost.gpu.get_or_insert_with(Vec::new).extend(t);
        }
        Ok(cost)
    }

    /// Before the check of pose `k`, the lights as frame `frame` had them (`None`: as they are,
    /// frame 0's draws): moving lights moved there and the hierarchy built over them; static
    /// lights whose hierarchy samples its bands built once, with frame 0's draws (the timed
    /// frames drew their own); the stochastic ranges drawn.
    pub(crate) fn before_check(
        &mut self,
        ctx: &GpuContext,
        k: usize,
        frame: Option<u32>,
    ) -> Result<(), LabError> {
        match frame {
            Some(f) if self.moving() => {
                self.move_and_build(ctx, f)?;
            }
            _ if k == 0 && self.sampled_bands && !self.moving() => {
                self.move_and_build(ctx, 0)?;
            }
            _ => {}
        }
        if let Some(d) = &self.draws {
            d.draw(ctx, frame.unwrap_or(0))?;
        }
        Ok(())
    }

    /// Moves the lights to where they are at frame `frame`, then builds the hierarchy.
    fn move_and_build(&mut self, ctx: &GpuContext, frame: u32) -> Result<UpdateCost, LabError> {
        let moved = match &mut self.motion {
            Some(m) => Some(match m.update {
                LightUpdate::Gpu => m.motion.animate(ctx, frame)?,
                LightUpdate::Upload => m.motion.upload(ctx, frame)?,
            }),
            None => None,
        };
        let (mut gpu, host_ms) = moved.map_or((None, None), |c| (c.gpu, c.host_ms));
        if let Some(h) = &self.hierarchy {
            // Sampled bands draw afresh each frame.
            h.set_seed(ctx, frame);
            if let Some(t) = h.build(ctx)? {
                gpu.get_or_insert_with(Vec::new).extend(t);
            }
            if let Some(to) = self.motion.as_ref().and_then(|m| m.as_they_are.as_ref()) {
                let mut e = ctx
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("lights.as_they_are"),
                    });
                e.copy_buffer_to_buffer(h.source(), 0, to, 0, h.source().size().min(to.size()));
                ctx.submit_and_wait(e, "lights.as_they_are")?;
            }
        }
        Ok(UpdateCost { gpu, host_ms })
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

#[cfg(test)]
mod tests {
    use manylights_scene::{LightSpec, Motion};

    #[test]
    fn the_last_generated_lights_move() {
        let spec = LightSpec {
            count: 400,
            motion: Motion::Orbit(1.0),
            moving: 0.25,
            ..LightSpec::default()
        };
        // 10 lights of the scene's own, then 400 generated: the last 100 move.
        assert_eq!(super::first_moving(&spec, 410, 10), 310);
        let all = LightSpec {
            moving: 1.0,
            ..spec
        };
        assert_eq!(super::first_moving(&all, 410, 10), 10);
        let none = LightSpec {
            motion: Motion::Static,
            ..spec
        };
        assert_eq!(super::first_moving(&none, 410, 10), 410);
    }
}
