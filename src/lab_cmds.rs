//! `run`, `merge` and `report`: experiments, their shards and their reports.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use manylights_gpu::{GpuContext, GpuOptions};

use crate::show_progress;

#[derive(clap::Args, Debug)]
pub(crate) struct RunArgs {
    /// The experiment file (see experiments/ and docs/EXPERIMENTS.md), or a directory of them
    /// (such as experiments/stability), each run into OUT/<file stem> with a stability report in
    /// OUT/stability.md.
    pub(crate) experiment: PathBuf,
    /// Output directory (default: out/<experiment file stem>).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Run only every N-th cell, starting at cell I (I/N, 0 <= I < N), to spread a sweep over
    /// machines; join the outputs with `manylights merge`.
    #[arg(long, value_parser = parse_shard)]
    pub(crate) shard: Option<(usize, usize)>,
    /// Start no cell after this many seconds (a cell already started runs to its end); the
    /// cells left are reported, and running again with the same --out resumes them. For batch
    /// systems' wall-time limits and for sweeps whose slowest cells would not finish.
    #[arg(long, value_name = "SECONDS", value_parser = parse_time_limit)]
    pub(crate) time_limit: Option<f64>,
    /// Do not write the report at the end.
    #[arg(long)]
    pub(crate) no_report: bool,
    /// GPU adapter (see `render --help`).
    #[arg(long)]
    pub(crate) adapter: Option<String>,
}

#[derive(clap::Args, Debug)]
pub(crate) struct MergeArgs {
    /// Output directory.
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// Shard output directories.
    #[arg(required = true)]
    pub(crate) inputs: Vec<PathBuf>,
}

#[derive(clap::Args, Debug)]
pub(crate) struct ReportArgs {
    /// A run directory.
    pub(crate) dir: PathBuf,
}

pub(crate) fn parse_time_limit(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{s}`: need a positive number of seconds")),
    }
}

pub(crate) fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| format!("`{s}`: expected I/N, such as 0/4"))?;
    let i: usize = i
        .trim()
        .parse()
        .map_err(|_| format!("`{s}`: I must be an integer"))?;
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| format!("`{s}`: N must be an integer"))?;
    if n == 0 || i >= n {
        return Err(format!("`{s}`: need 0 <= I < N"));
    }
    Ok((i, n))
}

/// `run DIR`: every experiment file of a directory (the stability suite), each into
/// OUT/<file stem>, then OUT/stability.md. A case that fails to run is recorded, not fatal.
pub(crate) fn run_suite(args: &RunArgs) -> Result<()> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(&args.experiment)
        .with_context(|| format!("cannot read {}", args.experiment.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    files.sort();
    if files.is_empty() {
        bail!("{}: no .ron experiment files", args.experiment.display());
    }
    let out = args.out.clone().unwrap_or_else(|| {
        PathBuf::from("out").join(
            args.experiment
                .file_name()
                .map_or_else(|| "suite".into(), |s| s.to_string_lossy().into_owned()),
        )
    });
    // Parse every file first: a malformed file fails before anything runs.
    for f in &files {
        manylights_lab::Experiment::load(f)?;
    }
    let ctx = GpuContext::new(&GpuOptions {
        adapter: args.adapter.clone(),
    })?;
    eprintln!("adapter: {}", ctx.summary());
    let opts = manylights_lab::runner::RunOptions {
        shard: args.shard,
        max_cells: None,
        // One deadline for the whole suite: the cases after it start no cell.
        deadline: args
            .time_limit
            .map(|t| std::time::Instant::now() + std::time::Duration::from_secs_f64(t)),
        progress: show_progress(),
        commit: env!("MANYLIGHTS_COMMIT").to_string(),
    };
    let mut cases = Vec::new();
    for f in &files {
        let name = f
            .file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        eprintln!("case {name}");
        let dir = out.join(&name);
        let rows = manylights_lab::runner::run(&ctx, f, &dir, &opts)
            .and_then(|s| s.check().map(|()| s.rows))
            .map_err(|e| e.to_string());
        if let Err(e) = &rows {
            eprintln!("  failed: {e}");
        } else if !args.no_report {
            manylights_lab::report::write_report(&dir)?;
        }
        cases.push((name, rows));
    }
    let fails = manylights_lab::stability::write_report(&out, &cases)?;
    eprintln!(
        "stability report: {} ({fails} failing entries)",
        out.join("stability.md").display()
    );
    Ok(())
}

/// `report DIR`: a run directory's report, or for a suite (case subdirectories, each with
/// results) every case's report and the stability report.
pub(crate) fn report(dir: &Path) -> Result<()> {
    if dir.join("results.json").exists() || dir.join("cells").is_dir() {
        let p = manylights_lab::report::write_report(dir)?;
        eprintln!("report: {}", p.display());
        return Ok(());
    }
    let mut cases: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("results.json").exists() || p.join("cells").is_dir())
        .collect();
    cases.sort();
    if cases.is_empty() {
        bail!(
            "{}: neither a run directory (results.json, cells/) nor a suite of them",
            dir.display()
        );
    }
    let mut rows = Vec::new();
    for c in &cases {
        manylights_lab::report::write_report(c)?;
        let name = c
            .file_name()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        if c.join("results.json").exists() {
            rows.push((
                name,
                manylights_lab::results::load_rows(c).map_err(|e| e.to_string()),
            ));
        } else {
            // A case whose run did not finish: its finished cells, and the name says so.
            let done = manylights_lab::results::load_cells(c).map_err(|e| e.to_string());
            let total = manylights_lab::Experiment::load(&c.join("experiment.ron"))
                .map_or(0, |(e, _)| e.cells().len());
            let k = done.as_ref().map_or(0, Vec::len);
            rows.push((format!("{name} (incomplete: {k} of {total} cells)"), done));
        }
    }
    let fails = manylights_lab::stability::write_report(dir, &rows)?;
    eprintln!(
        "stability report: {} ({fails} failing entries)",
        dir.join("stability.md").display()
    );
    Ok(())
}

pub(crate) fn run_experiment(args: &RunArgs) -> Result<()> {
    if args.experiment.is_dir() {
        return run_suite(args);
    }
    let out = args.out.clone().unwrap_or_else(|| {
        PathBuf::from("out").join(
            args.experiment
                .file_stem()
                .map_or_else(|| "experiment".into(), |s| s.to_string_lossy().into_owned()),
        )
    });
    // Parse first: a malformed file fails before any device is opened or any file is written.
    let (exp, _) = manylights_lab::Experiment::load(&args.experiment)?;
    let cells = exp.cells().len();
    let ctx = GpuContext::new(&GpuOptions {
        adapter: args.adapter.clone(),
    })?;
    eprintln!("adapter: {}", ctx.summary());
    eprintln!(
        "experiment `{}`: {cells} cells{}",
        exp.name,
        args.shard
            .map_or(String::new(), |(i, n)| format!(", shard {i}/{n}"))
    );
    let opts = manylights_lab::runner::RunOptions {
        shard: args.shard,
        max_cells: None,
        deadline: args
            .time_limit
            .map(|t| std::time::Instant::now() + std::time::Duration::from_secs_f64(t)),
        progress: show_progress(),
        commit: env!("MANYLIGHTS_COMMIT").to_string(),
    };
    let s = manylights_lab::runner::run(&ctx, &args.experiment, &out, &opts)?;
    eprintln!(
        "ran {} cells, {} already done; {} rows in {}",
        s.ran,
        s.skipped,
        s.rows.len(),
        out.join("results.csv").display()
    );
    let left = s.in_shard - s.ran - s.skipped;
    if left > 0 {
        eprintln!(
            "{left} cells not run (--time-limit reached); run the same command again to resume them"
        );
    }
    if !args.no_report && s.rows.iter().any(|r| r.error.is_none()) {
        let html = manylights_lab::report::write_report(&out)?;
        eprintln!(
            "report: {} and {}",
            out.join("report.md").display(),
            html.display()
        );
    }
    // Failed cells are in the results and the report; the run says so and fails.
    s.check()?;
    Ok(())
}
