//! Paper-style reports of a run directory: `report.md` and `report.html` with SVG figures in
//! `figures/`, drawn with plotters and the embedded DejaVu Sans (no system fonts needed).
//!
//! Contents: the setup (adapter, driver, date, commit, the exact experiment file); a summary of
//! findings generated from the rows (the fastest conservative configuration at each light count
//! and where the winner changes; any false negatives or dropped lights); a results table; GPU
//! time against light count per configuration; per-pass stacked bars, raster and compute
//! labelled; speed against accuracy with the Pareto front marked; renders and lights-per-pixel
//! heatmaps.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::figures::{
    Axis, passes, register_font, series_key, shade_vs_lights, speed_accuracy, time_vs_lights,
};
use crate::results::{Row, load_rows};
use crate::{LabError, write_atomic};

mod page;
use page::{Page, html, markdown, results_table};

/// The distinct values of one field over the cells, in the order first seen: the value alone
/// when all cells agree, otherwise each with its number of cells ("a (22 cells), b (5 cells)").
pub(crate) fn distinct<'a>(values: impl IntoIterator<Item = &'a str>) -> String {
    let mut seen: Vec<(&str, usize)> = Vec::new();
    for v in values {
        match seen.iter_mut().find(|(s, _)| *s == v) {
            Some((_, n)) => *n += 1,
            None => seen.push((v, 1)),
        }
    }
    if seen.len() == 1 {
        return seen[0].0.to_string();
    }
    seen.iter()
        .map(|(v, n)| format!("{v} ({n} cell{})", if *n == 1 { "" } else { "s" }))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `YYYY-MM-DD HH:MM UTC` of a Unix time (civil-from-days, Howard Hinnant's algorithm).
pub fn utc(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let (h, m) = ((secs % 86_400) / 3600, (secs % 3600) / 60);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{d:02} {h:02}:{m:02} UTC")
}

pub(crate) fn fmt_opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("-".into(), |x| {
        if x.is_infinite() {
            "inf".into()
        } else {
            format!("{:.digits$}", x + 0.0) // `+ 0.0`: an empty sum's -0.0 shows as 0
        }
    })
}

/// The generated summary of findings.
/// What moving the lights cost, per light count, where cells moved them: the GPU animation
/// pass against an upload's copy and host time (medians over the cells).
fn moving_lights_summary(by_lights: &BTreeMap<u64, Vec<&Row>>) -> Vec<String> {
    let median = |v: Vec<f64>| crate::results::percentiles(&v).map(|p| p.0);
    let mut out = Vec::new();
    for (n, rs) in by_lights {
        let of = |update: &str, f: &dyn Fn(&Row) -> Option<f64>| {
            median(
                rs.iter()
                    .filter(|r| r.params.ends_with(&format!(";light_update={update}")))
                    .filter_map(|r| f(r))
                    .collect(),
            )
        };
        let animate = of("gpu", &|r| r.gpu_ms_light_update);
        let copy = of("upload", &|r| r.gpu_ms_light_update);
        let host = of("upload", &|r| r.cpu_ms_upload);
        let ms = |v: Option<f64>| v.map_or("-".to_owned(), |v| format!("{v:.3} ms"));
        if animate.is_some() || host.is_some() {
            out.push(format!(
                "At {n} lights, moving the lights took {} on the GPU (`lights.animate`), against {} of host work and {} of copy (`lights.upload`) to upload them (medians over the cells).",
                ms(animate),
                ms(host),
                ms(copy)
            ));
        }
    }
    out
}

fn summary(rows: &[Row]) -> Vec<String> {
    let mut out = Vec::new();
    let mut by_lights: BTreeMap<u64, Vec<&Row>> = BTreeMap::new();
    for r in rows {
        by_lights.entry(r.setting_lights()).or_default().push(r);
    }
    let mut prev: Option<String> = None;
    for (n, rs) in &by_lights {
        let exact: Vec<&Row> = rs
            .iter()
            .copied()
            .filter(|r| r.false_negatives.unwrap_or(0) == 0 && r.dropped_lights == 0)
            .collect();
        // Where every such cell has it, the frame in steady state (its geometry, then culling
        // and shading, back to back after the clock has risen) decides, or else culling and
        // shading in steady state: a single frame is timed with the host in the loop, at
        // whatever clock the GPU has fallen to (docs/BENCHMARKS.md).
        let all =
            |f: fn(&Row) -> Option<f64>| !exact.is_empty() && exact.iter().all(|r| f(r).is_some());
        let (measure, what): (fn(&Row) -> Option<f64>, _) = if all(|r| r.gpu_ms_frame_steady) {
            (
                |r| r.gpu_ms_frame_steady,
                "the frame in steady state, `gpu_ms_frame_steady`",
            )
        } else if all(|r| r.gpu_ms_cull_shade) {
            (
                |r| r.gpu_ms_cull_shade,
                "culling and shading in steady state, `gpu_ms_cull_shade`",
            )
        } else {
            (|r| r.gpu_ms_total, "a frame's GPU time")
        };
        let best = exact
            .iter()
            .filter_map(|r| Some((measure(r)?, *r)))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((t, r)) = best {
            let key = series_key(r);
            let mut line = format!(
                "At {n} lights the fastest configuration with no false negatives and no dropped lights is `{key}` ({t:.3} ms, {what})."
            );
            if let Some(p) = &prev {
                if *p != key {
                    line.push_str(&format!(" The winner changes here (crossover from `{p}`)."));
                }
            }
            prev = Some(key);
            out.push(line);
        }
    }
    out.extend(crate::budgets::findings(rows));
    out.extend(moving_lights_summary(&by_lights));
    out.extend(crate::forward_deferred::msaa_summary(rows));
    out.extend(crate::forward_deferred::materials_summary(rows));
    let fns: Vec<&Row> = rows
        .iter()
        .filter(|r| r.false_negatives.unwrap_or(0) > 0)
        .collect();
    if fns.is_empty() {
        if rows.iter().any(|r| r.false_negatives.is_some()) {
            out.push(
                "No configuration had false negatives against the exact per-pixel oracle.".into(),
            );
        }
    } else {
        for r in fns {
            out.push(format!(
                "`{}` had {} false negatives{}.",
                r.cell,
                r.false_negatives.unwrap_or(0),
                if r.dropped_lights > 0 {
                    format!(" ({} lights dropped by its capacity)", r.dropped_lights)
                } else {
                    String::new()
                }
            ));
        }
    }
    if let Some(r) = rows
        .iter()
        .filter_map(|r| Some((r.false_positive_ratio?, r)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
    {
        out.push(format!(
            "The tightest lists (lights evaluated / needed {:.2}) came from `{}`.",
            r.0, r.1.cell
        ));
    }
    if let Some((walked, r)) = rows
        .iter()
        .filter_map(|r| {
            Some((
                r.lights_walked_per_pixel_mean? / r.lights_needed_per_pixel_mean?,
                r,
            ))
        })
        .filter(|(x, _)| x.is_finite())
        .min_by(|a, b| a.0.total_cmp(&b.0))
    {
        out.push(format!(
            "The fewest lights walked by the shading per light needed ({walked:.2}; its lists hold {:.2}) came from `{}`.",
            r.lights_per_pixel_mean.unwrap_or(f64::NAN) / r.lights_needed_per_pixel_mean.unwrap_or(f64::NAN),
            r.cell
        ));
    }
    if rows
        .iter()
        .any(|r| r.adapter.contains("H100") || r.adapter.contains("H200"))
    {
        out.push(
            "Measured on an NVIDIA H100/H200, a compute chip with little raster hardware: raster passes (depth prepass, G-buffer, forward shading) are far slower relative to compute passes than on a consumer GPU, so raster and compute times are reported apart."
                .into(),
        );
    }
    if rows
        .iter()
        .any(|r| r.adapter.to_lowercase().contains("llvmpipe"))
    {
        out.push("Measured on lavapipe (a CPU rasteriser): the times say nothing about GPUs; accuracy and list metrics hold.".into());
    }
    out
}

/// The names of the experiment's cells that the run in `dir` should hold but has no row for
/// (a run stopped by `--time-limit` or killed; a shard's directory expects its own cells only).
fn cells_not_run(exp: &crate::Experiment, dir: &Path, rows: &[Row]) -> Vec<String> {
    let shard = std::fs::read_to_string(dir.join("meta.json"))
        .ok()
        .and_then(|m| serde_json::from_str::<serde_json::Value>(&m).ok())
        .and_then(|m| m.get("shard")?.as_str().map(str::to_owned))
        .and_then(|s| {
            let (i, n) = s.split_once('/')?;
            Some((i.parse::<usize>().ok()?, n.parse::<usize>().ok()?))
        });
    // By index: the runner refuses a run directory of another experiment file.
    let done: std::collections::BTreeSet<usize> = rows.iter().map(|r| r.index).collect();
    exp.cells()
        .into_iter()
        .filter(|c| shard.is_none_or(|(i, n)| c.index % n == i))
        .filter(|c| !done.contains(&c.index))
        .map(|c| c.name)
        .collect()
}

/// The setup's cell count, naming the cells that failed (with why) and those not run.
fn cells_line(done: usize, failed: &[Row], not_run: &[String]) -> String {
    if failed.is_empty() && not_run.is_empty() {
        return done.to_string();
    }
    let mut parts = Vec::new();
    if !failed.is_empty() {
        let why: Vec<&str> = failed.iter().filter_map(|r| r.error.as_deref()).collect();
        parts.push(format!("{} failed: {}", failed.len(), why.join("; ")));
    }
    if !not_run.is_empty() {
        parts.push(format!("{} not run: {}", not_run.len(), not_run.join("; ")));
    }
    format!(
        "{done} of {} ({})",
        done + failed.len() + not_run.len(),
        parts.join("; ")
    )
}

/// Writes `report.md`, `report.html` and `figures/` for the run in `dir`; returns the HTML path.
pub fn write_report(dir: &Path) -> Result<PathBuf, LabError> {
    register_font();
    let (failed, mut rows): (Vec<Row>, Vec<Row>) =
        load_rows(dir)?.into_iter().partition(|r| r.error.is_some());
    if rows.is_empty() {
        return Err(LabError::refused(
            dir.display().to_string(),
            "no finished cells to report on (run the experiment first)",
        ));
    }
    let exp_src = std::fs::read_to_string(dir.join("experiment.ron")).unwrap_or_default();
    let exp = crate::Experiment::parse(&exp_src, &dir.join("experiment.ron")).ok();
    let description = exp
        .as_ref()
        .map(|e| e.description.clone())
        .unwrap_or_default();
    if let Some(e) = &exp {
        crate::results::in_experiment_order(e, &mut rows);
    }
    crate::results::backfill(&mut rows);
    let not_run = exp.as_ref().map_or_else(Vec::new, |e| {
        cells_not_run(e, dir, &[&rows[..], &failed[..]].concat())
    });
    let figs = draw_figures(&rows, &dir.join("figures"))?;
    let name = rows[0].experiment.clone();
    // The rows say what ran each cell: a resumed run may mix commits (or machines), and the
    // setup lists each with its count (meta.json holds the last run's only).
    let adapter = distinct(rows.iter().map(|r| r.adapter.as_str()));
    let driver = distinct(rows.iter().map(|r| r.driver.as_str()));
    let commit = distinct(rows.iter().map(|r| r.commit.as_str()));
    let date = rows.iter().map(|r| r.finished_unix).max().unwrap_or(0);
    let findings = summary(&rows);
    let (head, table) = results_table(&rows);
    // The gallery: a cell a setting where the sweep has settings (the first with a render),
    // else the first cells with one; 12 at most.
    let mut settings = std::collections::BTreeSet::new();
    let images: Vec<(&Row, bool)> = rows
        .iter()
        .filter(|r| {
            dir.join("images")
                .join(format!("{}_render.png", r.id))
                .exists()
        })
        .filter(|r| r.sweep.setting.is_empty() || settings.insert(r.sweep.setting.clone()))
        .take(12)
        .map(|r| {
            let flip = dir.join("images").join(format!("{}_flip.png", r.id));
            (r, flip.exists())
        })
        .collect();

    let page = Page {
        name: &name,
        description: &description,
        adapter: &adapter,
        driver: &driver,
        commit: &commit,
        date,
        cells: cells_line(rows.len(), &failed, &not_run),
        exp_src: &exp_src,
        findings: &findings,
        head: &head,
        table: &table,
        figs: &figs,
        images: &images,
    };
    write_atomic(&dir.join("report.md"), markdown(&page).as_bytes())?;
    let path = dir.join("report.html");
    write_atomic(&path, html(&page).as_bytes())?;
    Ok(path)
}

/// Draws the report's figures into `figures`, each through a temporary file, and removes those
/// this run has none of; returns each drawn figure's file name and caption.
fn draw_figures(rows: &[Row], figures: &Path) -> Result<Vec<(&'static str, String)>, LabError> {
    std::fs::create_dir_all(figures).map_err(|e| LabError::Io {
        path: figures.display().to_string(),
        message: e.to_string(),
    })?;
    let mut figs: Vec<(&str, String)> = Vec::new();
    // Each figure is drawn to a temporary name and renamed, so no half-written SVG remains.
    let mut draw = |name: &'static str,
                    caption: &str,
                    f: &dyn Fn(&Path) -> Result<Option<crate::figures::Layout>, LabError>|
     -> Result<(), LabError> {
        let tmp = figures.join(format!(".{name}.tmp.svg"));
        if let Some(layout) = f(&tmp)? {
            std::fs::rename(&tmp, figures.join(name)).map_err(|e| LabError::Io {
                path: name.into(),
                message: e.to_string(),
            })?;
            // What a reader needs to name every point: the sweeps' orders, numbered points.
            let mut caption = caption.to_owned();
            if !layout.notes.is_empty() {
                caption += &format!(" {}.", layout.notes.join("; "));
            }
            figs.push((name, caption));
        } else {
            // A figure this run does not have: an earlier report's copy must not linger.
            let stale = figures.join(name);
            if stale.exists() {
                std::fs::remove_file(&stale).map_err(|e| LabError::Io {
                    path: stale.display().to_string(),
                    message: e.to_string(),
                })?;
            }
        }
        Ok(())
    };
    draw(
        "time_vs_lights.svg",
        "GPU time per frame against light count, one line per configuration.",
        &|p| time_vs_lights(rows, p),
    )?;
    draw(
        "passes.svg",
        "Per-pass GPU time of each cell: the geometry pass (raster), culling (compute) and shading.",
        &|p| passes(rows, p),
    )?;
    // The frame in steady state where every cell has it (see `summary`).
    let gpu: Axis<'_> = if rows.iter().all(|r| r.gpu_ms_frame_steady.is_some()) {
        ("frame, GPU ms (steady state)", &|r| r.gpu_ms_frame_steady)
    } else {
        ("GPU ms (median)", &|r| r.gpu_ms_total)
    };
    let frame: Axis<'_> = ("culling + shading, GPU ms (steady state)", &|r| {
        r.gpu_ms_cull_shade
    });
    let fp: Axis<'_> = ("false-positive ratio", &|r| r.false_positive_ratio);
    let error: Axis<'_> = ("mean FLIP vs reference", &|r| r.flip_mean);
    draw(
        "speed_fp.svg",
        "Speed against list quality: lights evaluated per light needed (1.0 is exact). A panel a setting; marker: the strategy; filled: deferred or visibility, open: forward. Black: each panel's Pareto front.",
        &|p| speed_accuracy(rows, p, gpu, fp),
    )?;
    draw(
        "speed_error.svg",
        "Speed against image error: mean FLIP against the brute-force reference with the same light ranges (what culling and shading lose, not the cut-off). A panel a setting; colour: the method family, a line through its sweep; marker: the strategy; filled: deferred or visibility, open: forward. Black: each panel's Pareto front.",
        &|p| speed_accuracy(rows, p, gpu, error),
    )?;
    draw(
        "frame_fp.svg",
        "The frame against list quality: culling and the shading pass that reads its lists, back to back as frames run (gpu_ms_cull_shade), against lights evaluated per light needed. A panel a setting; marker: the strategy; filled: deferred or visibility, open: forward. Black: each panel's Pareto front.",
        &|p| speed_accuracy(rows, p, frame, fp),
    )?;
    let flip_inf: Axis<'_> = ("mean FLIP vs infinite range", &|r| r.flip_mean_infinite);
    // A hierarchy's frame builds it too: its points carry the build
    // (`Row::hierarchy_build_ms`: in steady state where it was timed so).
    let hierarchy = rows.iter().any(|r| r.hierarchy_build_ms().is_some());
    let (frame_cost, built, with_build): (Axis<'_>, _, _) = if hierarchy {
        (
            (
                "culling + shading (+ hierarchy build), GPU ms (steady state)",
                &crate::tune::cost,
            ),
            " and, for the lighting grid hierarchy, its build each frame (gpu_ms_hierarchy_steady, in steady state; in earlier runs gpu_ms_hierarchy)",
            " with, for the lighting grid hierarchy, its build timed in it (gpu_ms_frame_build_steady; in earlier runs gpu_ms_hierarchy_steady, or gpu_ms_hierarchy, added)",
        )
    } else {
        (frame, "", "")
    };
    draw(
        "frame_infinite.svg",
        &format!(
            "Speed against accuracy against the light as it is: culling + shading in steady state (gpu_ms_cull_shade, one frame; an accumulated point costs this a frame, K times it for its image){built} against mean FLIP against the infinite-range reference (at the reference's exposure). A panel a setting; colour: the method family (radius cut-offs, stochastic light culling in one frame, accumulated, interleaved, the hierarchy), a line through each configuration's sweep; marker: the strategy; filled: deferred or visibility, open: forward. Black: each panel's Pareto front."
        ),
        &|p| speed_accuracy(rows, p, frame_cost, flip_inf),
    )?;
    if rows.iter().all(|r| r.gpu_ms_frame_steady.is_some()) {
        let whole: Axis<'_> = ("frame, GPU ms (steady state)", &|r| r.frame_with_build_ms());
        draw(
            "frame_steady_infinite.svg",
            &format!(
                "The whole frame against accuracy against the light as it is: the frame in steady state (gpu_ms_frame_steady: geometry, culling and shading){with_build} against mean FLIP against the infinite-range reference. A panel a setting; colour: the method family, a line through its sweep; marker: the strategy; filled: deferred or visibility, open: forward. Black: each panel's Pareto front."
            ),
            &|p| speed_accuracy(rows, p, whole, flip_inf),
        )?;
    }
    if rows.iter().any(|r| r.shadow.flip_mean_shadowed.is_some()) {
        let whole: Axis<'_> = ("frame, GPU ms (steady state)", &|r| r.frame_with_build_ms());
        let shadowed: Axis<'_> = ("mean FLIP vs the shadowed light", &|r| {
            r.shadow.flip_mean_shadowed
        });
        draw(
            "frame_shadowed.svg",
            &format!(
                "The whole frame against accuracy against the light as it arrives: the frame in steady state (gpu_ms_frame_steady){with_build} against mean FLIP against the shadowed infinite-range reference (flip_mean_shadowed, a ray from every pixel to every light). A panel a setting; colour: the method family, with shadows (`shadowed: `) a family apart, a line through its sweep; marker: the strategy; filled: deferred or visibility, open: forward. Black: each panel's Pareto front."
            ),
            &|p| speed_accuracy(rows, p, whole, shadowed),
        )?;
    }
    draw(
        "shade_vs_lights.svg",
        "What a loose list costs: the shading pass against the lights it evaluates per pixel, one point per cell.",
        &|p| shade_vs_lights(rows, p),
    )?;

    Ok(figs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_dates() {
        assert_eq!(utc(0), "1970-01-01 00:00 UTC");
        assert_eq!(utc(951_782_400), "2000-02-29 00:00 UTC");
        assert_eq!(utc(1_795_243_888), "2026-11-21 06:51 UTC");
    }

    #[test]
    fn distinct_values_counted_only_when_they_differ() {
        assert_eq!(distinct(["a", "a"]), "a");
        assert_eq!(distinct(["b", "a", "b"]), "b (2 cells), a (1 cell)");
        assert_eq!(distinct([]), "");
    }
}
