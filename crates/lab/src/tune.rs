//! `manylights tune`: the Forward+ paper's future work (an automatic tile size), generalised. For
//! one scene, light set, camera and resolution, every culling strategy is tried with several
//! parameters ([`candidates`]) on this device, as the cells of one experiment (so they are
//! measured, persisted and resumed as any experiment's are); a configuration with a false
//! negative or a dropped light is rejected; the rest are ranked by the whole frame in steady
//! state (`gpu_ms_frame_steady`: the raster pass, culling and the shading pass that reads the
//! lists, each back to back), or with [`Rank::CullShade`] by culling and shading alone
//! (`gpu_ms_cull_shade`, for culling studies).
//! The best is written as an experiment file of its own (`best.ron`) that `manylights run`
//! reproduces. A time budget stops starting candidates; those left are reported as untried.
//!
//! With an error budget ([`TuneOptions::max_error`]) the light ranges are candidates too
//! ([`TuneOptions::radii`]: radius cut-offs from thresholds, stochastic light culling's
//! error bounds and the lighting grid hierarchy's alphas, its build counted in its time:
//! [`cost`]), every candidate is scored against the infinite-range reference (computed
//! once and cached in the output folder), and only those within the budget of mean FLIP
//! against it (`flip_mean_infinite`) are ranked: the fastest configuration that is accurate
//! enough against the light as it is. With shadows (`shadows: Exact`) the budget is against the
//! shadowed infinite-range reference (`flip_mean_shadowed`, [`budget_error`]): the light as it
//! arrives.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use manylights_cull::{CullSettings, Slicing, Strategy};
use manylights_gpu::GpuContext;

use crate::experiment::{Config, Experiment, Sweep, Variant};
use crate::results::Row;
use crate::runner::{RunOptions, run_parsed};
use crate::{LabError, write_atomic};

/// What a culling study ranks a candidate by, ms: culling and the shading pass that reads the
/// lists, back to back (`gpu_ms_cull_shade`), and, with the lighting grid hierarchy, its build
/// each frame ([`Row::hierarchy_build_ms`]: in steady state where it was timed so), which the
/// frame pays too.
pub fn cost(r: &Row) -> Option<f64> {
    r.gpu_ms_cull_shade
        .map(|t| t + r.hierarchy_build_ms().unwrap_or(0.0))
}

/// What `tune` ranks candidates by.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Rank {
    /// The whole frame in steady state (`gpu_ms_frame_steady`: the raster pass, culling and
    /// shading), and the hierarchy's build: what users pay (the default).
    #[default]
    Frame,
    /// Culling and shading alone ([`cost`]), for culling studies.
    CullShade,
}

impl Rank {
    /// A row's time by this rank, ms.
    pub fn time(self, r: &Row) -> Option<f64> {
        match self {
            Self::Frame => r.frame_with_build_ms(),
            Self::CullShade => cost(r),
        }
    }

    /// What it ranks by, in words, with its column.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Frame => "the whole frame in steady state (gpu_ms_frame_steady)",
            Self::CullShade => "culling and shading together (gpu_ms_cull_shade)",
        }
    }
}

/// How to tune.
#[derive(Clone, Debug)]
pub struct TuneOptions {
    /// Start no candidate after this long.
    pub budget: Duration,
    /// Show a progress bar.
    pub progress: bool,
    /// The commit the binary was built from.
    pub commit: String,
    /// Rank only candidates within this mean FLIP of the infinite-range reference (> 0).
    pub max_error: Option<f64>,
    /// With `max_error`, the radius rules tried with every strategy (none: the base's alone).
    pub radii: Vec<manylights_scene::RadiusRule>,
    /// What candidates are ranked by.
    pub rank: Rank,
}

/// What tuning found.
#[derive(Clone, Debug)]
pub struct TuneReport {
    /// Conservative candidates (no false negative, no dropped light) with a culling-and-shading
    /// time, fastest first.
    pub ranked: Vec<Row>,
    /// Candidates that finished but are not eligible, with why.
    pub rejected: Vec<(Row, String)>,
    /// Candidates the budget left untried (their cell names).
    pub untried: Vec<String>,
    /// Candidates left out before running, as the device cannot hold them (z-binning's masks,
    /// tiles x lights / 8 bytes, past a storage binding), with why.
    pub left_out: Vec<(Strategy, String)>,
    /// The best candidate's experiment file, `best.ron` in the output directory.
    pub best_file: PathBuf,
}

/// The strategies and parameters tried: tiles of 8, 16 and 32 pixels for gather, 2.5D, tiled
/// scatter and z-binning (its default 256 exponential bins); clusters of 16, 24, 32 and 64
/// pixels with 16, 32 and 48 exponential slices, their lists in light order (bit-identical
/// frames). (At 1M lights of radius 0.5 m at 1080p on the H100, 24 x 32 took 1.971 ms, 32 x 32
/// 1.989, 32 x 24 2.00, 24 x 48 2.02 and 40 x 32 2.03: docs/BENCHMARKS.md, "Goals".)
pub fn candidates() -> Vec<Strategy> {
    let mut v = Vec::new();
    for tile in [8, 16, 32] {
        v.push(Strategy::tiled_gather(tile));
        v.push(Strategy::depth_mask(tile));
        v.push(Strategy::TiledScatter { tile_size: tile });
        v.push(Strategy::ZBin {
            tile_size: tile,
            bins: manylights_cull::DEFAULT_ZBINS,
            slicing: Slicing::Exponential,
        });
    }
    for tile in [16, 24, 32, 64] {
        for slices in [16, 32, 48] {
            v.push(Strategy::Clustered {
                tile_size: tile,
                slices,
                slicing: Slicing::Exponential,
                skip_empty: false,
                ordered: true,
                cells: false,
            });
        }
    }
    v
}

/// The candidates the device holds for `base`, and those it does not with why: z-binning's
/// masks and sorted lights must fit one storage binding (1 GB at 1M lights and 1080p).
pub fn fitting(ctx: &GpuContext, base: &Config) -> (Vec<Strategy>, Vec<(Strategy, String)>) {
    let (w, h) = base.resolution;
    // (Only the tiles and the light count size them.)
    let settings = CullSettings {
        near: 0.1,
        far: 1.0,
        slack: base.slack,
        capacity: None,
        mask_budget: None,
        tile_boxes: true,
        occlusion: false,
    };
    let mut fit = Vec::new();
    let mut left_out = Vec::new();
    for s in candidates() {
        if let Strategy::ZBin { .. } = s {
            let p = s.params(w, h, base.lights.count, &settings);
            let bytes = manylights_cull::strategies::zbin::index_words(&p) * 4;
            if let Err(e) = ctx.check_storage("zbin masks and sorted lights", bytes) {
                left_out.push((s, e.to_string()));
                continue;
            }
        }
        fit.push(s);
    }
    (fit, left_out)
}

/// An experiment's RON text, in the form the parser reads (newtype variants unwrapped,
/// options implicit).
fn to_ron(e: &Experiment) -> Result<String, LabError> {
    let pretty = ron::ser::PrettyConfig::new().struct_names(true).extensions(
        ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES
            | ron::extensions::Extensions::IMPLICIT_SOME,
    );
    ron::ser::to_string_pretty(e, pretty)
        .map_err(|err| LabError::refused("writing the experiment", err.to_string()))
}

/// Tries every candidate on `base` (its strategy is replaced; everything else is kept) and
/// ranks them; the cells, results and report go to `out`.
pub fn tune(
    ctx: &GpuContext,
    base: &Config,
    out: &Path,
    opts: &TuneOptions,
) -> Result<TuneReport, LabError> {
    let (fit, left_out) = fitting(ctx, base);
    let variants: Vec<Variant> = fit
        .into_iter()
        .map(|s| Variant {
            strategy: Some(s),
            ..Variant::default()
        })
        .collect();
    let mut config = base.clone();
    let mut radius = None;
    if let Some(f) = opts.max_error {
        if !(f.is_finite() && f > 0.0) {
            return Err(LabError::refused(
                format!("max_error = {f}"),
                "a mean FLIP above 0 (and finite)",
            ));
        }
        // Scored against infinite range only: the same cut-off's brute-force reference is not
        // what the budget is about.
        config.accuracy = true;
        config.cutoff_reference = false;
        if !opts.radii.is_empty() {
            radius = Some(opts.radii.clone());
        }
    }
    let exp = Experiment {
        name: "tune".into(),
        description: match opts.max_error {
            // Nor what they are ranked by (`--rank`): the same cells serve either.
            None => format!(
                "manylights tune: every strategy and parameter candidate with the {} backend, ranked by the whole frame in steady state (gpu_ms_frame_steady) or by culling and shading together (gpu_ms_cull_shade).",
                base.backend.name(),
            ),
            // The budget is left out: the same cells serve any budget, so a rerun with another
            // one in the same folder ranks them again without running anything.
            Some(_) => format!(
                "manylights tune --max-error: every strategy and parameter candidate with every light range (radius cut-offs, stochastic light culling and the lighting grid hierarchy) and the {} backend, scored against the infinite-range reference; those within the error budget ranked by the whole frame in steady state (gpu_ms_frame_steady) or by culling and shading together (gpu_ms_cull_shade).",
                base.backend.name(),
            ),
        },
        config,
        sweep: Sweep {
            radius,
            variants: Some(variants),
            ..Sweep::default()
        },
    };
    let src = to_ron(&exp)?;
    // What is written is what a rerun reads.
    Experiment::parse(&src, &out.join("experiment.ron"))?;
    let run = run_parsed(
        ctx,
        &exp,
        &src,
        Path::new("."),
        out,
        &RunOptions {
            deadline: Some(Instant::now() + opts.budget),
            progress: opts.progress,
            commit: opts.commit.clone(),
            ..RunOptions::default()
        },
    )?;
    let cells = exp.cells();
    let untried = cells
        .iter()
        .filter(|c| !run.rows.iter().any(|r| r.id == c.id()))
        .map(|c| c.name.clone())
        .collect();
    let (mut ranked, mut rejected) = (Vec::new(), Vec::new());
    for r in run.rows {
        match why_not(&r, opts.max_error, opts.rank) {
            None => ranked.push(r),
            Some(why) => rejected.push((r, why)),
        }
    }
    let time = |r: &Row| opts.rank.time(r).unwrap_or(f64::INFINITY);
    ranked.sort_by(|a, b| time(a).total_cmp(&time(b)));
    let best = ranked.first().ok_or_else(|| {
        let closest = rejected
            .iter()
            .filter_map(|(r, _)| budget_error(r))
            .reduce(f64::min);
        let against = against(base.shadows.casts());
        let error = match (opts.max_error, closest) {
            (Some(f), Some(c)) => format!(
                "; the lowest mean FLIP against {against} was {c:.4}, against --max-error {f}: \
                 raise it, or try longer ranges (--thresholds, --errors, --alphas)"
            ),
            _ => String::new(),
        };
        LabError::refused(
            "tune",
            format!(
                "no candidate was eligible within the budget of {} s ({} rejected, {} untried): \
                 raise --budget-s, or see {} for the rejected ones{error}",
                opts.budget.as_secs(),
                rejected.len(),
                cells.len() - rejected.len(),
                out.join("results.csv").display()
            ),
        )
    })?;
    let cell = cells
        .iter()
        .find(|c| c.id() == best.id)
        .expect("every row is a cell of the experiment");
    let best_exp = Experiment {
        name: "tuned".into(),
        description: format!(
            "The fastest conservative configuration manylights tune found on {} ({} + {}, {}, {}: {:.3} ms, {}{}{}).",
            best.adapter,
            best.backend,
            best.strategy,
            best.params,
            cell.config.lights.radius.kind(),
            opts.rank.time(best).unwrap_or(f64::NAN),
            opts.rank.describe(),
            if best.hierarchy_build_ms().is_some() {
                " with the hierarchy's build"
            } else {
                ""
            },
            match (opts.max_error, budget_error(best)) {
                (Some(b), Some(f)) => format!(
                    ", mean FLIP {f:.4} against {} within {b}",
                    against(base.shadows.casts())
                ),
                _ => String::new(),
            }
        ),
        config: cell.config.clone(),
        sweep: Sweep::default(),
    };
    let best_file = out.join("best.ron");
    write_atomic(&best_file, to_ron(&best_exp)?.as_bytes())?;
    Ok(TuneReport {
        ranked,
        rejected,
        untried,
        left_out,
        best_file,
    })
}

/// Why a finished candidate cannot be the answer: a false negative, a dropped light, no time
/// for culling and shading (no timestamps, or naive forward), or with an error budget an error
/// against infinite range above it.
fn why_not(r: &Row, max_error: Option<f64>, rank: Rank) -> Option<String> {
    if let Some(e) = &r.error {
        return Some(e.clone());
    }
    match r.false_negatives {
        Some(0) => {}
        Some(n) => return Some(format!("{n} false negatives")),
        None => return Some("no exact oracle (exact_stride 0)".into()),
    }
    if r.dropped_lights > 0 {
        return Some(format!("{} dropped lights", r.dropped_lights));
    }
    if rank.time(r).is_none() {
        return Some(format!(
            "no time for {} (no timestamp queries?)",
            rank.describe()
        ));
    }
    if let Some(budget) = max_error {
        let against = against(!matches!(r.shadow.shadows.as_str(), "" | "off"));
        match budget_error(r) {
            Some(f) if f <= budget => {}
            Some(f) => {
                return Some(format!(
                    "mean FLIP {f:.4} against {against}, above --max-error {budget}"
                ));
            }
            None => return Some(format!("no accuracy against {against}")),
        }
    }
    None
}

/// The error `--max-error` holds a candidate to: with shadows, mean FLIP against the shadowed
/// infinite-range reference (`flip_mean_shadowed`), else against the infinite-range one
/// (`flip_mean_infinite`).
pub fn budget_error(r: &Row) -> Option<f64> {
    if !matches!(r.shadow.shadows.as_str(), "" | "off") {
        r.shadow.flip_mean_shadowed
    } else {
        r.flip_mean_infinite
    }
}

/// What [`budget_error`] measures against, for a candidate with or without shadows.
fn against(shadows: bool) -> &'static str {
    if shadows {
        "the shadowed infinite range"
    } else {
        "infinite range"
    }
}
