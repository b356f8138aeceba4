//! `manylights`: the command-line front end.
//!
//! Exit codes: 0 success; 1 a run failed (bad input values, a malformed scene file, no usable
//! GPU adapter, a device error, an unwritable output); 2 the command line itself is malformed
//! (unknown option, unparsable number, value outside an option's range).

mod cull_cmd;
mod hierarchy_opt;
mod lab_cmds;
mod options;
mod render_cmd;
mod score_cmd;
mod strategy_opts;
mod tune_cmd;

use std::path::{Path, PathBuf};

use clap::{Parser, Subcommand};

use cull_cmd::{CullArgs, cull};
use lab_cmds::{MergeArgs, ReportArgs, RunArgs, report, run_experiment};
use render_cmd::{RenderArgs, render};
use score_cmd::{ScoreArgs, ScoreChartArgs, run_score, score_chart};
use tune_cmd::{TuneArgs, run_tune};

/// Light-culling research workbench: culling strategies and shading backends on wgpu,
/// measured for speed and for exactness against a brute-force reference.
#[derive(Parser, Debug)]
#[command(name = "manylights", version = concat!(env!("CARGO_PKG_VERSION"), " (commit ", env!("MANYLIGHTS_COMMIT"), ")"), about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Log to stderr what each stage of the work takes: -v the stages of every experiment cell
    /// (scene upload, frames, oracle, reference), -vv also every GPU submission's wait.
    /// RUST_LOG (such as `RUST_LOG=manylights_lab=debug`) overrides it. Logging hides the
    /// progress bar.
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    verbose: u8,
}

/// Whether `-v` was given (the progress bar would garble the log lines).
static VERBOSE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

fn show_progress() -> bool {
    !VERBOSE.load(std::sync::atomic::Ordering::Relaxed)
        && std::io::IsTerminal::is_terminal(&std::io::stderr())
}

/// Logs to stderr at the level `-v` asks for (or RUST_LOG's).
fn init_logging(verbose: u8) {
    let level = match verbose {
        0 => "warn",
        1 => "warn,manylights_lab=info",
        _ => {
            "warn,manylights_lab=debug,manylights_gpu=debug,manylights_shade=debug,manylights_cull=debug"
        }
    };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(level));
    VERBOSE.store(
        verbose > 0 || std::env::var_os("RUST_LOG").is_some(),
        std::sync::atomic::Ordering::Relaxed,
    );
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene with the brute-force reference renderer (every light at every pixel, no
    /// culling) or with a shading backend over a culling strategy, and write the HDR image
    /// (EXR), a tonemapped PNG and, for a backend, a heatmap of lights evaluated per pixel.
    /// --compare prints the image error against the reference and the infinite-range reference.
    ///
    /// Lights are generated deterministically from --seed and added to any lights the scene
    /// holds (glTF KHR_lights_punctual). The output files are written atomically: a failed run
    /// leaves no partial file.
    Render(RenderArgs),
    /// Cull the lights of a scene with one strategy and measure the lists against the exact
    /// per-pixel oracle: false negatives, false-positive ratio, lights per pixel, the longest
    /// list, list memory, per-pass GPU times, the lights deferred shading of the lists walks; and
    /// write heatmaps of lights per tile and per pixel.
    Cull(CullArgs),
    /// Run an experiment (a RON file): every cell of its sweep, with a progress bar, each cell
    /// persisted as soon as it finishes (a rerun skips finished cells), then DIR/results.csv,
    /// DIR/results.json and the report (DIR/report.md, DIR/report.html).
    Run(RunArgs),
    /// Join the output directories of the shards of one experiment into one, and report.
    Merge(MergeArgs),
    /// Write the paper-style report of a run directory: report.md and report.html with figures.
    Report(ReportArgs),
    /// Find the fastest conservative configuration for a scene, light set and resolution on
    /// this device: try every strategy with several tile sizes (and cluster grids), reject any
    /// with a false negative, rank the rest by the whole frame in steady state
    /// (gpu_ms_frame_steady; --rank cull-shade: culling and shading together,
    /// gpu_ms_cull_shade), print the table, and write the best as an experiment file
    /// (OUT/best.ron) with the candidates' results and report in OUT (default out/tune).
    Tune(TuneArgs),
    /// Score another program's light lists (an engine's clusters or tiles, written as
    /// grid.json, offsets.npy and indices.npy) against the exact per-pixel oracle over an
    /// export's depth buffer, camera and lights: false negatives and where they are, lights
    /// evaluated per light needed, lights per pixel, the longest list (docs/EXPERIMENTS.md,
    /// "Scoring another engine's lists").
    Score(ScoreArgs),
    /// Chart a referee's scores: DIR/scores.csv (one row a setting and list source, as
    /// scripts/referee-bevy.sh writes it) drawn as DIR/figures/scores.svg, lights evaluated per
    /// light needed against the lists' memory, a panel a setting, sources that miss lights
    /// ringed in red.
    ScoreChart(ScoreChartArgs),
}

/// Mesa's implicit Vulkan layer `VK_LAYER_MESA_device_select` connects to a Wayland display while
/// the adapters are enumerated, and without a usable `XDG_RUNTIME_DIR` libwayland prints
/// "error: XDG_RUNTIME_DIR is invalid or not set in the environment." (twice) before any work:
/// not our error, and alarming. Where that directory is missing, the layer is turned off through
/// its own switch, `NODEVICE_SELECT=1` (it only reorders adapters; `--adapter` picks ours).
fn quiet_device_select() {
    let usable = std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| Path::new(&d).is_dir());
    if !usable && std::env::var_os("NODEVICE_SELECT").is_none() {
        #[allow(
            unsafe_code,
            reason = "set_var is unsafe only where other threads may read the environment; \
                      this runs first in main, before any thread is started"
        )]
        // SAFETY: called at the start of `main`, while the process has a single thread.
        unsafe {
            std::env::set_var("NODEVICE_SELECT", "1");
        }
    }
}

fn main() -> std::process::ExitCode {
    quiet_device_select();
    let cli = Cli::parse();
    init_logging(cli.verbose);
    if let Err(e) = manylights_gpu::shaders::check_override_dir() {
        eprintln!("error: {e}");
        return std::process::ExitCode::FAILURE;
    }
    let result = match &cli.command {
        Command::Render(args) => render(args),
        Command::Cull(args) => cull(args),
        Command::Run(args) => run_experiment(args),
        Command::Merge(args) => {
            let inputs: Vec<&Path> = args.inputs.iter().map(PathBuf::as_path).collect();
            manylights_lab::results::merge(&inputs, &args.out)
                .map_err(anyhow::Error::from)
                .and_then(|rows| {
                    eprintln!("merged {} cells into {}", rows.len(), args.out.display());
                    let html = manylights_lab::report::write_report(&args.out)?;
                    eprintln!("report: {}", html.display());
                    Ok(())
                })
        }
        Command::Report(args) => report(&args.dir),
        Command::Tune(args) => run_tune(args),
        Command::Score(args) => run_score(args),
        Command::ScoreChart(args) => score_chart(&args.dir),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
