//! The experiment schema (RON, through serde); its expansion into cells is in `cells`.
//!
//! An experiment fixes one configuration and, in `sweep`, lists of values for any of its fields;
//! the cells are the cartesian product of those lists (in the order of [`Sweep`]'s fields), each
//! with a readable name built from its swept values. `sweep.variants` is one more axis whose
//! values change several fields together (a backend with its strategy, say), for comparisons that
//! are not a product. Unknown fields and bad values are errors with the file, line and column.

use std::path::Path;

use manylights_cull::{CullSettings, Strategy};
use manylights_scene::procedural::{
    AtriumParams, Cis5650Params, CityParams, PillarsParams, ProceduralScene, TopdownParams,
};
use manylights_scene::{LightGenerator, LightSpec, Model, Motion, RadiusRule};
use manylights_shade::{Backend, HdrFormat, Shadows, VisibilityPass};
use serde::{Deserialize, Serialize};

pub use crate::camera_spec::{CameraSpec, Pose};
pub use crate::cells::{Cell, params_label};

/// Where a scene comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum SceneSpec {
    /// The procedural atrium.
    Atrium(#[serde(default)] AtriumParams),
    /// Thin pillars before a far wall.
    Pillars(#[serde(default)] PillarsParams),
    /// A flat ground seen from above.
    Topdown(#[serde(default)] TopdownParams),
    /// A grid of boxes.
    City(#[serde(default)] CityParams),
    /// The CIS 5650 hall: Sponza's extents, two rows of pillars.
    Cis5650(#[serde(default)] Cis5650Params),
    /// A glTF file (relative paths are relative to the experiment file; read compressed where
    /// it ends in `.xz`).
    Gltf(String),
    /// A real scene of the repository's `scenes/` by name (`sponza`, `staircase`,
    /// `dining-room`, `bathroom`, `kitchen`; `manylights_scene::real`), its checksum checked.
    Real(String),
}

impl SceneSpec {
    /// Short name for results.
    pub fn name(&self) -> String {
        match self {
            Self::Atrium(_) => "atrium".into(),
            Self::Pillars(_) => "pillars".into(),
            Self::Topdown(_) => "topdown".into(),
            Self::City(_) => "city".into(),
            Self::Cis5650(_) => "cis5650".into(),
            Self::Gltf(p) => {
                let stem = |p: &Path| p.file_stem().map(|s| s.to_string_lossy().into_owned());
                // `sponza.glb.xz` is `sponza`, as `sponza.glb` is.
                let p = Path::new(p);
                match p.extension() {
                    Some(x) if x == "xz" => stem(&p.with_extension("")),
                    _ => stem(p),
                }
                .unwrap_or_else(|| p.display().to_string())
            }
            Self::Real(name) => name.clone(),
        }
    }

    /// Its name in cell names: the short name, and `+glass` where a procedural scene has its
    /// glass on.
    pub fn label(&self) -> String {
        let glass = match self {
            Self::Atrium(p) => p.glass,
            Self::Pillars(p) => p.glass,
            Self::Cis5650(p) => p.glass,
            _ => false,
        };
        if glass {
            format!("{}+glass", self.name())
        } else {
            self.name()
        }
    }

    /// The scene a command line names: a procedural scene's name (its default parameters) or
    /// a glTF file's path.
    pub fn from_name(name: &str) -> Self {
        match ProceduralScene::from_name(name) {
            Ok(ProceduralScene::Atrium(p)) => Self::Atrium(p),
            Ok(ProceduralScene::Pillars(p)) => Self::Pillars(p),
            Ok(ProceduralScene::Topdown(p)) => Self::Topdown(p),
            Ok(ProceduralScene::City(p)) => Self::City(p),
            Ok(ProceduralScene::Cis5650(p)) => Self::Cis5650(p),
            Err(_) if manylights_scene::real::find(name).is_some() => Self::Real(name.to_owned()),
            Err(_) => Self::Gltf(name.to_owned()),
        }
    }

    /// The procedural scene, if this is one.
    pub fn procedural(&self) -> Option<ProceduralScene> {
        Some(match self {
            Self::Atrium(p) => ProceduralScene::Atrium(*p),
            Self::Pillars(p) => ProceduralScene::Pillars(*p),
            Self::Topdown(p) => ProceduralScene::Topdown(*p),
            Self::City(p) => ProceduralScene::City(*p),
            Self::Cis5650(p) => ProceduralScene::Cis5650(*p),
            Self::Gltf(_) | Self::Real(_) => return None,
        })
    }
}

/// Partial overrides applied together: one value of the `variants` sweep axis.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    /// Name of the variant in cell names (default: built from its fields).
    #[serde(default)]
    pub label: Option<String>,
    /// Strategy override.
    #[serde(default)]
    pub strategy: Option<Strategy>,
    /// Backend override.
    #[serde(default)]
    pub backend: Option<Backend>,
    /// Capacity override.
    #[serde(default)]
    pub capacity: Option<u32>,
    /// Tile-mask budget override, bytes.
    #[serde(default)]
    pub mask_budget: Option<u64>,
    /// Box test override.
    #[serde(default)]
    pub tile_boxes: Option<bool>,
    /// Culling by visibility override.
    #[serde(default)]
    pub occlusion: Option<bool>,
    /// Light motion override.
    #[serde(default)]
    pub motion: Option<Motion>,
    /// Light update override.
    #[serde(default)]
    pub light_update: Option<LightUpdate>,
    /// MSAA sample count override.
    #[serde(default)]
    pub msaa: Option<u32>,
    /// The visibility backend's pass override (`Compute` or `Raster`).
    #[serde(default)]
    pub visibility_pass: Option<VisibilityPass>,
    /// Shadows override (`Off` or `Exact`).
    #[serde(default)]
    pub shadows: Option<Shadows>,
}

/// One value of the `settings` sweep axis: a scene, lights, camera and resolution (and how
/// finely they can be checked) that belong together, such as a paper's configuration; the
/// other axes apply after it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Setting {
    /// Its name in cell names.
    pub label: String,
    /// Scene override.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<SceneSpec>,
    /// Lights override (the radius, count and motion axes still apply after it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lights: Option<LightSpec>,
    /// Camera override.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraSpec>,
    /// Resolution override.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolution: Option<(u32, u32)>,
    /// Exact-oracle stride override.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exact_stride: Option<u32>,
    /// `cutoff_reference` override.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cutoff_reference: Option<bool>,
}

/// Lists of values for the fields of [`Config`]; the cells are their cartesian product.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Sweep {
    /// Settings (scene, lights, camera, resolution together), applied before every other axis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub settings: Option<Vec<Setting>>,
    /// Scenes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scene: Option<Vec<SceneSpec>>,
    /// Whole light sets (each a `lights` value), for light sets that differ in more than one
    /// field; the axes after it (count, seed, generator, radius, motion) override their parts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lights: Option<Vec<LightSpec>>,
    /// Light counts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_count: Option<Vec<u32>>,
    /// Light seeds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_seed: Option<Vec<u64>>,
    /// Light generators.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub generator: Option<Vec<LightGenerator>>,
    /// Radius rules.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radius: Option<Vec<RadiusRule>>,
    /// Cameras.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub camera: Option<Vec<CameraSpec>>,
    /// Resolutions.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resolution: Option<Vec<(u32, u32)>>,
    /// Strategies.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub strategy: Option<Vec<Strategy>>,
    /// Backends.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub backend: Option<Vec<Backend>>,
    /// Capacities (`None` entries mean none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub capacity: Option<Vec<Option<u32>>>,
    /// Tile-mask budgets, bytes (`None` entries mean the default).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mask_budget: Option<Vec<Option<u64>>>,
    /// The box test on and off.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tile_boxes: Option<Vec<bool>>,
    /// Light motions (`lights.motion`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion: Option<Vec<Motion>>,
    /// Ways moving lights reach the GPU.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_update: Option<Vec<LightUpdate>>,
    /// MSAA sample counts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub msaa: Option<Vec<u32>>,
    /// Lit image formats (`hdr`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hdr: Option<Vec<HdrFormat>>,
    /// Material model lists (`materials`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub materials: Option<Vec<Vec<Model>>>,
    /// Device limits (`None` entries mean none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub device_limit: Option<Vec<Option<DeviceLimit>>>,
    /// Combined overrides.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub variants: Option<Vec<Variant>>,
}

/// One resolved configuration: what one cell runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// The scene.
    pub scene: SceneSpec,
    /// The generated lights (added to the scene's own).
    #[serde(default)]
    pub lights: LightSpec,
    /// The camera.
    #[serde(default)]
    pub camera: CameraSpec,
    /// Width and height in pixels.
    #[serde(default = "resolution")]
    pub resolution: (u32, u32),
    /// The culling strategy (ignored by `NaiveForward`).
    #[serde(default = "strategy")]
    pub strategy: Strategy,
    /// The shading backend.
    #[serde(default = "backend")]
    pub backend: Backend,
    /// A deliberate cap on list lengths (dropped lights are counted).
    #[serde(default)]
    pub capacity: Option<u32>,
    /// Most bytes of tile masks (a bit per tile and light) the strategy may use: gather, 2.5D
    /// and tiled scatter use them where they fit; 0 never. Default (none): the culler's, 16 MiB.
    /// Whether a cell used them is the `tile_masks` result column.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mask_budget: Option<u64>,
    /// Whether tile tests also test each light's sphere against the view-space box of the
    /// tile's frustum (true, the default; `CullSettings::tile_boxes`). Off only for ablations.
    /// (Left out of a cell's identity when on, so that earlier results keep their cells.)
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub tile_boxes: bool,
    /// How moving lights (`lights.motion` other than `Static`) reach the GPU each frame: `Gpu`
    /// (the default), an animation pass; `Upload`, computed on the host and uploaded. Static
    /// lights are never updated. (Left out of a cell's identity when `Gpu`.)
    #[serde(default, skip_serializing_if = "LightUpdate::is_gpu")]
    pub light_update: LightUpdate,
    /// Samples a pixel: 1 (the default), or 2, 4, 8, 16 for MSAA where the device has the count
    /// for the depth buffer and the HDR target (a cell that asks for one it lacks fails with
    /// the counts it has). Forward and naive forward shade each fragment once and resolve;
    /// the culling bounds and the exact oracle cover every sample (list metrics are per
    /// covered sample); the references render at the same count. Deferred lights a
    /// multisampled G-buffer once a pixel, and each sample apart at edges;
    /// `DeferredStoredPosition` takes no MSAA. (Left out of a cell's identity when 1.)
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub msaa: u32,
    /// The lit image's format: `F32` (the default) or `F16`, a 16-bit float HDR target as
    /// engines' (`manylights_shade::HdrFormat`: half the bytes the lighting pass writes, each
    /// channel rounded to half precision; the references keep 32 bits, so accuracy carries the
    /// rounding). (Left out of a cell's identity when `F32`; `hdr=f16` in its `params`.)
    #[serde(default, skip_serializing_if = "is_f32")]
    pub hdr: HdrFormat,
    /// How the visibility backend finds each pixel's triangle: `Compute` (the default: the
    /// compute rasteriser, where it can: one sample a pixel, no glass, 64-bit atomic max; the
    /// raster pass elsewhere) or `Raster` (the raster pass, `@builtin(primitive_index)`,
    /// always). Other backends ignore it. (Left out of a cell's identity when `Compute`;
    /// `visibility_pass=raster` in its `params`.)
    #[serde(default, skip_serializing_if = "is_compute")]
    pub visibility_pass: VisibilityPass,
    /// Shadows: `Off` (the default: every light shines through walls), `Exact`, a shadow ray
    /// for every light that adds radiance at a shaded point, through the BVH of the scene's
    /// opaque triangles, built for the cell, or `Stochastic(rays: K)`, K rays a pixel to lights
    /// drawn in proportion to their unshadowed luminance, combined as the ratio estimator, its
    /// noise measured over `seeds` (`manylights_shade::Shadows`); the windowed reference is
    /// shadowed exactly, so PSNR and FLIP stay the implementation check (for `Stochastic` they
    /// carry its noise), the infinite-range reference is not (`flip_mean_infinite`), and with
    /// `accuracy` the shadowed infinite-range reference scores the image
    /// (`flip_mean_shadowed`). (Left out of a cell's identity when `Off`; `shadows=exact` or
    /// `shadows=stochastic;shadow_rays=K` in its `params`.)
    #[serde(default, skip_serializing_if = "is_off")]
    pub shadows: Shadows,
    /// With `accuracy`, whether to render the shadowed infinite-range reference (a ray from
    /// every covered pixel to every light, through the scene's BVH, built for it) and score the
    /// image against it (`flip_mean_shadowed`, `energy_error_shadowed`) where the cell casts no
    /// shadows itself: how much light leaks through walls. Cells with shadows always do.
    /// Cached in the run folder as the unshadowed one is. (Left out of a cell's identity when
    /// false.)
    #[serde(default, skip_serializing_if = "is_false")]
    pub shadowed_reference: bool,
    /// The shadowed infinite-range reference as an unbiased estimate with this many shadow
    /// rays a pixel in expectation (`manylights_shade::InfiniteReference::with_estimate`), for
    /// views where a ray for every (pixel, light) pair would take too long (a million lights
    /// at 1080p: 242 s on an H100 exact); `None` (the default): exact. The estimate is the
    /// mean of four, whose standard error is `shadowed_reference_se`. MSAA 1, opaque scenes.
    /// (Left out of a cell's identity when `None`.)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shadowed_reference_rays: Option<u32>,
    /// Culling by visibility (`CullSettings::occlusion`): after the strategy's lists, each
    /// bin's list loses the lights one of the scene's 64 largest opaque convex polygons hides
    /// from its whole cell (`manylights_cull::blocks::occlusion`); not with z-binning. The
    /// scene's BVH is built for it: its false negatives count against the shadowed exact set.
    /// (Left out of a cell's identity when false.)
    #[serde(default, skip_serializing_if = "is_false")]
    pub occlusion: bool,
    /// Material models to give the scene's surfaces, in turns (`manylights_scene::material::
    /// assign_models`): `[Ggx]` makes every surface GGX; `[BlinnPhong, Ggx, Sheen, ClearCoat,
    /// Wrap]` mixes five models in one frame, each material's parameters carried over
    /// (`Material::with_model`). Empty (the default): the scene's own materials (procedural
    /// scenes: Blinn-Phong; glTF files: GGX). Forward draws each model with its own pipeline;
    /// deferred branches on the model in one lighting pass. (Left out of a cell's identity when
    /// empty.)
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub materials: Vec<Model>,
    /// Conservative culling slack.
    #[serde(default = "slack")]
    pub slack: f32,
    /// Measured frames (GPU times are medians over them).
    #[serde(default = "frames")]
    pub frames: u32,
    /// Frames rendered before measuring.
    #[serde(default = "warmup")]
    pub warmup: u32,
    /// Whether to render the references and measure image error.
    #[serde(default = "yes")]
    pub accuracy: bool,
    /// With `accuracy`, whether to render the reference with the same radius cut-off as the
    /// method (true, the default): the implementation check (`psnr_db`, `flip_mean`,
    /// `max_abs_error`, the temporal columns). Off, only the infinite-range reference is
    /// computed, for cells with so many lights at so many pixels that the brute-force raster
    /// pass would take minutes (its columns empty). (Left out of a cell's identity when on.)
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub cutoff_reference: bool,
    /// Pixel stride of the exact per-pixel oracle (1: every pixel; larger samples a grid, for
    /// light counts where O(pixels x lights) is too slow). 0 turns list metrics off.
    #[serde(default = "one")]
    pub exact_stride: u32,
    /// Set one dimension to the device's limit when the cell runs (stability case 14).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub device_limit: Option<DeviceLimit>,
    /// Also write each cell's data at its first pose as NumPy arrays under `cells/<id>/`
    /// (`manylights_lab::export`; cells without lists, naive forward, export nothing).
    #[serde(default, skip_serializing_if = "is_false")]
    pub export: bool,
}

/// How moving lights reach the GPU each frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum LightUpdate {
    /// A compute pass moves them on the GPU (`lights.animate`; `gpu_ms_light_update`).
    #[default]
    Gpu,
    /// The host computes every moving light and uploads all of them (`cpu_ms_upload`, and the
    /// copy `lights.upload` in `gpu_ms_light_update`).
    Upload,
}

impl LightUpdate {
    fn is_gpu(&self) -> bool {
        *self == Self::Gpu
    }

    /// `gpu` or `upload`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Gpu => "gpu",
            Self::Upload => "upload",
        }
    }
}

/// A value the runner takes from the device's limits when the cell runs, so that one
/// experiment file probes the limit of whatever device it runs on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum DeviceLimit {
    /// The width: `max_texture_dimension_2d`.
    Width,
    /// The height: `max_texture_dimension_2d`.
    Height,
    /// The light count: the most lights the device holds (`manylights_cull::max_lights`:
    /// per-light buffers within one storage binding, and llvmpipe's loop limit).
    Lights,
}

impl Config {
    /// Whether the cell renders the shadowed infinite-range reference: with `accuracy`, where
    /// it casts shadows or asks for it (`shadowed_reference`).
    pub fn shadowed_truth(&self) -> bool {
        self.accuracy && (self.shadows.casts() || self.shadowed_reference)
    }

    /// Whether the exact oracle's set is shadowed (a light needed where its shadow ray is
    /// clear): where the cell culls by visibility, and where it casts shadows on a driver
    /// whose loop limit lets the oracle trace every light's ray
    /// (`manylights_cull::per_pixel::shadowed_exact_fits`; otherwise unshadowed there).
    pub fn shadowed_exact(&self) -> bool {
        self.shadows.casts() || self.occlusion
    }

    /// This configuration with its `device_limit` resolved against the device `ctx`.
    pub fn at_limits(&self, ctx: &manylights_gpu::GpuContext) -> Config {
        let limits = &ctx.limits;
        let mut c = self.clone();
        match c.device_limit {
            Some(DeviceLimit::Width) => c.resolution.0 = limits.max_texture_dimension_2d,
            Some(DeviceLimit::Height) => c.resolution.1 = limits.max_texture_dimension_2d,
            Some(DeviceLimit::Lights) => c.lights.count = manylights_cull::max_lights(ctx),
            None => {}
        }
        c
    }
}

fn resolution() -> (u32, u32) {
    (1280, 720)
}
fn strategy() -> Strategy {
    Strategy::tiled_gather(16)
}
fn backend() -> Backend {
    Backend::Forward
}
fn slack() -> f32 {
    manylights_cull::layout::DEFAULT_SLACK
}
fn frames() -> u32 {
    10
}
fn warmup() -> u32 {
    3
}
fn is_false(b: &bool) -> bool {
    !*b
}

fn is_true(b: &bool) -> bool {
    *b
}

fn yes() -> bool {
    true
}
fn is_one(n: &u32) -> bool {
    *n == 1
}

fn is_f32(h: &HdrFormat) -> bool {
    *h == HdrFormat::F32
}

fn is_off(s: &Shadows) -> bool {
    *s == Shadows::Off
}

fn is_compute(p: &VisibilityPass) -> bool {
    *p == VisibilityPass::Compute
}

fn one() -> u32 {
    1
}

/// An experiment file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Experiment {
    /// Name (the `experiment` column).
    pub name: String,
    /// What it measures, for the report.
    #[serde(default)]
    pub description: String,
    /// The base configuration.
    pub config: Config,
    /// Swept fields.
    #[serde(default)]
    pub sweep: Sweep,
}

impl Config {
    /// Checks values that the types do not; errors name the field.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        for (i, m) in self.materials.iter().enumerate() {
            if self.materials[..i].contains(m) {
                return Err((
                    "materials",
                    format!(
                        "materials lists {m:?} twice: each of BlinnPhong, Ggx, Sheen, ClearCoat, \
                         Wrap at most once"
                    ),
                ));
            }
        }
        let (w, h) = self.resolution;
        if !(1..=65536).contains(&w) || !(1..=65536).contains(&h) {
            return Err((
                "resolution",
                format!("resolution ({w}, {h}): width and height in 1..=65536"),
            ));
        }
        if self.frames == 0 {
            return Err(("frames", "frames = 0: at least one measured frame".into()));
        }
        if let SceneSpec::Real(name) = &self.scene
            && manylights_scene::real::find(name).is_none()
        {
            return Err((
                "scene",
                format!(
                    "scene Real(\"{name}\"): no such real scene; accepted: {}",
                    manylights_scene::real::names()
                ),
            ));
        }
        if ![1, 2, 4, 8, 16].contains(&self.msaa) {
            return Err((
                "msaa",
                format!(
                    "msaa = {}: 1, 2, 4, 8 or 16 samples a pixel (where the device has them)",
                    self.msaa
                ),
            ));
        }
        if self.export && self.scene.label().ends_with("+glass") {
            return Err((
                "export",
                format!(
                    "export: true with scene {}: exports hold one depth a pixel, not glass \
                     (leave glass: false to export)",
                    self.scene.label()
                ),
            ));
        }
        if let Some(rays) = self.shadowed_reference_rays {
            if rays == 0 {
                return Err((
                    "shadowed_reference_rays",
                    "shadowed_reference_rays = Some(0): the estimate casts at least one ray a \
                     pixel (None: the exact reference)"
                        .into(),
                ));
            }
            if self.msaa > 1 || self.scene.label().ends_with("+glass") {
                return Err((
                    "shadowed_reference_rays",
                    format!(
                        "shadowed_reference_rays = Some({rays}) with msaa = {} and scene {}: the \
                         estimate shades one opaque surface a pixel (msaa: 1, no glass; or None)",
                        self.msaa,
                        self.scene.label()
                    ),
                ));
            }
        }
        if self.occlusion && matches!(self.strategy, Strategy::ZBin { .. }) {
            return Err((
                "occlusion",
                "occlusion = true with strategy ZBin: culling by visibility drops lights from \
                 lists of a list a bin (TiledGather, DepthMask, TiledScatter or Clustered), \
                 not from z-binning's"
                    .into(),
            ));
        }
        if self.msaa > 1 && self.export {
            return Err((
                "msaa",
                format!(
                    "msaa = {} with export: exports hold one depth a pixel (msaa: 1 to export)",
                    self.msaa
                ),
            ));
        }
        if self.msaa > 1 && self.backend == Backend::DeferredStoredPosition {
            return Err((
                "msaa",
                format!(
                    "msaa = {} with backend deferred_stored_position: the stored position takes \
                     no MSAA (Forward, Deferred or NaiveForward, or msaa: 1)",
                    self.msaa
                ),
            ));
        }
        self.lights
            .validate()
            .map_err(|e| ("lights", e.to_string()))?;
        self.shadows.validate().map_err(|e| ("shadows", e))?;
        self.strategy
            .validate()
            .map_err(|e| ("strategy", e.to_string()))?;
        let settings = CullSettings {
            near: 0.1,
            far: 1.0,
            slack: self.slack,
            capacity: self.capacity,
            mask_budget: self.mask_budget,
            tile_boxes: self.tile_boxes,
            occlusion: self.occlusion,
        };
        settings.validate().map_err(|e| ("slack", e.to_string()))?;
        match &self.camera {
            CameraSpec::Default => {}
            CameraSpec::Pose(p) => p
                .camera()
                .validate()
                .map_err(|e| ("camera", e.to_string()))?,
            CameraSpec::Path(ps) => {
                if ps.is_empty() {
                    return Err((
                        "camera",
                        "camera Path([]): a path needs at least one pose".into(),
                    ));
                }
                for p in ps {
                    p.camera()
                        .validate()
                        .map_err(|e| ("camera", e.to_string()))?;
                }
            }
            CameraSpec::Walkthrough(w) => w.validate().map_err(|e| ("camera", e))?,
        }
        Ok(())
    }
}
