//! A cell's result row from what its poses and frames measured (`cell_row`): the timed frames'
//! medians by category (`Timings`), the worst pose's metrics (`Worst`), and the columns derived
//! from them.

use std::collections::BTreeSet;

use manylights_gpu::GpuContext;
use manylights_gpu::timing::{Category, PassKind, PassTiming};
use manylights_scene::{RadiusRule, Scene};
use manylights_shade::Backend;

use crate::evaluate::{PoseEval, temporal_stability};
use crate::experiment::{Cell, Config, Experiment, params_label};
use crate::noise::{Draws, Noise};
use crate::results::{Row, ShadowColumns, SweepColumns, percentiles};
use crate::runner::now;
use crate::steady::{PassMedian, SteadyCull};

/// The material models of the scene's surfaces, by id, their names joined by `+`.
fn frame_models(scene: &Scene) -> String {
    let models: std::collections::BTreeSet<manylights_scene::Model> = scene
        .primitives
        .iter()
        .map(|p| scene.materials[p.material as usize].brdf.model())
        .collect();
    crate::cells::models_label(&models.into_iter().collect::<Vec<_>>())
}

/// The shading passes' steady-state time (those of [`Category::Shade`]) per light evaluated,
/// ns; none where they were not timed apart or nothing was evaluated.
fn ns_per_light_eval(passes: &[PassMedian], evaluated: f64) -> Option<f64> {
    let ms: f64 = passes
        .iter()
        .filter(|p| p.category == Category::Shade)
        .map(|p| p.ms)
        .sum();
    (ms > 0.0 && evaluated > 0.0).then(|| ms * 1e6 / evaluated)
}

/// What a cell's row is made of: its configuration, its scene, what each pose measured and the
/// timed frames.
pub(crate) struct RowParts<'a> {
    pub(crate) exp: &'a Experiment,
    pub(crate) cell: &'a Cell,
    pub(crate) c: &'a Config,
    pub(crate) ctx: &'a GpuContext,
    pub(crate) commit: &'a str,
    pub(crate) scene: &'a Scene,
    pub(crate) transparent: bool,
    pub(crate) light_count: u64,
    pub(crate) evals: &'a [PoseEval],
    /// Poses (or measured frames of moving lights) checked.
    pub(crate) poses: u32,
    pub(crate) draws: Option<&'a Draws>,
    pub(crate) noise: Option<Noise>,
    /// The hierarchy's build in steady state (`gpu_ms_hierarchy_steady`, its passes in
    /// `passes_steady`).
    pub(crate) hierarchy_steady: Option<SteadyCull>,
    /// Each timed frame's passes, the encode and upload times, whether they were timed.
    pub(crate) measured: (&'a [Vec<PassTiming>], &'a [f64], &'a [f64], bool),
}

/// The result row of a cell from what it measured.
pub(crate) fn cell_row(parts: RowParts<'_>) -> Row {
    let RowParts {
        exp,
        cell,
        c,
        ctx,
        commit,
        scene,
        transparent,
        light_count,
        evals,
        poses,
        draws,
        noise,
        hierarchy_steady,
        measured: (frames, encode, uploads, timed),
    } = parts;
    let id = cell.id();
    let (w, h) = c.resolution;
    let first = &evals[0];
    let (bytes_written, bytes_read) = c.backend.bytes_per_pixel(c.msaa, c.hdr);
    let temporal = temporal_stability(evals);
    let worst = Worst::of(evals, noise.as_ref());
    let (list_bytes, gbuffer_bytes) = (first.list_bytes, first.gbuffer_bytes);

    let Timings {
        total,
        cull,
        shade,
        prepass,
        light_update,
        raster,
        compute,
        hierarchy: hierarchy_ms,
        passes,
    } = Timings::of(frames, timed);
    let med = |s: Option<(f64, f64, f64)>| s.map(|x| x.0);
    let p10 = |s: Option<(f64, f64, f64)>| s.map(|x| x.1);
    let p90 = |s: Option<(f64, f64, f64)>| s.map(|x| x.2);
    Row {
        experiment: exp.name.clone(),
        cell: cell.name.clone(),
        scene: c.scene.name(),
        lights: light_count,
        width: w,
        height: h,
        strategy: strategy_column(c).into(),
        backend: c.backend.name().into(),
        params: params_label(c),
        gpu_ms_total: med(total),
        gpu_ms_cull: med(cull),
        gpu_ms_shade: med(shade),
        gpu_ms_prepass: med(prepass),
        cpu_ms_encode: percentiles(encode).map_or(0.0, |x| x.0),
        // Naive forward has no lists, so none can miss a light: its exactness is its image
        // against the reference, not a count.
        false_negatives: worst
            .false_negatives
            .filter(|_| c.backend != Backend::NaiveForward),
        false_positive_ratio: worst.fp_ratio,
        lights_per_pixel_mean: worst.per_pixel_mean,
        max_lights_per_tile: worst.max_per_bin,
        dropped_lights: worst.dropped,
        list_bytes,
        gbuffer_bytes,
        msaa: c.msaa,
        transparent,
        passes_steady: steady_passes(first, hierarchy_steady.as_ref()),
        pass_categories: pass_categories(frames, first, hierarchy_steady.as_ref()),
        gpu_ms_geometry_steady: first.steady_geometry,
        gpu_ms_frame_steady: match (c.backend, first.steady_geometry, first.steady_frame) {
            (Backend::NaiveForward, g, _) => g,
            (_, Some(g), Some(f)) => Some(g + f.0),
            _ => None,
        },
        msaa_target_bytes: first.msaa_target_bytes,
        psnr_db: worst.psnr,
        flip_mean: worst.flip,
        max_abs_error: worst.max_abs,
        adapter: ctx.info.name.clone(),
        driver: format!("{} {}", ctx.info.driver, ctx.info.driver_info)
            .trim()
            .to_string(),
        commit: commit.to_string(),
        gpu_ms_total_p10: p10(total),
        gpu_ms_total_p90: p90(total),
        gpu_ms_cull_p10: p10(cull),
        gpu_ms_cull_p90: p90(cull),
        gpu_ms_shade_p10: p10(shade),
        gpu_ms_shade_p90: p90(shade),
        gpu_ms_prepass_p10: p10(prepass),
        gpu_ms_prepass_p90: p90(prepass),
        gpu_ms_raster: med(raster),
        gpu_ms_compute: med(compute),
        psnr_db_infinite: worst.psnr_inf,
        flip_mean_infinite: worst.flip_inf,
        max_abs_error_infinite: worst.max_abs_inf,
        exact_stride: c.exact_stride,
        frames: c.frames,
        nonfinite_pixels: worst.nonfinite,
        poses,
        temporal_change: temporal.map(|t| t.0),
        temporal_change_reference: temporal.map(|t| t.1),
        temporal_flicker: temporal.map(|t| t.2),
        tile_masks: first.tile_masks,
        gpu_ms_cull_steady: first.steady.map(|s| s.0),
        gpu_ms_cull_span: first.steady.and_then(|s| s.1),
        gpu_ms_cull_shade: first.steady_frame.map(|s| s.0),
        gpu_ms_cull_shade_span: first.steady_frame.and_then(|s| s.1),
        radius_rule: c.lights.radius.kind().into(),
        exposure_infinite: worst.exposure_inf,
        rmse_infinite: worst.rmse_inf,
        energy_error_infinite: worst.energy_inf,
        seeds: draws.map(|d| d.seeds),
        accumulate: draws.map(|d| d.accumulate),
        bias_infinite: noise.and_then(|n| n.bias),
        noise_infinite: noise.and_then(|n| n.noise),
        temporal_flicker_mean: noise.and_then(|n| n.flicker_mean),
        reference_infinite_cached: first.infinite_cached,
        materials: frame_models(scene),
        covered_pixels: Some(first.covered),
        gpu_ms_hierarchy: med(hierarchy_ms),
        gpu_ms_hierarchy_steady: hierarchy_steady.as_ref().map(|s| s.total_ms),
        gpu_ms_frame_build_steady: match (first.steady_geometry, first.steady_frame_built) {
            (Some(g), Some(f)) => Some(g + f),
            _ => None,
        },
        scene_lights: (c.lights.radius.kind() == "hierarchy").then_some(scene.lights.len() as u64),
        bytes_written_per_pixel: Some(bytes_written),
        bytes_read_per_pixel: Some(bytes_read),
        ns_per_light_eval: light_eval_ns(c, first, light_count),
        lights_needed_per_pixel_mean: worst.needed_per_pixel_mean,
        lights_walked_per_pixel_mean: first
            .walked
            .map(|n| n as f64 / first.covered.max(1) as f64),
        gpu_ms_light_update: med(light_update),
        cpu_ms_upload: percentiles(uploads).map(|x| x.0),
        sweep: sweep_columns(cell, &c.lights.radius),
        shadow: shadow_columns(c, first, &worst),
        passes,
        index: cell.index,
        id,
        finished_unix: now(),
        error: None,
    }
}

/// `ns_per_light_eval`: the first pose's shading passes over the lights it evaluates (naive
/// forward: every light at every covered pixel).
fn light_eval_ns(c: &Config, first: &PoseEval, light_count: u64) -> Option<f64> {
    let per_pixel = if c.backend == Backend::NaiveForward {
        light_count as f64
    } else {
        first.lights_per_pixel_mean
    };
    ns_per_light_eval(&first.steady_passes, per_pixel * first.covered as f64)
}

/// The shadow columns: the first pose's rays and their cost, the worst pose's error against the
/// shadowed light (a stochastic cell's: its seeds' mean).
fn shadow_columns(c: &Config, first: &PoseEval, worst: &Worst) -> ShadowColumns {
    let rays = first.rays.map(|n| n as f64);
    let gpu_ms_shadow = match (first.steady_frame, first.steady_frame_unshadowed) {
        (Some((with, _)), Some(without)) => Some(with - without),
        _ => None,
    };
    ShadowColumns {
        shadows: c.shadows.name().to_owned(),
        flip_mean_shadowed: worst.flip_shadowed,
        energy_error_shadowed: worst.energy_shadowed,
        rays_per_pixel: rays.map(|n| n / first.covered.max(1) as f64),
        gpu_ms_shadow,
        grays_per_s: match (rays, gpu_ms_shadow) {
            (Some(n), Some(ms)) if ms > 0.0 => Some(n / (ms * 1e-3) / 1e9),
            _ => None,
        },
        reference_shadowed_cached: first.shadowed_cached,
        shadowed_reference_se: worst.shadowed_se,
        occluded_pairs: c.occlusion.then_some(first.occluded),
    }
}

/// The `strategy` column: `none` for naive forward, which culls nothing.
fn strategy_column(c: &Config) -> &'static str {
    if c.backend == Backend::NaiveForward {
        "none"
    } else {
        c.strategy.name()
    }
}

/// The row of a cell that failed with `error`: its identity, parameters and where it ran, no
/// measurement, and the error (`Row::error`).
pub(crate) fn failed_row(
    exp: &Experiment,
    cell: &Cell,
    ctx: &GpuContext,
    commit: &str,
    error: &str,
) -> Row {
    let c = &cell.config;
    let (w, h) = c.resolution;
    let identity = serde_json::json!({
        "experiment": exp.name, "cell": cell.name, "scene": c.scene.name(),
        "lights": c.lights.count, "width": w, "height": h, "strategy": strategy_column(c),
        "backend": c.backend.name(), "params": params_label(c),
        "adapter": ctx.info.name,
        "driver": format!("{} {}", ctx.info.driver, ctx.info.driver_info).trim(),
        "commit": commit, "exact_stride": c.exact_stride, "frames": c.frames,
        "index": cell.index, "id": cell.id(), "finished_unix": now(),
        "msaa": c.msaa, "radius_rule": c.lights.radius.kind(),
    });
    let mut row = Row::unmeasured(identity);
    row.sweep = sweep_columns(cell, &c.lights.radius);
    row.error = Some(error.to_owned());
    row
}

/// The cell's parameters and its light range's as the row's columns.
fn sweep_columns(cell: &Cell, rule: &RadiusRule) -> SweepColumns {
    // As the rule's f32 is written (0.1, not 0.10000000149011612).
    let col = |v: f32| v.to_string().parse::<f64>().ok();
    let sweep = SweepColumns {
        setting: cell
            .parameters
            .iter()
            .find(|(k, _)| k == "setting")
            .map(|(_, v)| v.clone())
            .unwrap_or_default(),
        parameters: cell.parameters.iter().cloned().collect(),
        ..SweepColumns::default()
    };
    match *rule {
        RadiusRule::Fixed(v) | RadiusRule::Threshold(v) => SweepColumns {
            radius_value: col(v),
            ..sweep
        },
        RadiusRule::Hierarchy {
            alpha,
            spacing,
            finest_nodes,
            growth,
            ramp,
            sample_from,
            spot_bins,
        } => SweepColumns {
            radius_value: col(alpha),
            hierarchy_spacing: col(spacing),
            hierarchy_finest_nodes: col(finest_nodes),
            hierarchy_growth: col(growth),
            hierarchy_ramp: col(ramp),
            hierarchy_sample_from: sample_from,
            hierarchy_spot_bins: Some(spot_bins),
            ..sweep
        },
        RadiusRule::Stochastic {
            error,
            bound,
            exposure,
            interleave,
            draw,
            ..
        } => SweepColumns {
            radius_value: col(error),
            stochastic_bound: Some(bound.name().into()),
            stochastic_draw: Some(draw.name().into()),
            interleave: Some(interleave),
            stochastic_exposure: col(exposure),
            ..sweep
        },
    }
}

/// Each steady-state pass's median, ms, summed by label: the first pose's geometry, culling and
/// shading, and the hierarchy's build where it was timed (`passes_steady`).
fn steady_passes(
    first: &PoseEval,
    build: Option<&SteadyCull>,
) -> std::collections::BTreeMap<String, f64> {
    let build = build.into_iter().flat_map(|s| s.passes.iter());
    let mut m = std::collections::BTreeMap::new();
    for p in first.steady_passes.iter().chain(build) {
        *m.entry(p.label.clone()).or_insert(0.0) += p.ms;
    }
    m
}

/// The category of every pass the row times (`passes`, `passes_steady`), by label.
fn pass_categories(
    frames: &[Vec<PassTiming>],
    first: &PoseEval,
    build: Option<&SteadyCull>,
) -> std::collections::BTreeMap<String, String> {
    let steady = first
        .steady_passes
        .iter()
        .chain(build.into_iter().flat_map(|s| s.passes.iter()))
        .map(|p| (p.label.clone(), p.category));
    frames
        .iter()
        .flatten()
        .map(|p| (p.label.clone(), p.category))
        .chain(steady)
        .map(|(l, c)| (l, c.as_str().to_owned()))
        .collect()
}

/// A cell's measured frames as median and 10th and 90th percentile milliseconds: the whole,
/// each category and kind of pass, and each pass by label.
struct Timings {
    total: Option<(f64, f64, f64)>,
    cull: Option<(f64, f64, f64)>,
    shade: Option<(f64, f64, f64)>,
    prepass: Option<(f64, f64, f64)>,
    /// Where the update was timed (an upload's copy is not where the device cannot write
    /// timestamps between passes): never a made-up 0.
    light_update: Option<(f64, f64, f64)>,
    raster: Option<(f64, f64, f64)>,
    compute: Option<(f64, f64, f64)>,
    /// The lighting grid hierarchy's build (`lights.hierarchy.*`), where it ran and was timed.
    hierarchy: Option<(f64, f64, f64)>,
    passes: std::collections::BTreeMap<String, f64>,
}

impl Timings {
    /// Of `frames`, each a frame's passes; all `None` (and no passes) unless `timed`.
    fn of(frames: &[Vec<PassTiming>], timed: bool) -> Timings {
        let series = |pick: &dyn Fn(&PassTiming) -> bool| -> Vec<f64> {
            frames
                .iter()
                .map(|t| t.iter().filter(|p| pick(p)).map(|p| p.ms).sum())
                .collect()
        };
        let stats = |v: Vec<f64>| if timed { percentiles(&v) } else { None };
        let of_category = |c: Category| stats(series(&|p| p.category == c));
        let updates_timed = frames
            .iter()
            .any(|t| t.iter().any(|p| p.category == Category::LightUpdate));
        let mut passes = std::collections::BTreeMap::new();
        if timed {
            let labels: BTreeSet<String> = frames
                .iter()
                .flat_map(|t| t.iter().map(|p| p.label.clone()))
                .collect();
            for l in labels {
                if let Some((m, _, _)) = percentiles(&series(&|p| p.label == l)) {
                    passes.insert(l, m);
                }
            }
        }
        Timings {
            total: stats(series(&|_| true)),
            cull: of_category(Category::Cull),
            shade: of_category(Category::Shade),
            prepass: of_category(Category::Prepass),
            light_update: if updates_timed {
                of_category(Category::LightUpdate)
            } else {
                None
            },
            raster: stats(series(&|p| p.kind == PassKind::Raster)),
            compute: stats(series(&|p| p.kind == PassKind::Compute)),
            hierarchy: frames
                .iter()
                .any(|t| t.iter().any(|p| p.label.starts_with("lights.hierarchy.")))
                .then(|| stats(series(&|p| p.label.starts_with("lights.hierarchy."))))
                .flatten(),
            passes,
        }
    }
}

/// The worst of each measure over a cell's checked poses (a stochastic cell's image error
/// against infinite range: its seeds' mean).
struct Worst {
    false_negatives: Option<u64>,
    fp_ratio: Option<f64>,
    max_per_bin: Option<u64>,
    per_pixel_mean: Option<f64>,
    needed_per_pixel_mean: Option<f64>,
    dropped: u64,
    nonfinite: u64,
    psnr: Option<f64>,
    flip: Option<f64>,
    max_abs: Option<f64>,
    psnr_inf: Option<f64>,
    flip_inf: Option<f64>,
    max_abs_inf: Option<f64>,
    rmse_inf: Option<f64>,
    energy_inf: Option<f64>,
    exposure_inf: Option<f64>,
    flip_shadowed: Option<f64>,
    energy_shadowed: Option<f64>,
    shadowed_se: Option<f64>,
}

impl Worst {
    fn of(evals: &[PoseEval], noise: Option<&Noise>) -> Worst {
        let first = &evals[0];
        // The worst pose of each measure.
        let max_u64 = |f: &dyn Fn(&PoseEval) -> Option<u64>| evals.iter().filter_map(f).max();
        let max_f64 =
            |f: &dyn Fn(&PoseEval) -> Option<f64>| evals.iter().filter_map(f).reduce(f64::max);
        let min_f64 =
            |f: &dyn Fn(&PoseEval) -> Option<f64>| evals.iter().filter_map(f).reduce(f64::min);
        let false_negatives = evals
            .iter()
            .map(|e| e.metrics.as_ref().map(|m| m.false_negatives))
            .try_fold(0u64, |a, f| f.map(|f| a + f));
        let fp_ratio = max_f64(&|e| e.metrics.as_ref().and_then(|m| m.false_positive_ratio));
        let max_per_bin = max_u64(&|e| e.metrics.as_ref().map(|m| u64::from(m.max_lights_per_bin)));
        let per_pixel_mean = max_f64(&|e| Some(e.lights_per_pixel_mean));
        let dropped = max_u64(&|e| Some(e.dropped)).unwrap_or(0);
        let nonfinite = max_u64(&|e| Some(e.nonfinite)).unwrap_or(0);
        let (psnr, flip, max_abs) = (
            min_f64(&|e| e.acc.map(|a| a.psnr_db)),
            max_f64(&|e| e.acc.map(|a| a.flip_mean)),
            max_f64(&|e| e.acc.map(|a| a.max_abs_error)),
        );
        let (psnr_inf, mut flip_inf, max_abs_inf) = (
            min_f64(&|e| e.acc_inf.map(|a| a.psnr_db)),
            max_f64(&|e| e.acc_inf.map(|a| a.flip_mean)),
            max_f64(&|e| e.acc_inf.map(|a| a.max_abs_error)),
        );
        let mut rmse_inf = max_f64(&|e| e.acc_inf.map(|a| a.rmse));
        // The energy error of the pose farthest from zero.
        let mut energy_inf = evals
            .iter()
            .filter_map(|e| e.acc_inf.map(|a| a.energy_error))
            .reduce(|a, b| if b.abs() > a.abs() { b } else { a });
        let mut exposure_inf = first.acc_inf.map(|a| f64::from(a.exposure));
        let mut flip_shadowed = max_f64(&|e| e.acc_shadowed.map(|a| a.flip_mean));
        let mut energy_shadowed = evals
            .iter()
            .filter_map(|e| e.acc_shadowed.map(|a| a.energy_error))
            .reduce(|a, b| if b.abs() > a.abs() { b } else { a });
        if let Some((flip, energy)) = noise.and_then(|n| n.shadowed) {
            // A stochastic cell's error is its seeds' mean.
            (flip_shadowed, energy_shadowed) = (Some(flip), Some(energy));
        }
        if let Some(n) = noise {
            // A stochastic cell's image error is its seeds' mean.
            flip_inf = Some(n.flip_mean);
            rmse_inf = Some(n.rmse);
            energy_inf = Some(n.energy_error);
            exposure_inf = Some(n.exposure);
        }
        let needed_per_pixel_mean =
            max_f64(&|e| e.metrics.as_ref().map(|m| m.lights_needed_per_pixel_mean));
        Worst {
            false_negatives,
            fp_ratio,
            max_per_bin,
            per_pixel_mean,
            needed_per_pixel_mean,
            dropped,
            nonfinite,
            psnr,
            flip,
            max_abs,
            psnr_inf,
            flip_inf,
            max_abs_inf,
            rmse_inf,
            energy_inf,
            exposure_inf,
            flip_shadowed,
            energy_shadowed,
            shadowed_se: max_f64(&|e| e.shadowed_se),
        }
    }
}
