//! `manylights`: the command-line front end.
//!
//! Exit codes: 0 success; 1 a run failed (bad input values, a malformed scene file, no usable
//! GPU adapter, a device error, an unwritable output); 2 the command line itself is malformed
//! (unknown option, unparsable number, value outside an option's range).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand, ValueEnum};
use manylights_cull::layout::DEFAULT_SLACK;
use manylights_cull::{CullOutput, CullSettings, Culler, Slicing, Strategy, heatmap, metrics};
use manylights_gpu::prepass::{DepthPrepass, depth_target};
use manylights_gpu::timing::{GpuTimer, MAX_QUERIES};
use manylights_gpu::{GpuContext, GpuOptions, GpuScene};
use manylights_scene::gltf_import::{self, GltfOptions};
use manylights_scene::procedural::{self, ProceduralScene};
use manylights_scene::{LightGenerator, LightSpec, RadiusRule, Scene};
use manylights_shade::image_out::write_atomic;
use manylights_shade::{Backend, ReferenceRenderer, Renderer, accuracy};

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
    /// list, list memory, per-pass GPU times; and write heatmaps of lights per tile and per pixel.
    Cull(CullArgs),
    /// Run an experiment (a RON file): every cell of its sweep, with a progress bar, each cell
    /// persisted as soon as it finishes (a rerun skips finished cells), then DIR/results.csv,
    /// DIR/results.json and the report (DIR/report.md, DIR/report.html).
    Run(RunArgs),
    /// Join the output directories of the shards of one experiment into one, and report.
    Merge(MergeArgs),
    /// Write the paper-style report of a run directory: report.md and report.html with figures.
    Report(ReportArgs),
}

#[derive(clap::Args, Debug)]
struct RunArgs {
    /// The experiment file (see experiments/ and docs/EXPERIMENTS.md), or a directory of them
    /// (such as experiments/stability), each run into OUT/<file stem> with a stability report in
    /// OUT/stability.md.
    experiment: PathBuf,
    /// Output directory (default: out/<experiment file stem>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Run only every N-th cell, starting at cell I (I/N, 0 <= I < N), to spread a sweep over
    /// machines; join the outputs with `manylights merge`.
    #[arg(long, value_parser = parse_shard)]
    shard: Option<(usize, usize)>,
    /// Do not write the report at the end.
    #[arg(long)]
    no_report: bool,
    /// GPU adapter (see `render --help`).
    #[arg(long)]
    adapter: Option<String>,
}

#[derive(clap::Args, Debug)]
struct MergeArgs {
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
    /// Shard output directories.
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
}

#[derive(clap::Args, Debug)]
struct ReportArgs {
    /// A run directory.
    dir: PathBuf,
}

fn parse_shard(s: &str) -> Result<(usize, usize), String> {
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
fn run_suite(args: &RunArgs) -> Result<()> {
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
            .map(|s| s.rows)
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
fn report(dir: &Path) -> Result<()> {
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

fn run_experiment(args: &RunArgs) -> Result<()> {
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
    if !args.no_report {
        let html = manylights_lab::report::write_report(&out)?;
        eprintln!(
            "report: {} and {}",
            out.join("report.md").display(),
            html.display()
        );
    }
    Ok(())
}

/// Scene, lights, resolution and adapter: shared by every subcommand.
#[derive(clap::Args, Debug)]
struct SceneArgs {
    /// A procedural scene (atrium, pillars, topdown, city) or a path to a .gltf/.glb file.
    #[arg(long, default_value = "atrium")]
    scene: String,
    /// Number of lights to generate (0 renders only the scene's own lights).
    #[arg(long, default_value_t = 1024)]
    lights: u32,
    /// Where lights are placed.
    #[arg(long, value_enum, default_value_t = Generator::Field)]
    generator: Generator,
    /// Seed of every random choice of the light generator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Fixed light radius in metres (the light contributes exactly nothing beyond it).
    #[arg(long, default_value_t = 3.0, conflicts_with = "threshold")]
    radius: f32,
    /// Derive each radius from its intensity instead: the distance where intensity / d^2 falls
    /// to this threshold.
    #[arg(long)]
    threshold: Option<f32>,
    /// Intensity of every generated light.
    #[arg(long, default_value_t = 4.0)]
    intensity: f32,
    /// Fraction of generated lights that are spot lights, in [0, 1].
    #[arg(long, default_value_t = 0.0)]
    spot_fraction: f32,
    /// Image width in pixels (at most the device's max_texture_dimension_2d).
    #[arg(long, default_value_t = 1280, value_parser = clap::value_parser!(u32).range(1..=65536))]
    width: u32,
    /// Image height in pixels (at most the device's max_texture_dimension_2d).
    #[arg(long, default_value_t = 720, value_parser = clap::value_parser!(u32).range(1..=65536))]
    height: u32,
    /// Output directory, created if needed (default: out/<subcommand>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// GPU adapter: a substring of its name or its index (default: $MANYLIGHTS_ADAPTER, else the
    /// first discrete GPU, else any adapter, lavapipe included).
    #[arg(long)]
    adapter: Option<String>,
}

#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Shading backend: the brute-force reference, or a backend over a culling strategy
    /// (--strategy and its options; naive-forward culls nothing).
    #[arg(long, value_enum, default_value_t = BackendName::Reference)]
    backend: BackendName,
    #[command(flatten)]
    cull: StrategyArgs,
    /// Also render the reference and the infinite-range reference, and print the image error
    /// against each (max abs error, RMSE, PSNR, mean FLIP).
    #[arg(long)]
    compare: bool,
    /// With --compare, also write the FLIP error map against the reference as a PNG.
    #[arg(long, requires = "compare")]
    flip_map: bool,
    /// Exposure applied before tonemapping the PNG (and for FLIP).
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
}

#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
struct CullArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    cull: StrategyArgs,
    /// Top of the heatmaps' colour scale (default: the longest list shown), so that heatmaps
    /// of several runs can share one scale.
    #[arg(long)]
    heat_max: Option<u32>,
    /// For clusters, the depth slice the tile heatmap shows (default: the longest list over
    /// all slices of each tile).
    #[arg(long)]
    slice: Option<u32>,
    /// Also time this many runs back to back in one submission (no host round trip between
    /// or inside them, the lists sized from the first run) and print each pass's median over
    /// them: steady-state times, as the benchmarks measure; then the same runs timed with one
    /// pair of timestamps around each run's passes (where the device can write timestamps
    /// between passes), their median as `span`. 0: only the single run.
    #[arg(long, default_value_t = 0)]
    repeat: u32,
    /// Build the lists without tile masks (a bit per tile and light, used where they fit 16
    /// MiB): gather's and 2.5D's fill then tests every light again, and tiled scatter writes
    /// (tile, light) pairs and radix-sorts them, as Harada et al. 2012 describe.
    #[arg(long, conflicts_with = "mask_budget")]
    no_tile_masks: bool,
    /// Most bytes of tile masks the run may use (default: 16 MiB; 0 is --no-tile-masks), as an
    /// experiment's `mask_budget`. The output says whether the run used them.
    #[arg(long, value_name = "BYTES")]
    mask_budget: Option<u64>,
}

/// A culling strategy and its parameters.
#[derive(clap::Args, Debug)]
struct StrategyArgs {
    /// Culling strategy.
    #[arg(long, value_enum, default_value_t = StrategyName::TiledGather)]
    strategy: StrategyName,
    /// Tile side in pixels (8, 16 and 32 are usual; 4..=256 accepted). Default: 16, or 64 for
    /// clustered.
    #[arg(long)]
    tile_size: Option<u32>,
    /// Depth slices of the cluster grid (clustered only).
    #[arg(long, default_value_t = 24)]
    slices: u32,
    /// Slicing of the cluster grid (clustered only).
    #[arg(long, value_enum, default_value_t = SlicingName::Exponential)]
    slicing: SlicingName,
    /// Emit lights only into clusters that hold geometry (clustered only).
    #[arg(long)]
    skip_empty: bool,
    /// Keep the clusters' atomic fill order instead of sorting each list into light order
    /// (clustered only; one pass less, images no longer bit-identical across runs).
    #[arg(long)]
    unordered: bool,
    /// Gather and 2.5D: 8 culls lights against coarse tiles of 8 x 8 tiles first, and each tile
    /// tests only its coarse tile's survivors; 0 tests every light at every tile (the paper's
    /// single level).
    #[arg(long, default_value_t = manylights_cull::DEFAULT_COARSE)]
    coarse: u32,
    /// Conservative slack, relative to each light's distance from the eye.
    #[arg(long, default_value_t = DEFAULT_SLACK)]
    slack: f32,
    /// A deliberate cap on each list's length: lights beyond it are dropped and counted (the
    /// default, none, sizes lists exactly and drops nothing).
    #[arg(long)]
    capacity: Option<u32>,
}

impl StrategyArgs {
    fn strategy(&self) -> Result<Strategy> {
        let default_tile = if matches!(self.strategy, StrategyName::Clustered) {
            64
        } else {
            16
        };
        let tile_size = self.tile_size.unwrap_or(default_tile);
        let strategy = match self.strategy {
            StrategyName::TiledGather => Strategy::TiledGather {
                tile_size,
                coarse: self.coarse,
            },
            StrategyName::TiledScatter => Strategy::TiledScatter { tile_size },
            StrategyName::DepthMask => Strategy::DepthMask {
                tile_size,
                coarse: self.coarse,
            },
            StrategyName::Clustered => Strategy::Clustered {
                tile_size,
                slices: self.slices,
                slicing: match self.slicing {
                    SlicingName::Linear => Slicing::Linear,
                    SlicingName::Exponential => Slicing::Exponential,
                },
                skip_empty: self.skip_empty,
                ordered: !self.unordered,
            },
        };
        strategy.validate()?;
        Ok(strategy)
    }

    fn settings(&self, camera: &manylights_scene::Camera) -> Result<CullSettings> {
        let s = CullSettings {
            slack: self.slack,
            capacity: self.capacity,
            ..CullSettings::for_camera(camera)
        };
        s.validate().context("invalid --slack or --capacity")?;
        Ok(s)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum BackendName {
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
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Generator {
    /// Uniform in the scene's light volume.
    Uniform,
    /// On the scene's surfaces, lifted 0.1 m along the normal.
    Surface,
    /// Eight Gaussian hot spots of 1.5 m standard deviation.
    Clustered,
    /// A stratified field through the whole volume (the Forward+ paper's demo).
    Field,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum StrategyName {
    /// Forward+ tiled gather (Harada et al. 2012, 4.1).
    TiledGather,
    /// Forward+ tiled scatter with the GPU radix sort (Harada et al. 2012, 4.2).
    TiledScatter,
    /// 2.5D culling with depth masks (Harada 2012).
    DepthMask,
    /// 3D clusters (Olsson et al. 2012).
    Clustered,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum SlicingName {
    /// Equal depth per slice.
    Linear,
    /// Equal depth ratio per slice.
    Exponential,
}

fn load_scene(name: &str) -> Result<Scene> {
    let looks_like_file = name.ends_with(".gltf") || name.ends_with(".glb") || name.contains('/');
    if looks_like_file {
        let (scene, report) = gltf_import::load(Path::new(name), &GltfOptions::default())?;
        if report.skipped_primitives + report.skipped_directional_lights > 0 {
            eprintln!(
                "note: {name}: skipped {} point/line primitives and {} directional lights (not supported)",
                report.skipped_primitives, report.skipped_directional_lights
            );
        }
        Ok(scene)
    } else {
        ProceduralScene::from_name(name)
            .with_context(|| {
                format!(
                    "--scene {name}: not a file path (.gltf/.glb) and not one of {}",
                    procedural::NAMES.join(", ")
                )
            })?
            .build()
            .map_err(Into::into)
    }
}

impl SceneArgs {
    /// The scene with its generated lights, validated.
    fn build(&self) -> Result<Scene> {
        let mut scene = load_scene(&self.scene)?;
        let spec = LightSpec {
            generator: match self.generator {
                Generator::Uniform => LightGenerator::Uniform,
                Generator::Surface => LightGenerator::SurfaceHugging { offset: 0.1 },
                Generator::Clustered => LightGenerator::Clustered {
                    clusters: 8,
                    spread: 1.5,
                },
                Generator::Field => LightGenerator::LightField,
            },
            count: self.lights,
            seed: self.seed,
            radius: self
                .threshold
                .map_or(RadiusRule::Fixed(self.radius), RadiusRule::Threshold),
            intensity: self.intensity,
            spot_fraction: self.spot_fraction,
            ..LightSpec::default()
        };
        let generated = spec.generate(&scene).context(
            "invalid light options (--radius, --threshold, --intensity, --spot-fraction)",
        )?;
        scene.lights.extend(generated);
        scene
            .validate()
            .with_context(|| format!("scene {}", scene.name))?;
        Ok(scene)
    }

    /// The device, checked against the resolution.
    fn gpu(&self) -> Result<GpuContext> {
        let ctx = GpuContext::new(&GpuOptions {
            adapter: self.adapter.clone(),
        })?;
        eprintln!("adapter: {}", ctx.summary());
        ctx.check_resolution(self.width, self.height)
            .context("invalid --width/--height")?;
        Ok(ctx)
    }
}

fn print_timings(timings: Option<&[manylights_gpu::timing::PassTiming]>) {
    match timings {
        Some(t) => {
            for p in t {
                println!("  {:<28} {:>8} {:>10.3} ms", p.label, p.kind.as_str(), p.ms);
            }
        }
        None => println!("  (no GPU timings: the adapter has no timestamp queries)"),
    }
}

fn render(args: &RenderArgs) -> Result<()> {
    if !(args.exposure.is_finite() && args.exposure > 0.0) {
        bail!("invalid --exposure {}: a finite value > 0", args.exposure);
    }
    let a = &args.scene;
    let scene = a.build()?;
    let strategy = args.cull.strategy()?;
    let settings = args.cull.settings(&scene.camera)?;
    let ctx = a.gpu()?;
    let (w, h) = (a.width, a.height);
    let gpu_scene = GpuScene::upload(&ctx, &scene, &scene.camera, w, h)?;
    let dir = a.out.clone().unwrap_or_else(|| PathBuf::from("out/render"));
    println!(
        "{}: {} triangles, {} lights, {w}x{h}",
        scene.name,
        scene.triangle_count(),
        scene.lights.len()
    );
    let reference = ReferenceRenderer::new(&ctx, &gpu_scene);
    let mut outputs: Vec<(PathBuf, image::RgbImage)> = Vec::new();
    let (name, image) = if args.backend == BackendName::Reference {
        let frame = reference.render(&ctx, &gpu_scene, w, h)?;
        print_timings(frame.timings.as_deref());
        ("reference", frame.color)
    } else {
        let backend = match args.backend {
            BackendName::Forward => Backend::Forward,
            BackendName::Deferred => Backend::Deferred,
            BackendName::DeferredStoredPosition => Backend::DeferredStoredPosition,
            BackendName::NaiveForward | BackendName::Reference => Backend::NaiveForward,
        };
        let renderer = Renderer::new(&ctx, &gpu_scene);
        let out = renderer.render(&ctx, &gpu_scene, backend, &strategy, &settings, (w, h))?;
        if backend != Backend::NaiveForward {
            println!("  strategy {strategy:?}");
        }
        print_timings(out.timings.as_deref());
        let per_pixel: Vec<u32> = match &out.lists {
            Some(lists) => renderer
                .culler
                .lights_per_pixel(&ctx, &gpu_scene, &out.depth, lists)?,
            None => out
                .color
                .data
                .iter()
                .map(|c| {
                    if c[3] > 0.0 {
                        scene.lights.len() as u32
                    } else {
                        0
                    }
                })
                .collect(),
        };
        if let Some(lists) = &out.lists {
            println!(
                "  list entries / bytes    {} / {}",
                lists.total,
                lists.list_bytes()
            );
            println!("  dropped lights          {}", lists.dropped);
        }
        if out.gbuffer_bytes > 0 {
            println!("  G-buffer bytes          {}", out.gbuffer_bytes);
        }
        let covered = out.color.data.iter().filter(|c| c[3] > 0.0).count().max(1);
        let max = per_pixel.iter().copied().max().unwrap_or(0).max(1);
        let mean = per_pixel.iter().map(|&n| f64::from(n)).sum::<f64>() / covered as f64;
        println!("  lights per pixel        {mean:.2} (mean over covered pixels), {max} at most");
        let heat = dir.join(format!("heatmap_lights_per_pixel_{}.png", backend.name()));
        outputs.push((heat, heatmap::pixels(&per_pixel, w, h, max)));
        (backend.name(), out.color)
    };
    let bad = image.non_finite_count();
    if bad > 0 {
        bail!("the render holds {bad} NaN/Inf pixels; nothing was written");
    }
    if args.compare {
        let windowed = reference.render(&ctx, &gpu_scene, w, h)?.color;
        let infinite = reference
            .render_infinite(&ctx, &gpu_scene, &scene.camera, w, h)?
            .color;
        for (label, r) in [
            ("reference", &windowed),
            ("infinite-range reference", &infinite),
        ] {
            let e = accuracy::compare(&image, r, args.exposure);
            println!(
                "  vs {label:<25} max abs {:.3e} ({:.2e} of peak), RMSE {:.3e}, PSNR {:.2} dB, mean FLIP {:.5}",
                e.max_abs_error,
                e.max_abs_error / e.peak.max(f64::MIN_POSITIVE),
                e.rmse,
                e.psnr_db,
                e.flip_mean
            );
        }
        if args.flip_map {
            outputs.push((
                dir.join(format!("flip_{name}.png")),
                accuracy::flip_map(&image, &windowed, args.exposure),
            ));
        }
    }
    let png = dir.join(format!("{name}.png"));
    let exr = dir.join(format!("{name}.exr"));
    image.write_exr(&exr)?;
    image.write_png(&png, args.exposure)?;
    for (path, img) in &outputs {
        write_atomic(path, |f| {
            img.write_to(f, image::ImageFormat::Png)
                .map_err(|e| e.to_string())
        })?;
        println!("wrote {}", path.display());
    }
    println!("wrote {} and {}", png.display(), exr.display());
    Ok(())
}

fn cull(args: &CullArgs) -> Result<()> {
    let a = &args.scene;
    let strategy = args.cull.strategy()?;
    let scene = a.build()?;
    let ctx = a.gpu()?;
    let (w, h) = (a.width, a.height);
    let gpu_scene = GpuScene::upload(&ctx, &scene, &scene.camera, w, h)?;
    let depth = depth_target(&ctx, w, h);
    let mut timer = GpuTimer::new(&ctx, 64);
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    DepthPrepass::new(&ctx, &gpu_scene).encode(
        &mut enc,
        &gpu_scene,
        &depth.create_view(&Default::default()),
        &mut timer,
    );
    ctx.submit_and_wait(enc, "depth prepass")?;
    let culler = Culler::new(&ctx, &gpu_scene);
    let settings = CullSettings {
        mask_budget: if args.no_tile_masks {
            Some(0)
        } else {
            args.mask_budget
        },
        ..args.cull.settings(&scene.camera)?
    };
    let out = culler.run(&ctx, &gpu_scene, &depth, &strategy, &settings, &mut timer)?;
    let timings = timer.read(&ctx)?;
    let repeated = if args.repeat > 0 {
        // The culling passes of the run above (the prepass is its one raster pass).
        let passes = timings.as_ref().map(|t| {
            t.iter()
                .filter(|p| p.kind == manylights_gpu::timing::PassKind::Compute)
                .count() as u32
        });
        repeated_timings(
            &ctx, &culler, &gpu_scene, &depth, &strategy, &settings, &out, passes, args,
        )?
    } else {
        String::new()
    };
    let lists = out.read(&ctx)?;
    let frame =
        manylights_gpu::layout::GpuFrame::new(&scene.camera, w, h, scene.lights.len() as u32);
    let counts = culler.exact_counts(
        &ctx,
        &gpu_scene,
        &depth,
        &out,
        frame.clip_from_world.inverse(),
        1,
    )?;
    let m = metrics::from_gpu_counts(&counts, &lists);
    let per_pixel: Vec<u32> = counts.iter().map(|c| c[0]).collect();
    let tiles = heatmap::tile_counts(&out.params, &lists, args.slice);
    let max = args
        .heat_max
        .unwrap_or_else(|| tiles.iter().copied().max().unwrap_or(0).max(1));
    let dir = a.out.clone().unwrap_or_else(|| PathBuf::from("out/cull"));
    let tile_png = dir.join(format!("heatmap_tiles_{}.png", strategy.name()));
    let pixel_png = dir.join(format!("heatmap_pixels_{}.png", strategy.name()));
    for (path, img) in [
        (&tile_png, heatmap::tiles(&out.params, &tiles, w, h, max)),
        (&pixel_png, heatmap::pixels(&per_pixel, w, h, max)),
    ] {
        write_atomic(path, |f| {
            img.write_to(f, image::ImageFormat::Png)
                .map_err(|e| e.to_string())
        })?;
    }
    println!(
        "{}: {} triangles, {} lights, {w}x{h}, {strategy:?}",
        scene.name,
        scene.triangle_count(),
        scene.lights.len()
    );
    println!("  covered pixels          {}", m.covered_pixels);
    println!("  false negatives         {}", m.false_negatives);
    match m.false_positive_ratio {
        Some(r) => println!("  false-positive ratio    {r:.3} (lights evaluated / lights needed)"),
        None => println!("  false-positive ratio    n/a (no pixel needs a light)"),
    }
    println!("  lights per pixel        {:.2}", m.lights_per_pixel_mean);
    println!("  max lights per bin      {}", m.max_lights_per_bin);
    println!(
        "  list entries / bytes    {} / {}",
        out.total,
        out.list_bytes()
    );
    println!("  dropped lights          {}", out.dropped);
    println!(
        "  tile masks              {}",
        match (&out.tile_masks, &out.tile_lines) {
            (Some(m), _) => format!("used ({} bytes)", m.size()),
            (None, Some(l)) => format!("used as tile lines ({} bytes)", l.size()),
            (None, None) => "not used".into(),
        }
    );
    print_timings(timings.as_deref());
    print!("{repeated}");
    println!(
        "heat scale 0..{max} lights; wrote {} and {}",
        tile_png.display(),
        pixel_png.display()
    );
    if m.false_negatives > 0 {
        bail!(
            "{} false negatives: a conservative strategy must have none (a bug, or --slack too small)",
            m.false_negatives
        );
    }
    Ok(())
}

/// `cull --repeat N`: N runs back to back in one submission; each pass's median over them, as
/// lines to print.
#[allow(
    clippy::too_many_arguments,
    reason = "the inputs of the run being repeated"
)]
fn repeated_timings(
    ctx: &GpuContext,
    culler: &Culler,
    scene: &GpuScene,
    depth: &wgpu::Texture,
    strategy: &Strategy,
    settings: &CullSettings,
    first: &CullOutput,
    passes: Option<u32>,
    args: &CullArgs,
) -> Result<String> {
    use std::fmt::Write as _;
    let n = args.repeat;
    // `passes`: those of `first`, or none without timestamp queries.
    let Some(passes) = passes else {
        return Ok("  (no GPU timings: the adapter has no timestamp queries)\n".into());
    };
    let most = manylights_lab::steady::max_runs(passes);
    if n > most {
        bail!(
            "invalid --repeat {n}: this strategy runs {passes} passes, and one timer holds {} \
             passes, so at most {most} runs",
            MAX_QUERIES / 2
        );
    }
    let s = manylights_lab::steady::steady_cull(
        ctx, culler, scene, depth, strategy, settings, first, passes, n,
    )?
    .expect("timestamps were there for the first run");
    let mut lines = format!("  {n} runs back to back (median per pass):\n");
    for (label, kind, ms) in &s.passes {
        writeln!(lines, "  {label:<28} {:>8} {ms:>10.3} ms", kind.as_str())?;
    }
    writeln!(
        lines,
        "  {:<28} {:>8} {:>10.3} ms",
        "total (median run)", "", s.total_ms
    )?;
    // The same runs again with one pair of timestamps around each run's passes, none between
    // them: the run as a frame waits for it, clears and gaps between passes included.
    if let Some(span) = s.span_ms {
        writeln!(
            lines,
            "  {:<28} {:>8} {span:>10.3} ms",
            "span (one timestamp pair)", ""
        )?;
    }
    Ok(lines)
}

fn main() -> std::process::ExitCode {
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
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
