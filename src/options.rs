//! What `render` and `cull` share: the scene, its lights, the resolution and the adapter
//! (`SceneArgs`), the culling strategy and its parameters (`StrategyArgs`, in
//! `strategy_opts.rs`), and the per-pass timings they print.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use manylights_gpu::stochastic::StochasticRanges;
use manylights_gpu::{GpuContext, GpuOptions, GpuScene};
use manylights_scene::gltf_import::{self, GltfOptions};
use manylights_scene::procedural::{self, ProceduralScene};
use manylights_scene::stochastic::{INTERLEAVE_MAX, StochasticBound, StochasticDraw};
use manylights_scene::{LightGenerator, LightSpec, Model, RadiusRule, Scene};

pub(crate) use crate::strategy_opts::StrategyArgs;

/// `--radius` where none is given.
const DEFAULT_RADIUS: f32 = 3.0;

/// Scene, lights, resolution and adapter: shared by every subcommand.
#[derive(clap::Args, Debug)]
pub(crate) struct SceneArgs {
    /// A procedural scene (atrium, pillars, topdown, city, cis5650), a real scene of scenes/
    /// (sponza, staircase, dining-room, bathroom, kitchen: scenes/NOTICE.md), or a path to a
    /// .gltf/.glb file (compressed where it ends in .xz).
    #[arg(long, default_value = "atrium")]
    pub(crate) scene: String,
    /// Add the procedural scene's glass (transparent surfaces): the atrium's gallery railings,
    /// a pane in front of the pillars' far wall, sheets before the CIS 5650 hall's pillars.
    #[arg(long)]
    pub(crate) glass: bool,
    /// Material models to give the scene's surfaces in turns, comma-separated (`ggx` makes
    /// every surface glTF's metallic-roughness GGX; `blinn-phong,ggx,sheen,clear-coat,wrap`
    /// mixes five in one frame). Default: the scene's own (procedural scenes: Blinn-Phong;
    /// glTF files: GGX).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub(crate) materials: Vec<ModelName>,
    /// Number of lights to generate (0 renders only the scene's own lights).
    #[arg(long, default_value_t = 1024)]
    pub(crate) lights: u32,
    /// Where lights are placed.
    #[arg(long, value_enum, default_value_t = Generator::Field)]
    pub(crate) generator: Generator,
    /// Seed of every random choice of the light generator.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Fixed light radius in metres (the light contributes exactly nothing beyond it; default
    /// 3). Stochastic ranges and the hierarchy choose their own ranges.
    #[arg(long, conflicts_with_all = ["threshold", "stochastic", "hierarchy"])]
    pub(crate) radius: Option<f32>,
    /// Derive each radius from its intensity instead: the distance where intensity / d^2 falls
    /// to this threshold.
    #[arg(long)]
    pub(crate) threshold: Option<f32>,
    /// Stochastic light culling (Tokuyoshi and Harada 2016) instead of a cut-off: each light
    /// draws a random range every frame, so that the image is an unbiased estimate of infinite
    /// range. E bounds one light's standard deviation: of its incident contribution
    /// (exposure * intensity * max(colour) * falloff at exposure 1) by default, of its
    /// reflected radiance with --bound albedo (docs/EXPERIMENTS.md).
    #[arg(long, value_name = "E", conflicts_with = "threshold", value_parser = positive_f32)]
    pub(crate) stochastic: Option<f32>,
    /// The lighting grid hierarchy (Yuksel and Yuksel 2017; Lin and Yuksel 2019) instead of a
    /// cut-off: near lights as they are, far ones from aggregates on nested grids, each level's
    /// light a sphere of bounded range with its band; deterministic, its bias shrinking as
    /// ALPHA (above 0; the papers use 1 and more) grows. Built once on the GPU before the frame; the lists and images
    /// are the hierarchy's, and render --compare also scores against infinite range.
    #[arg(long, value_name = "ALPHA", conflicts_with_all = ["threshold", "stochastic"], value_parser = crate::hierarchy_opt::alpha)]
    pub(crate) hierarchy: Option<f32>,
    /// The lighting grid hierarchy's finest grid spacing in metres, at least (it doubles while
    /// the grid would hold more than --finest-nodes times as many nodes as there are lights;
    /// default 0.25): with --hierarchy, and tune's --alphas.
    #[arg(long, value_name = "H", value_parser = positive_f32)]
    pub(crate) spacing: Option<f32>,
    /// The most nodes the hierarchy's finest grid may hold a point light (default 2; the
    /// authors' implementation 0.25, coarser grids): with --hierarchy, and tune's --alphas.
    #[arg(long, value_name = "R", value_parser = positive_f32)]
    pub(crate) finest_nodes: Option<f32>,
    /// How much farther, in its grid's units, each level of the hierarchy takes over than the
    /// level below (from 1, the papers' bands and the default, to 4): with --hierarchy, and
    /// tune's --alphas.
    #[arg(long, value_name = "K", value_parser = positive_f32)]
    pub(crate) growth: Option<f32>,
    /// How far each level of the hierarchy hands over to the next, from its band's r to this
    /// times r (above 1 and at most 2, the papers' ramps and the default): with --hierarchy,
    /// and tune's --alphas.
    #[arg(long, value_name = "C", value_parser = positive_f32)]
    pub(crate) ramp: Option<f32>,
    /// With --hierarchy: stochastic band selection from level L on (0: every level; 1: the
    /// aggregates): each of those lights draws its band, weight 1 inside it, unbiased against
    /// the hierarchy, with shorter lists and noise.
    #[arg(long, value_name = "L", requires = "hierarchy")]
    pub(crate) sample_from: Option<u32>,
    /// With --hierarchy: the spots' direction bins, N cells along each side of an octahedral
    /// map of their axes (1 to 16), each bin's aggregates spots of its cone; 0, the default:
    /// none, the spots spread into the point lights' nodes with their flux.
    #[arg(long, value_name = "N")]
    pub(crate) spot_bins: Option<u32>,
    /// With --stochastic: what E bounds.
    #[arg(long, value_enum, requires = "stochastic")]
    pub(crate) bound: Option<BoundName>,
    /// With --stochastic: frames drawn afresh, K >= 1 (1: one frame). render averages them
    /// into one image (a static view accumulated) and --compare scores that image; cull
    /// checks every frame's lists.
    #[arg(long, value_name = "K", requires = "stochastic")]
    pub(crate) accumulate: Option<u32>,
    /// With --stochastic: interleaved sampling over N x N pixel classes, each drawing its own
    /// ranges, N from 1 (none) to 8.
    #[arg(long, value_name = "N", requires = "stochastic")]
    pub(crate) interleave: Option<u32>,
    /// With --stochastic: how a frame's numbers are drawn across the lights (stratified by
    /// default: one shifted lattice over the lights in spatial order; independent: one hash a
    /// light, as Tokuyoshi and Harada 2016).
    #[arg(long, value_enum, requires = "stochastic")]
    pub(crate) draw: Option<DrawName>,
    /// Intensity of every generated light.
    #[arg(long, default_value_t = 4.0)]
    pub(crate) intensity: f32,
    /// The exposure rule, in place of --intensity: every generated light gets the intensity at
    /// which the median surface point of the scene receives this irradiance (1 is a sensible
    /// exposure; docs/EXPERIMENTS.md, "Lights").
    #[arg(long, value_parser = positive_f32, conflicts_with = "intensity")]
    pub(crate) irradiance: Option<f32>,
    /// Fraction of generated lights that are spot lights, in [0, 1].
    #[arg(long, default_value_t = 0.0)]
    pub(crate) spot_fraction: f32,
    /// Image width in pixels (at most the device's max_texture_dimension_2d).
    #[arg(long, default_value_t = 1280, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub(crate) width: u32,
    /// Image height in pixels (at most the device's max_texture_dimension_2d).
    #[arg(long, default_value_t = 720, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub(crate) height: u32,
    /// Output directory, created if needed (default: out/<subcommand>).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// GPU adapter: a substring of its name or its index (default: $MANYLIGHTS_ADAPTER, else the
    /// first discrete GPU, else any adapter, lavapipe included).
    #[arg(long)]
    pub(crate) adapter: Option<String>,
}

/// `--bound`'s values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum BoundName {
    /// One light's incident contribution, whatever the materials (the default).
    Light,
    /// The radiance a light reflects off a surface spreading the scene's largest directional
    /// albedo diffusely.
    Albedo,
}

/// `--draw`'s values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum DrawName {
    /// One randomly shifted lattice over the lights in spatial order (the default).
    Stratified,
    /// One independent hash a light and frame.
    Independent,
}

/// A finite number above 0, for clap.
pub(crate) fn positive_f32(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{s}`: a finite number above 0")),
    }
}

/// The most frames `--accumulate` takes.
pub(crate) const ACCUMULATE_MAX: u32 = 4096;

/// A material model's command-line name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum ModelName {
    /// Lambert plus a normalised Blinn-Phong lobe (the procedural scenes' own).
    BlinnPhong,
    /// glTF's metallic-roughness GGX.
    Ggx,
    /// Cloth: Lambert plus a Charlie sheen lobe.
    Sheen,
    /// A clear coat over GGX.
    ClearCoat,
    /// Wrapped diffuse.
    Wrap,
}

impl From<ModelName> for Model {
    fn from(m: ModelName) -> Self {
        match m {
            ModelName::BlinnPhong => Model::BlinnPhong,
            ModelName::Ggx => Model::Ggx,
            ModelName::Sheen => Model::Sheen,
            ModelName::ClearCoat => Model::ClearCoat,
            ModelName::Wrap => Model::Wrap,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum BackendName {
    /// The brute-force reference renderer.
    Reference,
    /// Forward+: depth prepass, culling, forward shading over the lists.
    Forward,
    /// Deferred: G-buffer, culling, compute lighting over the lists (position rebuilt from depth).
    Deferred,
    /// Deferred with the interpolated world position stored in the G-buffer.
    DeferredStoredPosition,
    /// Every light at every fragment, no culling.
    NaiveForward,
    /// Visibility buffer: depth and triangle ids, culling, compute lighting that interpolates
    /// each pixel's triangle.
    Visibility,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub(crate) enum Generator {
    /// Uniform in the scene's light volume.
    Uniform,
    /// On the scene's surfaces, lifted 0.1 m along the normal.
    Surface,
    /// Eight Gaussian hot spots of 1.5 m standard deviation.
    Clustered,
    /// A stratified field through the whole volume (the Forward+ paper's demo).
    Field,
    /// On the scene's surfaces, area-weighted, lifted 0.05 to 0.5 m along the shading normal
    /// (spots aim along it): lights stay in a real interior's rooms.
    OnSurfaces,
    /// Fixtures: hanging 0.15 m under downward-facing surfaces (spots aim down) and, half of
    /// them, 0.15 m out from walls (spots aim out and 30 degrees down).
    Fixtures,
}

pub(crate) fn load_scene(name: &str) -> Result<Scene> {
    let looks_like_file = name.ends_with(".gltf")
        || name.ends_with(".glb")
        || name.ends_with(".xz")
        || name.contains('/');
    let (scene, report) = if looks_like_file {
        gltf_import::load(Path::new(name), &GltfOptions::default())?
    } else if manylights_scene::real::find(name).is_some() {
        manylights_scene::real::load(name, &GltfOptions::default())?
    } else {
        return ProceduralScene::from_name(name)
            .with_context(|| {
                format!(
                    "--scene {name}: not a file path (.gltf, .glb, .xz), not a real scene ({}) and not a procedural one ({})",
                    manylights_scene::real::names(),
                    procedural::NAMES.join(", ")
                )
            })?
            .build()
            .map_err(Into::into);
    };
    if report.skipped_primitives + report.skipped_directional_lights > 0 {
        eprintln!(
            "note: {name}: skipped {} point/line primitives and {} directional lights (not supported)",
            report.skipped_primitives, report.skipped_directional_lights
        );
    }
    if report.unread_textures > 0 {
        eprintln!(
            "warning: {name}: {} material textures are not read (their factors are)",
            report.unread_textures
        );
    }
    Ok(scene)
}

impl SceneArgs {
    /// The scene with its generated lights, validated.
    /// The `--materials` models, each at most once.
    pub(crate) fn models(&self) -> Result<Vec<Model>> {
        let models: Vec<Model> = self.materials.iter().map(|&m| m.into()).collect();
        for (i, m) in models.iter().enumerate() {
            if models[..i].contains(m) {
                bail!(
                    "--materials names {} twice: each model at most once",
                    m.name()
                );
            }
        }
        Ok(models)
    }

    pub(crate) fn build(&self) -> Result<Scene> {
        let mut scene = if self.glass {
            let mut spec = ProceduralScene::from_name(&self.scene).with_context(|| {
                format!(
                    "--glass: --scene {} is not a procedural scene with glass (atrium, pillars, cis5650)",
                    self.scene
                )
            })?;
            match &mut spec {
                ProceduralScene::Atrium(p) => p.glass = true,
                ProceduralScene::Pillars(p) => p.glass = true,
                ProceduralScene::Cis5650(p) => p.glass = true,
                _ => bail!(
                    "--glass: scene {} has no glass panes (atrium, pillars and cis5650 have)",
                    self.scene
                ),
            }
            spec.build()?
        } else {
            load_scene(&self.scene)?
        };
        self.check_stochastic()?;
        scene.assign_models(&self.models()?);
        let spec = self.light_spec();
        let generated = spec.generate(&scene).context(
            "invalid light options (--radius, --threshold, --stochastic, --hierarchy, --spacing, --finest-nodes, --growth, --ramp, --spot-bins, --intensity, --spot-fraction)",
        )?;
        scene.lights.extend(generated);
        scene
            .validate()
            .with_context(|| format!("scene {}", scene.name))?;
        Ok(scene)
    }

    /// The generated lights' description.
    pub(crate) fn light_spec(&self) -> LightSpec {
        LightSpec {
            generator: match self.generator {
                Generator::Uniform => LightGenerator::Uniform,
                Generator::Surface => LightGenerator::SurfaceHugging { offset: 0.1 },
                Generator::Clustered => LightGenerator::Clustered {
                    clusters: 8,
                    spread: 1.5,
                },
                Generator::Field => LightGenerator::LightField,
                Generator::OnSurfaces => LightGenerator::OnSurfaces {
                    offset: (0.05, 0.5),
                },
                Generator::Fixtures => LightGenerator::Fixtures {
                    drop: 0.15,
                    on_walls: 0.5,
                },
            },
            count: self.lights,
            seed: self.seed,
            radius: match (self.stochastic, self.threshold) {
                (Some(error), _) => RadiusRule::Stochastic {
                    error,
                    bound: match self.bound {
                        Some(BoundName::Albedo) => StochasticBound::Albedo,
                        Some(BoundName::Light) | None => StochasticBound::Light,
                    },
                    exposure: 1.0,
                    // The experiments' form: 0 is one frame.
                    accumulate: if self.frames() > 1 { self.frames() } else { 0 },
                    seeds: 1,
                    interleave: self.interleave.unwrap_or(1),
                    draw: match self.draw {
                        Some(DrawName::Independent) => StochasticDraw::Independent,
                        Some(DrawName::Stratified) | None => StochasticDraw::Stratified,
                    },
                },
                (None, Some(t)) => RadiusRule::Threshold(t),
                (None, None) => self
                    .hierarchy_rule()
                    .unwrap_or(RadiusRule::Fixed(self.radius.unwrap_or(DEFAULT_RADIUS))),
            },
            intensity: self.intensity,
            irradiance: self.irradiance,
            spot_fraction: self.spot_fraction,
            ..LightSpec::default()
        }
    }

    /// Checks the stochastic options; the error names the option and what it accepts.
    pub(crate) fn check_stochastic(&self) -> Result<()> {
        if let Some(k) = self.accumulate
            && !(1..=ACCUMULATE_MAX).contains(&k)
        {
            bail!("invalid --accumulate {k}: frames from 1 (one frame) to {ACCUMULATE_MAX}");
        }
        if let Some(n) = self.interleave
            && !(1..=INTERLEAVE_MAX).contains(&n)
        {
            bail!("invalid --interleave {n}: 1 (none) to {INTERLEAVE_MAX} (N x N pixel classes)");
        }
        Ok(())
    }

    /// The frames drawn with --stochastic (`--accumulate`, 1 by default; always 1 without
    /// --stochastic, which --accumulate requires).
    pub(crate) fn frames(&self) -> u32 {
        self.accumulate.unwrap_or(1).max(1)
    }

    /// The stochastic ranges of `scene`'s generated lights (the last `--lights` of its light
    /// buffer) where --stochastic asks for them (the scene uploaded for them by `upload`).
    pub(crate) fn draws(
        &self,
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        scene: &Scene,
    ) -> Result<Option<StochasticRanges>> {
        let Some(params) = self.light_spec().stochastic(scene) else {
            return Ok(None);
        };
        let first = scene.lights.len() as u32 - self.lights;
        let strata = manylights_scene::stochastic::strata(&scene.lights[first as usize..]);
        Ok(Some(StochasticRanges::new(
            ctx,
            gpu_scene,
            first,
            self.lights,
            &params,
            &strata,
        )?))
    }

    /// The device, checked against the resolution.
    pub(crate) fn gpu(&self) -> Result<GpuContext> {
        let ctx = GpuContext::new(&GpuOptions {
            adapter: self.adapter.clone(),
        })?;
        eprintln!("adapter: {}", ctx.summary());
        ctx.check_resolution(self.width, self.height)
            .context("invalid --width/--height")?;
        Ok(ctx)
    }
}

pub(crate) fn print_timings(timings: Option<&[manylights_gpu::timing::PassTiming]>) {
    match timings {
        Some(t) => {
            for p in t {
                println!("  {:<28} {:>8} {:>10.3} ms", p.label, p.kind.as_str(), p.ms);
            }
        }
        None => println!("  (no GPU timings: the adapter has no timestamp queries)"),
    }
}
