//! `tune`: every strategy and its parameters on this device for one scene, light set and
//! resolution, ranked by culling and shading together (`manylights_lab::tune`).

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::ValueEnum;
use manylights_cull::layout::DEFAULT_SLACK;
use manylights_lab::experiment::{CameraSpec, Config, SceneSpec};
use manylights_lab::tune::{Rank, TuneOptions, tune};
use manylights_scene::RadiusRule;
use manylights_scene::stochastic::{StochasticBound, StochasticDraw};
use manylights_shade::Backend;

use crate::options::{SceneArgs, positive_f32};
use crate::show_progress;

#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub(crate) struct TuneArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    /// The shading backend the lists are for.
    #[arg(long, value_enum, default_value_t = TuneBackend::Deferred)]
    pub(crate) backend: TuneBackend,
    /// What candidates are ranked by: the whole frame in steady state (raster pass, culling and
    /// shading: what users pay), or culling and shading alone (for culling studies).
    #[arg(long, value_enum, default_value_t = TuneRank::Frame)]
    pub(crate) rank: TuneRank,
    /// Shadows of every candidate (--shadows, --shadow-rays): with shadows the candidates are
    /// ranked by their frames with them, and with --max-error held to mean FLIP against the
    /// shadowed infinite-range reference.
    #[command(flatten)]
    pub(crate) shadows: crate::render_cmd::ShadowArgs,
    /// Start no candidate after this many seconds (those left are listed as untried); a rerun
    /// with the same options and --out resumes where it stopped.
    #[arg(long, default_value_t = 600)]
    pub(crate) budget_s: u64,
    /// Measured frames of each candidate (times are medians over them, and over as many
    /// back-to-back runs).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub(crate) frames: u32,
    /// Frames rendered before measuring.
    #[arg(long, default_value_t = 2)]
    pub(crate) warmup: u32,
    /// Pixel stride of the exact oracle that rejects candidates with false negatives (1: every
    /// pixel; larger samples a grid, for light counts where every pixel would take long).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) exact_stride: u32,
    /// Rank only configurations within this mean FLIP of the infinite-range reference (the
    /// light with no cut-off): light ranges become candidates too (--thresholds, --errors,
    /// --alphas), each scored against that reference.
    #[arg(long, value_parser = positive_f64)]
    pub(crate) max_error: Option<f64>,
    /// With --max-error: the thresholds whose radius cut-offs are tried
    /// (radius = sqrt(intensity * max(colour) / threshold)).
    #[arg(long, value_delimiter = ',', default_values_t = [1.0, 0.3, 0.1, 0.03], value_parser = positive_f32)]
    pub(crate) thresholds: Vec<f32>,
    /// With --max-error: the error bounds of stochastic light culling tried (as --stochastic's
    /// E, which joins them; --bound, --accumulate and --interleave apply to each).
    #[arg(long, value_delimiter = ',', default_values_t = [4.0, 1.0, 0.25], value_parser = positive_f32)]
    pub(crate) errors: Vec<f32>,
    /// With --max-error: the accuracy parameters (alpha, above 0) of the lighting grid
    /// hierarchy tried, each with --spacing (`radius: Hierarchy(alpha, spacing)`; --hierarchy's
    /// alpha joins them).
    #[arg(long, value_delimiter = ',', default_values_t = [1.0, 2.0], value_parser = crate::hierarchy_opt::alpha)]
    pub(crate) alphas: Vec<f32>,
    /// With --max-error: the growths of the hierarchy's bands tried (as --growth's K, which
    /// joins them; from 1 to 4), each with every alpha of --alphas and ramp of --ramps; 1, the
    /// papers' bands, where neither is given.
    #[arg(long, value_delimiter = ',', value_parser = positive_f32)]
    pub(crate) growths: Vec<f32>,
    /// With --max-error: the hierarchy's ramps tried (as --ramp's C, which joins them; above 1
    /// and at most 2), each with every alpha and growth; 2, the papers', where neither is given.
    #[arg(long, value_delimiter = ',', value_parser = positive_f32)]
    pub(crate) ramps: Vec<f32>,
}

fn positive_f64(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{s}`: a finite number above 0")),
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum TuneBackend {
    /// Forward+: depth prepass, culling, forward shading over the lists.
    Forward,
    /// Deferred: G-buffer, culling, compute lighting over the lists.
    Deferred,
    /// Visibility buffer: depth and triangle ids, culling, compute lighting over the lists.
    Visibility,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum TuneRank {
    /// The whole frame in steady state (gpu_ms_frame_steady).
    Frame,
    /// Culling and shading together (gpu_ms_cull_shade).
    CullShade,
}

/// A time in ms to three places, `-` where there is none.
fn ms(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.3}"))
}

/// The ranked candidates as a table: the frame, culling and shading, culling, the lists' lights
/// a pixel, the lights shading walks and needs, the lists' lights per light needed, and the
/// error the budget limits (against the shadowed light where `shadowed`).
fn print_ranking(ranked: &[manylights_lab::Row], shadowed: bool) {
    println!(
        "{:>4}  {:<64} {:>11} {:>11} {:>11} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "rank",
        "strategy",
        "frame",
        "cull+shade",
        "cull",
        "lights/px",
        "walked",
        "needed",
        "per need",
        if shadowed {
            "FLIP shad"
        } else {
            "FLIP inf"
        }
    );
    for (i, r) in ranked.iter().enumerate() {
        println!(
            "{:>4}  {:<64} {:>8} ms {:>8} ms {:>8} ms {:>9} {:>9} {:>9} {:>9} {:>9}",
            i + 1,
            format!("{} ({}){}", r.strategy, r.params, range_of(r)),
            ms(Rank::Frame.time(r)),
            ms(manylights_lab::tune::cost(r)),
            ms(r.gpu_ms_cull_steady),
            r.lights_per_pixel_mean
                .map_or("-".into(), |v| format!("{v:.1}")),
            r.lights_walked_per_pixel_mean
                .map_or("-".into(), |v| format!("{v:.1}")),
            r.lights_needed_per_pixel_mean
                .map_or("-".into(), |v| format!("{v:.1}")),
            r.false_positive_ratio
                .map_or("-".into(), |v| format!("{v:.2}")),
            manylights_lab::tune::budget_error(r).map_or("-".into(), |v| format!("{v:.4}")),
        );
    }
}

pub(crate) fn run_tune(args: &TuneArgs) -> Result<()> {
    let a = &args.scene;
    args.shadows.check()?;
    // The scene and its lights, checked before any GPU work.
    let scene = a.build()?;
    let radii = candidate_ranges(args)?;
    let ctx = a.gpu()?;
    let out = a.out.clone().unwrap_or_else(|| PathBuf::from("out/tune"));
    let base = Config {
        scene: SceneSpec::from_name(&a.scene),
        lights: a.light_spec(),
        camera: CameraSpec::Default,
        resolution: (a.width, a.height),
        strategy: manylights_cull::Strategy::tiled_gather(16),
        backend: match args.backend {
            TuneBackend::Forward => Backend::Forward,
            TuneBackend::Deferred => Backend::Deferred,
            TuneBackend::Visibility => Backend::Visibility,
        },
        capacity: None,
        mask_budget: None,
        tile_boxes: true,
        light_update: Default::default(),
        msaa: 1,
        hdr: Default::default(),
        visibility_pass: Default::default(),
        shadows: args.shadows.shadows(),
        shadowed_reference: false,
        shadowed_reference_rays: None,
        occlusion: false,
        materials: a.models()?,
        slack: DEFAULT_SLACK,
        frames: args.frames,
        warmup: args.warmup,
        accuracy: false,
        cutoff_reference: true,
        exact_stride: args.exact_stride,
        device_limit: None,
        export: false,
    };
    let ranges = if args.max_error.is_some() {
        radii.len()
    } else {
        1
    };
    eprintln!(
        "tuning {} ({} lights) at {}x{} for {}: {} candidates, budget {} s",
        scene.name,
        scene.lights.len(),
        a.width,
        a.height,
        base.backend.name(),
        manylights_lab::tune::candidates().len() * ranges,
        args.budget_s
    );
    let rank = match args.rank {
        TuneRank::Frame => Rank::Frame,
        TuneRank::CullShade => Rank::CullShade,
    };
    let report = tune(
        &ctx,
        &base,
        &out,
        &TuneOptions {
            budget: Duration::from_secs(args.budget_s),
            progress: show_progress(),
            commit: env!("MANYLIGHTS_COMMIT").into(),
            max_error: args.max_error,
            radii,
            rank,
        },
    )?;
    print_ranking(&report.ranked, args.shadows.shadows().casts());
    for (r, why) in &report.rejected {
        println!(
            "rejected: {} ({}){}: {why}",
            r.strategy,
            r.params,
            range_of(r)
        );
    }
    for (s, why) in &report.left_out {
        println!("left out: {s:?}: {why}");
    }
    if !report.untried.is_empty() {
        println!(
            "untried within {} s: {} candidates ({})",
            args.budget_s,
            report.untried.len(),
            report.untried.join("; ")
        );
    }
    let best = &report.ranked[0];
    println!(
        "best: {} + {} ({}){}: {} ms, {}{}",
        best.backend,
        best.strategy,
        best.params,
        range_of(best),
        ms(rank.time(best)),
        rank.describe(),
        if best.hierarchy_build_ms().is_some() {
            " with the hierarchy's build"
        } else {
            ""
        }
    );
    println!(
        "wrote {} (reproduce it with `manylights run {}`)",
        report.best_file.display(),
        report.best_file.display()
    );
    let html = manylights_lab::report::write_report(&out)
        .with_context(|| format!("report of {}", out.display()))?;
    eprintln!("report: {}", html.display());
    Ok(())
}

/// `list` with `one` joined where it is not in it already, or `default` alone where both are
/// empty.
fn joined(list: &[f32], one: Option<f32>, default: f32) -> Vec<f32> {
    let mut v = list.to_vec();
    if let Some(x) = one
        && !v.contains(&x)
    {
        v.push(x);
    }
    if v.is_empty() {
        v.push(default);
    }
    v
}

/// With --max-error, the light ranges tried: --thresholds' cut-offs, --errors' stochastic
/// bounds (with --stochastic's E among them, and its --bound, --accumulate and --interleave
/// on each) and the lighting grid hierarchies of every alpha of --alphas, growth of --growths
/// and ramp of --ramps (with --spacing); a hierarchy's parameters out of range are an error
/// naming the options.
pub(crate) fn candidate_ranges(args: &TuneArgs) -> Result<Vec<RadiusRule>> {
    use manylights_scene::hierarchy::{GROWTH, RAMP};
    let a = &args.scene;
    let errors = joined(&args.errors, a.stochastic, 1.0);
    let alphas = joined(&args.alphas, a.hierarchy, 1.0);
    let growths = joined(&args.growths, a.growth, GROWTH as f32);
    let ramps = joined(&args.ramps, a.ramp, RAMP as f32);
    let mut hierarchies = Vec::new();
    for &alpha in &alphas {
        for &growth in &growths {
            for &ramp in &ramps {
                let rule = a.hierarchy_with(alpha, growth, ramp, None);
                rule.validate().with_context(|| {
                    format!(
                        "tune's hierarchy of alpha {alpha}, growth {growth}, ramp {ramp} \
                         (--alphas, --growths, --ramps)"
                    )
                })?;
                hierarchies.push(rule);
            }
        }
    }
    let stochastic = match a.light_spec().radius {
        r @ RadiusRule::Stochastic { .. } => r,
        _ => RadiusRule::Stochastic {
            error: 1.0,
            bound: StochasticBound::Light,
            exposure: 1.0,
            accumulate: 0,
            seeds: 4,
            interleave: 1,
            draw: StochasticDraw::Stratified,
        },
    };
    Ok(args
        .thresholds
        .iter()
        .map(|&t| RadiusRule::Threshold(t))
        .chain(errors.into_iter().map(|e| match stochastic {
            RadiusRule::Stochastic {
                bound,
                exposure,
                accumulate,
                interleave,
                draw,
                ..
            } => RadiusRule::Stochastic {
                error: e,
                bound,
                exposure,
                accumulate,
                seeds: 4,
                interleave,
                draw,
            },
            other => other,
        }))
        .chain(hierarchies)
        .collect())
}

/// The light range a ranked candidate was tried with, where ranges were candidates: its range
/// parameter (` threshold=0.1`, ` stochastic=1`, ` hierarchy=1/h0.25`), else nothing.
fn range_of(r: &manylights_lab::Row) -> String {
    manylights_lab::RADIUS_AXES
        .iter()
        .find_map(|k| r.sweep.parameters.get(*k).map(|v| format!(" {k}={v}")))
        .unwrap_or_default()
}
