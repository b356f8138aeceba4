//! The runner: every cell of an experiment (or of one shard of it), each persisted the moment
//! it finishes, so that a killed run loses nothing finished and a rerun skips what is done; the
//! renderers kept from cell to cell ([`crate::renderers`]).
//!
//! Per cell ([`crate::cell_run`]): build the scene and lights; render `warmup` frames, then `frames` measured frames
//! (GPU times from timestamp queries, medians with p10 and p90); at the first camera pose,
//! culling timed in steady state (`frames` runs back to back, [`crate::steady`]), the list
//! metrics from the exact per-pixel oracle (on the GPU, on every `exact_stride`-th pixel) and,
//! with `accuracy`, the image error against the reference and the infinite-range
//! reference; a small render and lights-per-pixel heatmap for the report. Moving lights
//! (`lights.motion`; `lights.moving` of them) move before each frame (`crate::frame_lights`),
//! their update timed with it, and the list metrics and accuracy are taken at every measured
//! frame instead of every pose.

use std::collections::BTreeSet;
use std::path::Path;
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use manylights_gpu::GpuContext;

use crate::experiment::{Cell, Experiment};
use crate::renderers::{LoadedScenes, ReferenceFrames, Renderers};
use crate::results::{Row, load_cells, save_cell, write_results};
use crate::{LabError, write_atomic};

/// How to run.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Run only cells whose index is `i` modulo `n`.
    pub shard: Option<(usize, usize)>,
    /// Stop after this many cells were run (as if the run were killed then).
    pub max_cells: Option<usize>,
    /// Start no cell after this instant (a time budget; the cells left are not run).
    pub deadline: Option<Instant>,
    /// Show a progress bar.
    pub progress: bool,
    /// The commit the binary was built from.
    pub commit: String,
}

/// What a run did.
#[derive(Clone, Debug)]
pub struct RunSummary {
    /// Cells run now.
    pub ran: usize,
    /// Cells skipped because a previous run finished them.
    pub skipped: usize,
    /// Cells of this shard.
    pub in_shard: usize,
    /// Every finished row of the experiment in the output directory, the failed cells' among
    /// them (`Row::error`).
    pub rows: Vec<Row>,
}

impl RunSummary {
    /// The cells whose rows hold an error: this run's failures and earlier runs' not retried.
    pub fn failed(&self) -> Vec<&Row> {
        self.rows.iter().filter(|r| r.error.is_some()).collect()
    }

    /// An error naming every failed cell and why, where any failed.
    pub fn check(&self) -> Result<(), LabError> {
        let failed = self.failed();
        if failed.is_empty() {
            return Ok(());
        }
        Err(LabError::CellsFailed {
            count: failed.len(),
            cells: failed
                .iter()
                .map(|r| r.error.clone().unwrap_or_default())
                .collect::<Vec<_>>()
                .join("; "),
        })
    }
}

fn io(path: &Path, e: impl ToString) -> LabError {
    LabError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// Runs the experiment at `path` into `out`.
pub fn run(
    ctx: &GpuContext,
    path: &Path,
    out: &Path,
    opts: &RunOptions,
) -> Result<RunSummary, LabError> {
    let (exp, src) = Experiment::load(path)?;
    run_parsed(
        ctx,
        &exp,
        &src,
        path.parent().unwrap_or(Path::new(".")),
        out,
        opts,
    )
}

/// Runs a parsed experiment whose text is `src` (kept in `out/experiment.ron`); relative glTF
/// paths are resolved against `base`.
pub fn run_parsed(
    ctx: &GpuContext,
    exp: &Experiment,
    src: &str,
    base: &Path,
    out: &Path,
    opts: &RunOptions,
) -> Result<RunSummary, LabError> {
    std::fs::create_dir_all(out)
        .map_err(|e| io(out, format!("cannot create the output directory: {e}")))?;
    let exp_copy = out.join("experiment.ron");
    match std::fs::read_to_string(&exp_copy) {
        Ok(prev) if prev != src => {
            return Err(LabError::refused(
                out.display().to_string(),
                "holds results of a different experiment file; choose another --out or remove it",
            ));
        }
        Ok(_) => {}
        Err(_) => write_atomic(&exp_copy, src.as_bytes())?,
    }
    let meta = serde_json::json!({
        "experiment": exp.name,
        "adapter": ctx.info.name,
        "driver": format!("{} {}", ctx.info.driver, ctx.info.driver_info),
        "backend": format!("{:?}", ctx.info.backend),
        "device_type": format!("{:?}", ctx.info.device_type),
        "summary": ctx.summary(),
        "commit": opts.commit,
        "started_unix": now(),
        "shard": opts.shard.map(|(i, n)| format!("{i}/{n}")),
    });
    write_atomic(
        &out.join("meta.json"),
        serde_json::to_string_pretty(&meta)
            .expect("json")
            .as_bytes(),
    )?;

    let cells = exp.cells();
    let ids: BTreeSet<String> = cells.iter().map(Cell::id).collect();
    let mine: Vec<&Cell> = cells
        .iter()
        .filter(|c| opts.shard.is_none_or(|(i, n)| c.index % n == i))
        .collect();
    // A failed cell is run again.
    let done: BTreeSet<String> = load_cells(out)?
        .into_iter()
        .filter(|r| r.error.is_none())
        .map(|r| r.id)
        .collect();
    let todo: Vec<&&Cell> = mine.iter().filter(|c| !done.contains(&c.id())).collect();
    let skipped = mine.len() - todo.len();
    let bar = if opts.progress {
        indicatif::ProgressBar::new(mine.len() as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:30} {pos}/{len} cells, {elapsed} elapsed, ETA {eta}  {msg}",
        )
        .expect("template")
        .progress_chars("=> "),
    );
    bar.set_position(skipped as u64);
    let mut ran = 0;
    let mut renderers = Renderers::default();
    let frames = ReferenceFrames::default();
    let loaded = LoadedScenes::default();
    for cell in todo {
        if opts.max_cells.is_some_and(|m| ran >= m)
            || opts.deadline.is_some_and(|d| Instant::now() >= d)
        {
            break;
        }
        bar.set_message(cell.name.clone());
        // A cell that fails is recorded with its error, and the sweep goes on.
        let row = crate::cell_run::run_cell(
            ctx,
            exp,
            cell,
            (base, out),
            &opts.commit,
            (&mut renderers, &frames, &loaded),
        )
        .unwrap_or_else(|e| {
            let error = LabError::Cell {
                index: cell.index,
                name: cell.name.clone(),
                message: e.to_string(),
            }
            .to_string();
            bar.suspend(|| eprintln!("{error}"));
            crate::cell_row::failed_row(exp, cell, ctx, &opts.commit, &error)
        });
        save_cell(out, &row)?;
        ran += 1;
        bar.inc(1);
    }
    bar.finish_and_clear();
    let rows: Vec<Row> = load_cells(out)?
        .into_iter()
        .filter(|r| ids.contains(&r.id))
        .collect();
    write_results(out, &rows)?;
    Ok(RunSummary {
        ran,
        skipped,
        in_shard: mine.len(),
        rows,
    })
}

/// Runs `f` and logs (at level info) how long the stage `what` of cell `cell` took: with
/// `manylights -v run`, a long cell shows where its time goes.
pub(crate) fn stage<T>(cell: &str, what: &str, f: impl FnOnce() -> T) -> T {
    let start = Instant::now();
    let out = f();
    tracing::info!(
        cell,
        ms = (start.elapsed().as_secs_f64() * 1e4).round() / 10.0,
        "{what}"
    );
    out
}

pub(crate) fn now() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}
