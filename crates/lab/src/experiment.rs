//! The experiment schema (RON, through serde) and its expansion into cells.
//!
//! An experiment fixes one configuration and, in `sweep`, lists of values for any of its fields;
//! the cells are the cartesian product of those lists (in the order of [`Sweep`]'s fields), each
//! with a readable name built from its swept values. `sweep.variants` is one more axis whose
//! values change several fields together (a backend with its strategy, say), for comparisons that
//! are not a product. Unknown fields and bad values are errors with the file, line and column.

use std::path::Path;

use manylights_cull::{CullSettings, Strategy};
use manylights_scene::procedural::{
    AtriumParams, CityParams, PillarsParams, ProceduralScene, TopdownParams,
};
use manylights_scene::{Camera, LightGenerator, LightSpec, Projection, RadiusRule};
use manylights_shade::Backend;
use serde::{Deserialize, Serialize};

use crate::LabError;

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
    /// A glTF file (relative paths are relative to the experiment file).
    Gltf(String),
}

impl SceneSpec {
    /// Short name for results.
    pub fn name(&self) -> String {
        match self {
            Self::Atrium(_) => "atrium".into(),
            Self::Pillars(_) => "pillars".into(),
            Self::Topdown(_) => "topdown".into(),
            Self::City(_) => "city".into(),
            Self::Gltf(p) => Path::new(p)
                .file_stem()
                .map_or_else(|| p.clone(), |s| s.to_string_lossy().into_owned()),
        }
    }

    /// The procedural scene, if this is one.
    pub fn procedural(&self) -> Option<ProceduralScene> {
        Some(match self {
            Self::Atrium(p) => ProceduralScene::Atrium(*p),
            Self::Pillars(p) => ProceduralScene::Pillars(*p),
            Self::Topdown(p) => ProceduralScene::Topdown(*p),
            Self::City(p) => ProceduralScene::City(*p),
            Self::Gltf(_) => return None,
        })
    }
}

/// A camera pose.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pose {
    /// Eye position.
    pub position: (f32, f32, f32),
    /// Point looked at.
    pub target: (f32, f32, f32),
    /// Up direction.
    #[serde(default = "up")]
    pub up: (f32, f32, f32),
    /// Vertical field of view in degrees (perspective).
    #[serde(default = "fov")]
    pub fov_y_deg: f32,
    /// Near plane distance.
    #[serde(default = "near")]
    pub near: f32,
    /// Far plane distance.
    #[serde(default = "far")]
    pub far: f32,
    /// With a value, an orthographic camera of this view height instead of a perspective one.
    #[serde(default)]
    pub orthographic_height: Option<f32>,
}

fn up() -> (f32, f32, f32) {
    (0.0, 1.0, 0.0)
}
fn fov() -> f32 {
    60.0
}
fn near() -> f32 {
    0.1
}
fn far() -> f32 {
    200.0
}

impl Pose {
    /// The camera.
    pub fn camera(&self) -> Camera {
        let v = |t: (f32, f32, f32)| glam::Vec3::new(t.0, t.1, t.2);
        let projection = match self.orthographic_height {
            Some(height) => Projection::Orthographic {
                height,
                near: self.near,
                far: self.far,
            },
            None => Projection::Perspective {
                fov_y_deg: self.fov_y_deg,
                near: self.near,
                far: self.far,
            },
        };
        Camera {
            position: v(self.position),
            target: v(self.target),
            up: v(self.up),
            projection,
        }
    }
}

/// The camera of an experiment.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum CameraSpec {
    /// The scene's own default camera.
    #[default]
    Default,
    /// One pose.
    Pose(Pose),
    /// A short path: measured frame k uses pose k modulo the path's length (accuracy and
    /// metrics use the first pose).
    Path(Vec<Pose>),
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
}

/// Lists of values for the fields of [`Config`]; the cells are their cartesian product.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Sweep {
    /// Scenes.
    pub scene: Option<Vec<SceneSpec>>,
    /// Light counts.
    pub light_count: Option<Vec<u32>>,
    /// Light seeds.
    pub light_seed: Option<Vec<u64>>,
    /// Light generators.
    pub generator: Option<Vec<LightGenerator>>,
    /// Radius rules.
    pub radius: Option<Vec<RadiusRule>>,
    /// Cameras.
    pub camera: Option<Vec<CameraSpec>>,
    /// Resolutions.
    pub resolution: Option<Vec<(u32, u32)>>,
    /// Strategies.
    pub strategy: Option<Vec<Strategy>>,
    /// Backends.
    pub backend: Option<Vec<Backend>>,
    /// Capacities (`None` entries mean none).
    pub capacity: Option<Vec<Option<u32>>>,
    /// Tile-mask budgets, bytes (`None` entries mean the default).
    pub mask_budget: Option<Vec<Option<u64>>>,
    /// Device limits (`None` entries mean none).
    pub device_limit: Option<Vec<Option<DeviceLimit>>>,
    /// Combined overrides.
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
    /// Pixel stride of the exact per-pixel oracle (1: every pixel; larger samples a grid, for
    /// light counts where O(pixels x lights) is too slow). 0 turns list metrics off.
    #[serde(default = "one")]
    pub exact_stride: u32,
    /// Set one dimension to the device's limit when the cell runs (stability case 14).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub device_limit: Option<DeviceLimit>,
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
fn yes() -> bool {
    true
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

/// One cell: a name and a configuration.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Cell {
    /// Position in the sweep order.
    pub index: usize,
    /// Readable name from the swept values (`base` without a sweep).
    pub name: String,
    /// The configuration.
    pub config: Config,
}

impl Cell {
    /// A stable identifier of the configuration (FNV-1a of its JSON), the cell's file name.
    pub fn id(&self) -> String {
        let json = serde_json::to_string(&self.config).expect("configs serialise");
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in json.bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x100_0000_01b3);
        }
        format!("{h:016x}")
    }
}

/// Line and column (1-based) of the first occurrence of `needle` at or after `from` in `src`.
fn locate(src: &str, needle: &str, from: usize) -> (usize, usize) {
    let at = src[from.min(src.len())..]
        .find(needle)
        .map_or(0, |i| i + from);
    let line = src[..at].matches('\n').count() + 1;
    let col = at - src[..at].rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, col)
}

fn strategy_label(s: &Strategy) -> String {
    match *s {
        Strategy::TiledScatter { tile_size } => format!("{}{tile_size}", s.name()),
        // The default coarse level is not named, so that labels stay as they were.
        Strategy::TiledGather { tile_size, coarse } | Strategy::DepthMask { tile_size, coarse } => {
            if coarse == manylights_cull::DEFAULT_COARSE {
                format!("{}{tile_size}", s.name())
            } else {
                format!("{}{tile_size}coarse{coarse}", s.name())
            }
        }
        Strategy::Clustered {
            tile_size,
            slices,
            slicing,
            skip_empty,
            ordered,
        } => format!(
            "clustered{tile_size}x{slices}{}{}{}",
            match slicing {
                manylights_cull::Slicing::Linear => "lin",
                manylights_cull::Slicing::Exponential => "exp",
            },
            if skip_empty { "skip" } else { "" },
            if ordered { "" } else { "unordered" }
        ),
    }
}

/// The strategy's parameters as `key=value` pairs (the `params` column).
pub fn params_label(c: &Config) -> String {
    let mut p = match c.strategy {
        Strategy::TiledScatter { tile_size } => format!("tile_size={tile_size}"),
        Strategy::TiledGather { tile_size, coarse } | Strategy::DepthMask { tile_size, coarse } => {
            if coarse == manylights_cull::DEFAULT_COARSE {
                format!("tile_size={tile_size}")
            } else {
                format!("tile_size={tile_size};coarse={coarse}")
            }
        }
        Strategy::Clustered {
            tile_size,
            slices,
            slicing,
            skip_empty,
            ordered,
        } => {
            // `ordered` is the default: named only when off, so that labels stay as they were.
            let unordered = if ordered { "" } else { ";ordered=false" };
            format!(
                "tile_size={tile_size};slices={slices};slicing={slicing:?};skip_empty={skip_empty}{unordered}"
            )
            .to_lowercase()
        }
    };
    if c.backend == Backend::NaiveForward {
        p = "none".into();
    }
    if let Some(cap) = c.capacity {
        p.push_str(&format!(";capacity={cap}"));
    }
    if let Some(b) = c.mask_budget {
        p.push_str(&format!(";mask_budget={b}"));
    }
    p
}

impl Experiment {
    /// Parses an experiment; errors name the file, line and column.
    pub fn parse(src: &str, file: &Path) -> Result<Self, LabError> {
        // `Atrium(bays: 7)` for newtype variants and `capacity: 4` for options read better.
        let options = ron::Options::default().with_default_extension(
            ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES
                | ron::extensions::Extensions::IMPLICIT_SOME,
        );
        let exp: Experiment = options.from_str(src).map_err(|e| LabError::Parse {
            file: file.display().to_string(),
            line: e.span.start.line,
            col: e.span.start.col,
            message: e.code.to_string(),
        })?;
        exp.validate(src, file)?;
        Ok(exp)
    }

    /// Reads and parses an experiment file.
    pub fn load(path: &Path) -> Result<(Self, String), LabError> {
        let src = std::fs::read_to_string(path).map_err(|e| LabError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        Ok((Self::parse(&src, path)?, src))
    }

    fn validate(&self, src: &str, file: &Path) -> Result<(), LabError> {
        // Validation errors point at the field (`name:`), inside `sweep:` for swept fields.
        let bad = |field: &str, message: String| {
            let sweep_at = src.find("sweep:").unwrap_or(0);
            let from = if message.starts_with("sweep") {
                sweep_at
            } else {
                src.find("config:").unwrap_or(0)
            };
            let (line, col) = locate(src, &format!("{field}:"), from);
            LabError::Parse {
                file: file.display().to_string(),
                line,
                col,
                message,
            }
        };
        if self.name.trim().is_empty() || self.name.contains(['/', '\\', ',']) {
            return Err(bad(
                "name",
                format!(
                    "name `{}`: a non-empty name without '/', '\\\\' or ','",
                    self.name
                ),
            ));
        }
        let s = &self.sweep;
        let lens = [
            ("scene", s.scene.as_ref().map(Vec::len)),
            ("light_count", s.light_count.as_ref().map(Vec::len)),
            ("light_seed", s.light_seed.as_ref().map(Vec::len)),
            ("generator", s.generator.as_ref().map(Vec::len)),
            ("radius", s.radius.as_ref().map(Vec::len)),
            ("camera", s.camera.as_ref().map(Vec::len)),
            ("resolution", s.resolution.as_ref().map(Vec::len)),
            ("strategy", s.strategy.as_ref().map(Vec::len)),
            ("backend", s.backend.as_ref().map(Vec::len)),
            ("capacity", s.capacity.as_ref().map(Vec::len)),
            ("mask_budget", s.mask_budget.as_ref().map(Vec::len)),
            ("variants", s.variants.as_ref().map(Vec::len)),
        ];
        for (field, len) in lens {
            if len == Some(0) {
                return Err(bad(
                    field,
                    format!(
                        "sweep.{field} is empty: a swept field needs at least one value (or leave it out)"
                    ),
                ));
            }
        }
        for cell in self.cells() {
            cell.config.check().map_err(|(field, message)| {
                bad(field, format!("cell `{}`: {message}", cell.name))
            })?;
        }
        Ok(())
    }

    /// The cells, in sweep order.
    pub fn cells(&self) -> Vec<Cell> {
        type Apply = Box<dyn Fn(&mut Config) -> String>;
        let s = &self.sweep;
        let mut axes: Vec<Vec<Apply>> = Vec::new();
        macro_rules! axis {
            ($field:expr, $apply:expr) => {
                if let Some(values) = &$field {
                    axes.push(
                        values
                            .iter()
                            .cloned()
                            .map(|v| Box::new(move |c: &mut Config| $apply(c, v.clone())) as Apply)
                            .collect(),
                    );
                }
            };
        }
        axis!(s.scene, |c: &mut Config, v: SceneSpec| {
            c.scene = v;
            format!("scene={}", c.scene.name())
        });
        axis!(s.light_count, |c: &mut Config, v: u32| {
            c.lights.count = v;
            format!("lights={v}")
        });
        axis!(s.light_seed, |c: &mut Config, v: u64| {
            c.lights.seed = v;
            format!("seed={v}")
        });
        axis!(s.generator, |c: &mut Config, v: LightGenerator| {
            c.lights.generator = v;
            format!("generator={v:?}")
        });
        axis!(s.radius, |c: &mut Config, v: RadiusRule| {
            c.lights.radius = v;
            match v {
                RadiusRule::Fixed(r) => format!("radius={r}"),
                RadiusRule::Threshold(t) => format!("threshold={t}"),
            }
        });
        let mut cam_i = 0usize;
        let _ = &mut cam_i;
        axis!(s.camera, |c: &mut Config, v: CameraSpec| {
            let label = match &v {
                CameraSpec::Default => "default".to_string(),
                CameraSpec::Pose(p) => format!("pose({:?})", p.position),
                CameraSpec::Path(p) => format!("path{}", p.len()),
            };
            c.camera = v;
            format!("camera={label}")
        });
        axis!(s.resolution, |c: &mut Config, v: (u32, u32)| {
            c.resolution = v;
            format!("res={}x{}", v.0, v.1)
        });
        axis!(s.strategy, |c: &mut Config, v: Strategy| {
            c.strategy = v;
            format!("strategy={}", strategy_label(&v))
        });
        axis!(s.backend, |c: &mut Config, v: Backend| {
            c.backend = v;
            format!("backend={}", v.name())
        });
        axis!(s.capacity, |c: &mut Config, v: Option<u32>| {
            c.capacity = v;
            format!("capacity={}", v.map_or("none".into(), |x| x.to_string()))
        });
        axis!(s.mask_budget, |c: &mut Config, v: Option<u64>| {
            c.mask_budget = v;
            format!(
                "mask_budget={}",
                v.map_or("default".into(), |x| x.to_string())
            )
        });
        axis!(s.device_limit, |c: &mut Config, v: Option<DeviceLimit>| {
            c.device_limit = v;
            format!(
                "limit={}",
                v.map_or("none".into(), |x| format!("{x:?}").to_lowercase())
            )
        });
        axis!(s.variants, |c: &mut Config, v: Variant| {
            if let Some(st) = v.strategy {
                c.strategy = st;
            }
            if let Some(b) = v.backend {
                c.backend = b;
            }
            if v.capacity.is_some() {
                c.capacity = v.capacity;
            }
            if v.mask_budget.is_some() {
                c.mask_budget = v.mask_budget;
            }
            let auto = format!(
                "{}+{}",
                c.backend.name(),
                if c.backend == Backend::NaiveForward {
                    "none".into()
                } else {
                    strategy_label(&c.strategy)
                }
            );
            format!("variant={}", v.label.unwrap_or(auto))
        });
        let mut cells = vec![(self.config.clone(), Vec::<String>::new())];
        for axis in &axes {
            let mut next = Vec::with_capacity(cells.len() * axis.len());
            for (cfg, names) in &cells {
                for apply in axis {
                    let mut c = cfg.clone();
                    let label = apply(&mut c);
                    let mut n = names.clone();
                    n.push(label);
                    next.push((c, n));
                }
            }
            cells = next;
        }
        cells
            .into_iter()
            .enumerate()
            .map(|(index, (config, names))| Cell {
                index,
                name: if names.is_empty() {
                    "base".into()
                } else {
                    names.join(",")
                },
                config,
            })
            .collect()
    }

    /// A tiny variant for tests: at most 48 x 27 pixels, one frame, no warm-up, at most 256
    /// lights, light counts deduplicated.
    pub fn tiny(&self) -> Self {
        let mut e = self.clone();
        let shrink = |(w, h): (u32, u32)| {
            let s = (48.0 / w as f32).min(27.0 / h as f32).min(1.0);
            (
                ((w as f32 * s).round() as u32).max(1),
                ((h as f32 * s).round() as u32).max(1),
            )
        };
        e.config.resolution = shrink(e.config.resolution);
        e.config.frames = 1;
        e.config.warmup = 0;
        e.config.lights.count = e.config.lights.count.min(256);
        if let Some(r) = &mut e.sweep.resolution {
            for v in r.iter_mut() {
                *v = shrink(*v);
            }
            r.dedup();
        }
        if let Some(l) = &mut e.sweep.light_count {
            for v in l.iter_mut() {
                *v = (*v).min(256);
            }
            l.dedup();
        }
        e
    }
}

impl Config {
    /// Checks values that the types do not; errors name the field.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
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
        self.lights
            .validate()
            .map_err(|e| ("lights", e.to_string()))?;
        self.strategy
            .validate()
            .map_err(|e| ("strategy", e.to_string()))?;
        let settings = CullSettings {
            near: 0.1,
            far: 1.0,
            slack: self.slack,
            capacity: self.capacity,
            mask_budget: self.mask_budget,
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
        }
        Ok(())
    }
}
