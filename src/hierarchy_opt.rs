//! `--hierarchy` on `render` and `cull`: the scene's lights shaded through the lighting grid
//! hierarchy (`radius: Hierarchy` in experiments), built once on the GPU before the frame
//! (`manylights_gpu::hierarchy`), and the lights as they are kept for the infinite-range
//! reference.

use anyhow::{Result, bail};
use manylights_gpu::hierarchy::{GpuHierarchy, HierarchyPlan};
use manylights_gpu::{GpuContext, GpuScene, LightModel};
use manylights_scene::{RadiusRule, Scene};

use crate::options::SceneArgs;

/// A scene on the GPU as it is shaded.
pub(crate) struct Shaded {
    /// The scene as shaded: with --hierarchy its geometry and the hierarchy's lights (every
    /// level's, each with its band), else the scene as built.
    pub(crate) scene: Scene,
    pub(crate) gpu_scene: GpuScene,
    /// With --hierarchy: the scene's lights as they are, the infinite-range reference's.
    pub(crate) as_they_are: Option<GpuScene>,
}

impl SceneArgs {
    /// `--hierarchy ALPHA` with `--spacing H` (0.25 m by default) as a radius rule.
    pub(crate) fn hierarchy_rule(&self) -> Option<RadiusRule> {
        self.hierarchy
            .map(|alpha| self.hierarchy_with(alpha, self.growth(), self.ramp(), self.sample_from))
    }

    /// The hierarchy of `alpha`, `growth` and `ramp` with `--spacing` and `--finest-nodes`
    /// (tune's candidates; --hierarchy's rule).
    pub(crate) fn hierarchy_with(
        &self,
        alpha: f32,
        growth: f32,
        ramp: f32,
        sample_from: Option<u32>,
    ) -> RadiusRule {
        RadiusRule::Hierarchy {
            alpha,
            spacing: self.spacing.unwrap_or(DEFAULT_SPACING),
            finest_nodes: self.finest_nodes(),
            growth,
            ramp,
            sample_from,
            spot_bins: self
                .spot_bins
                .unwrap_or(manylights_scene::hierarchy::SPOT_BINS),
        }
    }

    /// `--finest-nodes R`, or the default (2).
    pub(crate) fn finest_nodes(&self) -> f32 {
        self.finest_nodes
            .unwrap_or(manylights_scene::hierarchy::FINEST_NODES as f32)
    }

    /// `--growth K`, or the default (1).
    pub(crate) fn growth(&self) -> f32 {
        self.growth
            .unwrap_or(manylights_scene::hierarchy::GROWTH as f32)
    }

    /// `--ramp C`, or the default (2).
    pub(crate) fn ramp(&self) -> f32 {
        self.ramp
            .unwrap_or(manylights_scene::hierarchy::RAMP as f32)
    }

    /// `scene` uploaded at its camera: with --hierarchy, the hierarchy of its lights planned,
    /// built on the GPU and checked (a splat that found no room is an error), and what it is
    /// printed.
    pub(crate) fn upload(&self, ctx: &GpuContext, scene: Scene) -> Result<Shaded> {
        let (w, h) = (self.width, self.height);
        if let (Some(h), None) = (self.spacing, self.hierarchy) {
            bail!("--spacing {h} without --hierarchy: the spacing is the hierarchy's grid's");
        }
        if let (Some(r), None) = (self.finest_nodes, self.hierarchy) {
            bail!(
                "--finest-nodes {r} without --hierarchy: it is the hierarchy's finest grid's rule"
            );
        }
        if let (Some(k), None) = (self.growth, self.hierarchy) {
            bail!("--growth {k} without --hierarchy: it is the hierarchy's bands'");
        }
        if let (Some(c), None) = (self.ramp, self.hierarchy) {
            bail!("--ramp {c} without --hierarchy: it is the hierarchy's bands'");
        }
        if let (Some(n), None) = (self.spot_bins, self.hierarchy) {
            bail!("--spot-bins {n} without --hierarchy: they are the hierarchy's spots' bins");
        }
        let Some(
            rule @ RadiusRule::Hierarchy {
                alpha,
                finest_nodes,
                growth,
                ramp,
                sample_from,
                ..
            },
        ) = self.hierarchy_rule()
        else {
            // The generated lights are the last --lights of the light buffer.
            let first = scene.lights.len() as u32 - self.lights;
            let model = LightModel::of_rule(&self.light_spec().radius, first);
            let gpu_scene = GpuScene::upload_with(ctx, &scene, model, &scene.camera, w, h)?;
            return Ok(Shaded {
                scene,
                gpu_scene,
                as_they_are: None,
            });
        };
        let params = rule.hierarchy_params().expect("a hierarchy rule");
        let (plan, shaded) = HierarchyPlan::for_scene(&scene, params, None)?;
        let (levels, h_used, points, spots) = (plan.levels, plan.h, plan.points, plan.spots);
        let bins = plan.bins.len();
        let gpu_scene =
            GpuScene::upload_with(ctx, &shaded, plan.light_model(), &scene.camera, w, h)?;
        let build = GpuHierarchy::new(ctx, plan, &scene.lights, &gpu_scene)?;
        let timings = build.build(ctx)?;
        let (outside, full) = build.dropped(ctx)?;
        if outside + full > 0 {
            bail!(
                "--hierarchy: the build dropped {outside} splats outside its grids' boxes and \
                 {full} into full tables; a larger --spacing needs fewer nodes"
            );
        }
        let ms: Option<f64> = timings.map(|t| t.iter().map(|p| p.ms).sum());
        println!(
            "  lighting grid hierarchy: alpha {alpha}, finest spacing {h_used} m, {levels} levels, the finest grid at most {finest_nodes} nodes a point light, bands growing {growth} over ramps of {ramp}, {} lights shaded in place of {} ({points} point lights, {spots} spots in {} direction bins){}{} (its sums {})",
            shaded.lights.len(),
            scene.lights.len(),
            bins,
            sample_from.map_or_else(String::new, |l| format!(", bands sampled from level {l}")),
            ms.map_or_else(String::new, |ms| format!(", built in {ms:.3} ms")),
            build.sums().describe()
        );
        let as_they_are = GpuScene::upload(ctx, &scene, &scene.camera, w, h)?;
        Ok(Shaded {
            scene: shaded,
            gpu_scene,
            as_they_are: Some(as_they_are),
        })
    }
}

/// `--spacing`'s default, metres (the experiments' and `tune`'s).
pub(crate) const DEFAULT_SPACING: f32 = 0.25;

/// `--hierarchy`'s parser: a finite alpha above 0.
pub(crate) fn alpha(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{s}`: a finite accuracy parameter above 0")),
    }
}
