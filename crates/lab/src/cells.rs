//! An experiment's expansion into cells: parsing with errors at the file, line and column,
//! checks of every cell's configuration, the cartesian product of the sweep's axes (in the order
//! of `Sweep`'s fields, `variants` last), each cell's readable name and stable identifier, and
//! the labels of its parameters (the `params` column).

use std::path::Path;

use manylights_cull::Strategy;
use manylights_scene::stochastic::{StochasticBound, StochasticDraw};
use manylights_scene::{LightGenerator, LightSpec, Model, Motion, RadiusRule};
use manylights_shade::Backend;
use serde::Serialize;

use crate::LabError;
use crate::experiment::{
    CameraSpec, Config, DeviceLimit, Experiment, LightUpdate, SceneSpec, Setting, Variant,
};

/// One cell: a name and a configuration.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Cell {
    /// Position in the sweep order.
    pub index: usize,
    /// Readable name from the swept values (`base` without a sweep): its parameters as
    /// `name=value` parts joined by commas.
    pub name: String,
    /// The swept values: each axis's name (`setting`, `scene`, `lights`, `threshold`, ...,
    /// `variant`) and the value's, in sweep order.
    pub parameters: Vec<(String, String)>,
    /// The configuration.
    pub config: Config,
}

impl Cell {
    /// A stable identifier of the configuration (FNV-1a of its JSON), the cell's file name.
    pub fn id(&self) -> String {
        use std::hash::Hasher as _;
        let json = serde_json::to_string(&self.config).expect("configs serialise");
        let mut h = crate::reference_cache::Fnv::default();
        h.write(json.as_bytes());
        format!("{:016x}", h.finish())
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

/// Material models as a label: their names joined by `+` (`scene` for none: the scene's own).
pub fn models_label(models: &[Model]) -> String {
    if models.is_empty() {
        return "scene".into();
    }
    models
        .iter()
        .map(|m| m.name())
        .collect::<Vec<_>>()
        .join("+")
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
            cells,
        } => format!(
            "clustered{tile_size}x{slices}{}{}{}{}",
            slicing_label(slicing),
            if skip_empty { "skip" } else { "" },
            if ordered { "" } else { "unordered" },
            if cells { "cells" } else { "" }
        ),
        Strategy::ZBin {
            tile_size,
            bins,
            slicing,
        } => format!("zbin{tile_size}x{bins}{}", slicing_label(slicing)),
    }
}

fn slicing_label(s: manylights_cull::Slicing) -> &'static str {
    match s {
        manylights_cull::Slicing::Linear => "lin",
        manylights_cull::Slicing::Exponential => "exp",
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
            cells,
        } => {
            // `ordered` is the default: named only when off, and `cells` only when on, so that
            // labels stay as they were.
            let unordered = if ordered { "" } else { ";ordered=false" };
            let cells = if cells { ";cells=true" } else { "" };
            format!(
                "tile_size={tile_size};slices={slices};slicing={slicing:?};skip_empty={skip_empty}{unordered}{cells}"
            )
            .to_lowercase()
        }
        Strategy::ZBin {
            tile_size,
            bins,
            slicing,
        } => format!("tile_size={tile_size};bins={bins};slicing={slicing:?}").to_lowercase(),
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
    if !c.tile_boxes {
        p.push_str(";tile_boxes=false");
    }
    if c.occlusion {
        p.push_str(";occlusion=true");
    }
    if c.msaa > 1 {
        p.push_str(&format!(";msaa={}", c.msaa));
    }
    if c.hdr != manylights_shade::HdrFormat::F32 {
        p.push_str(&format!(";hdr={}", c.hdr.name()));
    }
    if c.visibility_pass != manylights_shade::VisibilityPass::Compute {
        p.push_str(&format!(";visibility_pass={}", c.visibility_pass.name()));
    }
    if c.shadows.casts() {
        p.push_str(&format!(";shadows={}", c.shadows.name()));
    }
    if let manylights_shade::Shadows::Stochastic {
        rays,
        accumulate,
        seeds,
    } = c.shadows
    {
        p.push_str(&format!(";shadow_rays={rays}"));
        if accumulate > 1 {
            p.push_str(&format!(";shadow_accumulate={accumulate}"));
        }
        if seeds != 4 {
            p.push_str(&format!(";shadow_seeds={seeds}"));
        }
    }
    if !c.materials.is_empty() {
        p.push_str(&format!(";materials={}", models_label(&c.materials)));
    }
    if !c.lights.motion.is_static() {
        p.push_str(&format!(
            ";motion={};light_update={}",
            c.lights.motion.label(),
            c.light_update.name()
        ));
        if c.lights.moving < 1.0 {
            p.push_str(&format!(";moving={}", c.lights.moving));
        }
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
            ("lights", s.lights.as_ref().map(Vec::len)),
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
            ("tile_boxes", s.tile_boxes.as_ref().map(Vec::len)),
            ("motion", s.motion.as_ref().map(Vec::len)),
            ("light_update", s.light_update.as_ref().map(Vec::len)),
            ("msaa", s.msaa.as_ref().map(Vec::len)),
            ("hdr", s.hdr.as_ref().map(Vec::len)),
            ("materials", s.materials.as_ref().map(Vec::len)),
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
        axis!(s.settings, apply_setting);
        axis!(s.scene, |c: &mut Config, v: SceneSpec| {
            c.scene = v;
            ("scene", c.scene.label())
        });
        axis!(s.lights, |c: &mut Config, v: LightSpec| {
            c.lights = v;
            // One name part (no comma), so that a figure's series drops it with the count.
            (
                "lights",
                format!("{}({})", v.count, radius_label(&v.radius)),
            )
        });
        axis!(s.light_count, |c: &mut Config, v: u32| {
            c.lights.count = v;
            ("lights", v.to_string())
        });
        axis!(s.light_seed, |c: &mut Config, v: u64| {
            c.lights.seed = v;
            ("seed", v.to_string())
        });
        axis!(s.generator, |c: &mut Config, v: LightGenerator| {
            c.lights.generator = v;
            ("generator", format!("{v:?}"))
        });
        axis!(s.radius, |c: &mut Config, v: RadiusRule| {
            c.lights.radius = v;
            radius_parameter(&v)
        });
        axis!(s.camera, |c: &mut Config, v: CameraSpec| {
            let label = match &v {
                CameraSpec::Default => "default".to_string(),
                CameraSpec::Pose(p) => format!("pose({:?})", p.position),
                CameraSpec::Path(p) => format!("path{}", p.len()),
                CameraSpec::Walkthrough(w) => format!("walk{}", w.poses),
            };
            c.camera = v;
            ("camera", label)
        });
        axis!(s.resolution, |c: &mut Config, v: (u32, u32)| {
            c.resolution = v;
            ("res", format!("{}x{}", v.0, v.1))
        });
        axis!(s.strategy, |c: &mut Config, v: Strategy| {
            c.strategy = v;
            ("strategy", strategy_label(&v))
        });
        axis!(s.backend, |c: &mut Config, v: Backend| {
            c.backend = v;
            ("backend", v.name().to_string())
        });
        axis!(s.capacity, |c: &mut Config, v: Option<u32>| {
            c.capacity = v;
            ("capacity", v.map_or("none".into(), |x| x.to_string()))
        });
        axis!(s.mask_budget, |c: &mut Config, v: Option<u64>| {
            c.mask_budget = v;
            ("mask_budget", v.map_or("default".into(), |x| x.to_string()))
        });
        axis!(s.tile_boxes, |c: &mut Config, v: bool| {
            c.tile_boxes = v;
            ("tile_boxes", v.to_string())
        });
        axis!(s.motion, |c: &mut Config, v: Motion| {
            c.lights.motion = v;
            ("motion", v.label())
        });
        axis!(s.light_update, |c: &mut Config, v: LightUpdate| {
            c.light_update = v;
            ("light_update", v.name().to_string())
        });
        axis!(s.msaa, |c: &mut Config, v: u32| {
            c.msaa = v;
            ("msaa", v.to_string())
        });
        axis!(s.hdr, |c: &mut Config, v: manylights_shade::HdrFormat| {
            c.hdr = v;
            ("hdr", v.name().to_string())
        });
        axis!(s.materials, |c: &mut Config, v: Vec<Model>| {
            let label = models_label(&v);
            c.materials = v;
            ("materials", label)
        });
        axis!(s.device_limit, |c: &mut Config, v: Option<DeviceLimit>| {
            c.device_limit = v;
            (
                "limit",
                v.map_or("none".into(), |x| format!("{x:?}").to_lowercase()),
            )
        });
        axis!(s.variants, apply_variant);
        product(&self.config, &axes)
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
        if let Some(l) = &mut e.sweep.lights {
            for v in l.iter_mut() {
                v.count = v.count.min(256);
            }
        }
        if let Some(settings) = &mut e.sweep.settings {
            for v in settings.iter_mut() {
                if let Some(l) = &mut v.lights {
                    l.count = l.count.min(256);
                }
                if let Some(r) = &mut v.resolution {
                    *r = shrink(*r);
                }
            }
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

/// The names of the parameter [`radius_parameter`] makes, one a rule: a cell whose parameters
/// hold one sweeps its light range.
pub const RADIUS_AXES: [&str; 4] = ["threshold", "stochastic", "radius", "hierarchy"];

/// A radius rule in cell names, one name part (no comma): `radius=R`, `threshold=T`,
/// `hierarchy=A/hH` (alpha A, spacing H; then `/nR` where the finest grid may hold R nodes a
/// point light, not the default 2, `/gK` with bands growing K, `/cC` with ramps of C, and `/sL`
/// with bands sampled from level L), or
/// `stochastic=E` with `/albedo` under the albedo bound, `/independent` for independent draws, `/accK` where K frames accumulate, `/ilN` with N x N interleaved pixel
/// classes and `/exposureX` where the exposure is not 1.
pub fn radius_label(rule: &RadiusRule) -> String {
    let (name, value) = radius_parameter(rule);
    format!("{name}={value}")
}

/// A radius rule as a sweep's parameter: the axis name (`radius`, `threshold`, `hierarchy`,
/// `stochastic`) and the value [`radius_label`] writes after it.
pub fn radius_parameter(rule: &RadiusRule) -> (&'static str, String) {
    match *rule {
        RadiusRule::Fixed(r) => ("radius", r.to_string()),
        RadiusRule::Threshold(t) => ("threshold", t.to_string()),
        RadiusRule::Hierarchy {
            alpha,
            spacing,
            finest_nodes,
            growth,
            ramp,
            sample_from,
            spot_bins,
        } => {
            let mut s = format!("{alpha}/h{spacing}");
            if f64::from(finest_nodes) != manylights_scene::hierarchy::FINEST_NODES {
                s += &format!("/n{finest_nodes}");
            }
            if f64::from(growth) != manylights_scene::hierarchy::GROWTH {
                s += &format!("/g{growth}");
            }
            if f64::from(ramp) != manylights_scene::hierarchy::RAMP {
                s += &format!("/c{ramp}");
            }
            if let Some(l) = sample_from {
                s += &format!("/s{l}");
            }
            if spot_bins != manylights_scene::hierarchy::SPOT_BINS {
                s += &format!("/b{spot_bins}");
            }
            ("hierarchy", s)
        }
        RadiusRule::Stochastic {
            error,
            bound,
            exposure,
            accumulate,
            interleave,
            draw,
            ..
        } => {
            let mut s = error.to_string();
            if bound != StochasticBound::Light {
                s += &format!("/{}", bound.name());
            }
            if draw != StochasticDraw::Stratified {
                s += &format!("/{}", draw.name());
            }
            if accumulate > 1 {
                s += &format!("/acc{accumulate}");
            }
            if interleave > 1 {
                s += &format!("/il{interleave}");
            }
            if exposure != 1.0 {
                s += &format!("/exposure{exposure}");
            }
            ("stochastic", s)
        }
    }
}

/// One value of a sweep axis: applies it to a configuration and returns its parameter, the
/// axis's name and the value's (the cell's name part `name=value`).
type Apply = Box<dyn Fn(&mut Config) -> (&'static str, String)>;

/// A setting of the sweep applied to `c`: what it sets, and its parameter.
fn apply_setting(c: &mut Config, v: Setting) -> (&'static str, String) {
    if let Some(scene) = v.scene {
        c.scene = scene;
    }
    if let Some(lights) = v.lights {
        c.lights = lights;
    }
    if let Some(camera) = v.camera {
        c.camera = camera;
    }
    if let Some(r) = v.resolution {
        c.resolution = r;
    }
    if let Some(s) = v.exact_stride {
        c.exact_stride = s;
    }
    if let Some(b) = v.cutoff_reference {
        c.cutoff_reference = b;
    }
    ("setting", v.label)
}

/// A variant of the sweep applied to `c`: what it sets, and its parameter (its label, or
/// backend+strategy).
fn apply_variant(c: &mut Config, v: Variant) -> (&'static str, String) {
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
    if let Some(b) = v.tile_boxes {
        c.tile_boxes = b;
    }
    if let Some(b) = v.occlusion {
        c.occlusion = b;
    }
    if let Some(m) = v.motion {
        c.lights.motion = m;
    }
    if let Some(u) = v.light_update {
        c.light_update = u;
    }
    if let Some(n) = v.msaa {
        c.msaa = n;
    }
    if let Some(pass) = v.visibility_pass {
        c.visibility_pass = pass;
    }
    if let Some(s) = v.shadows {
        c.shadows = s;
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
    ("variant", v.label.unwrap_or(auto))
}

/// Every combination of the axes' values over `base`, in sweep order (the last axis fastest),
/// each named by its values' name parts.
fn product(base: &Config, axes: &[Vec<Apply>]) -> Vec<Cell> {
    let mut cells = vec![(base.clone(), Vec::<(&'static str, String)>::new())];
    for axis in axes {
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
        .map(|(index, (config, parameters))| Cell {
            index,
            name: if parameters.is_empty() {
                "base".into()
            } else {
                parameters
                    .iter()
                    .map(|(k, v)| format!("{k}={v}"))
                    .collect::<Vec<_>>()
                    .join(",")
            },
            parameters: parameters
                .into_iter()
                .map(|(k, v)| (k.to_owned(), v))
                .collect(),
            config,
        })
        .collect()
}
