//! `score`: another program's light lists against the exact per-pixel oracle
//! (`manylights_lab::score`; the format in docs/EXPERIMENTS.md, "Scoring another engine's
//! lists").

use std::path::PathBuf;

use anyhow::Result;
use manylights_cull::heatmap;
use manylights_lab::score::on_grid::cluster_on_grid;
use manylights_lab::score::{Frame, Grid, Lists, score};
use manylights_shade::image_out::write_atomic;

#[derive(clap::Args, Debug)]
pub(crate) struct ScoreArgs {
    /// The export the lists were made for (`cull --export DIR`, `render --export DIR`, or a
    /// cell of an experiment with `export: true`): its depth buffer, camera and lights.
    #[arg(long, value_name = "DIR")]
    pub(crate) export: PathBuf,
    /// The lists: a directory with grid.json, offsets.npy and indices.npy (and the light-id
    /// map grid.json names, if any).
    #[arg(long, value_name = "DIR")]
    pub(crate) lists: PathBuf,
    /// Where the score (score.json), each pixel's false negatives and lights evaluated beyond
    /// need (false_negatives.npy, extra.npy) and their heatmaps are written.
    #[arg(long, value_name = "DIR", default_value = "out/score")]
    pub(crate) out: PathBuf,
    /// Score this workbench's cluster test on the grid of LISTS/grid.json instead of the lists
    /// there: each cell's lights by the sphere (a spot's capped cone) against the cell's side
    /// planes and depth slice and the box of its frustum, in f64 (docs/EXPERIMENTS.md). The
    /// lists are written to OUT/lists in the same format.
    #[arg(long)]
    pub(crate) cluster_on_grid: bool,
}

pub(crate) fn run_score(args: &ScoreArgs) -> Result<()> {
    let frame = Frame::from_export(&args.export)?;
    let lists = if args.cluster_on_grid {
        let grid = Grid::load(&args.lists.join("grid.json"), frame.width, frame.height)?;
        let lists = cluster_on_grid(&frame, &grid);
        lists.write(&args.out.join("lists"))?;
        lists
    } else {
        Lists::load(&args.lists, frame.width, frame.height, frame.lights.len())?
    };
    let s = score(&frame, &lists);
    let m = &s.metrics;
    let (w, h) = (frame.width, frame.height);
    std::fs::create_dir_all(&args.out)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.out.display()))?;
    let missed_png = args.out.join("heatmap_false_negatives.png");
    let extra_png = args.out.join("heatmap_extra.png");
    for (path, counts) in [(&missed_png, &s.missed), (&extra_png, &s.extra)] {
        let max = counts.iter().copied().max().unwrap_or(0).max(1);
        let img = heatmap::pixels(counts, w, h, max);
        write_atomic(path, |f| {
            img.write_to(f, image::ImageFormat::Png)
                .map_err(|e| e.to_string())
        })?;
    }
    let files = s.write(&args.out, &frame, &lists)?;
    let source = if lists.grid.source.is_empty() {
        "lists".to_string()
    } else {
        lists.grid.source.clone()
    };
    println!(
        "{source}: {} cells ({} x {} x {}), {} lights, {w}x{h}",
        lists.grid.cells(),
        lists.grid.dims[0],
        lists.grid.dims[1],
        lists.grid.dims[2],
        frame.lights.len()
    );
    println!(
        "false negatives: {} (pixel, light) pairs at {} pixels",
        m.false_negatives,
        s.missed.iter().filter(|&&n| n > 0).count()
    );
    for &(x, y, l) in &s.first_misses {
        println!("  missed: light {l} at pixel ({x}, {y})");
    }
    let ratio = m
        .false_positive_ratio
        .map_or("-".to_string(), |r| format!("{r:.3}"));
    println!(
        "lights evaluated per light needed: {ratio}; lights per pixel {:.2} (needed {:.2}); longest list {}; lists {:.1} KiB",
        m.lights_per_pixel_mean,
        m.lights_needed_per_pixel_mean,
        m.max_lights_per_bin,
        lists.bytes() as f64 / 1024.0
    );
    let shown: Vec<String> = files
        .iter()
        .chain([&missed_png, &extra_png])
        .map(|p| p.display().to_string())
        .collect();
    println!("wrote {}", shown.join(", "));
    Ok(())
}

#[derive(clap::Args, Debug)]
pub(crate) struct ScoreChartArgs {
    /// A directory holding scores.csv.
    pub(crate) dir: PathBuf,
}

pub(crate) fn score_chart(dir: &std::path::Path) -> Result<()> {
    let path = manylights_lab::score::chart(dir)?;
    println!("chart: {}", path.display());
    Ok(())
}
