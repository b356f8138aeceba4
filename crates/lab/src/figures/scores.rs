//! The referee's chart (`manylights score-chart`): every list source of every setting, lights
//! evaluated per light needed against the lists' memory, in small multiples (a panel a
//! setting, the same rules as the speed-accuracy charts): colour for who made the lists (the
//! engine, its second (GPU) clusterer, this workbench's cluster test on the engine's cells, this
//! workbench's strategies),
//! shape for the grid, a short label beside each point, a red ring around a source that misses
//! lights. Where an engine's GPU clusterer is scored too, each setting is a row of two panels,
//! the CPU clusterer's sources and the GPU clusterer's, each beside this workbench's strategies
//! on the same axes: the two clusterers' knobs lie close together and would crowd one panel.

use std::collections::BTreeMap;
use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::axes::{self, Scale};
use super::legend::{Mark, legend, legend_width};
use super::panels::{Shape, draw_marker};
use super::{FONT, Layout, PALETTE, err, write_svg};
use crate::LabError;

/// One row of `scores.csv`: what the chart needs.
#[derive(Clone, Debug)]
pub(crate) struct ScoreRow {
    pub(crate) setting: String,
    pub(crate) source: String,
    pub(crate) false_negatives: u64,
    pub(crate) evaluated_per_needed: f64,
    pub(crate) list_kib: f64,
}

/// Reads `scores.csv` (scripts/referee-bevy.sh's columns), naming the file and the column
/// that is missing or not a number.
pub(crate) fn read(path: &Path) -> Result<Vec<ScoreRow>, LabError> {
    let bad = |m: String| LabError::Io {
        path: path.display().to_string(),
        message: m,
    };
    let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let col = |name: &str| {
        head.iter()
            .position(|h| *h == name)
            .ok_or_else(|| bad(format!("no column `{name}` (columns: {})", head.join(", "))))
    };
    let (cs, cu, cf, ce, ck) = (
        col("setting")?,
        col("source")?,
        col("false_negatives")?,
        col("evaluated_per_needed")?,
        col("list_kib")?,
    );
    let mut rows = Vec::new();
    for (i, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        // The grid column may hold commas inside quotes: fields are taken from both ends.
        let f = split_csv(line);
        let num = |k: usize, name: &str| -> Result<f64, LabError> {
            f.get(k)
                .and_then(|v| v.parse::<f64>().ok())
                .ok_or_else(|| bad(format!("line {}: `{name}` is not a number", i + 2)))
        };
        rows.push(ScoreRow {
            setting: f.get(cs).cloned().unwrap_or_default(),
            source: f.get(cu).cloned().unwrap_or_default(),
            false_negatives: num(cf, "false_negatives")? as u64,
            evaluated_per_needed: num(ce, "evaluated_per_needed")?,
            list_kib: num(ck, "list_kib")?,
        });
    }
    if rows.is_empty() {
        return Err(bad("no scores".into()));
    }
    Ok(rows)
}

/// The fields of one CSV line (double quotes around a field that holds commas).
fn split_csv(line: &str) -> Vec<String> {
    let (mut out, mut cur, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(std::mem::take(&mut cur)),
            c => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// Who made a source's lists: its colour and legend name. Sources are named
/// `manylights-on-GRID`, `manylights-STRATEGY`, `ENGINE-gpu-GRID` or `ENGINE-GRID`.
fn maker(source: &str) -> (usize, &'static str) {
    if source.starts_with("manylights-on-") {
        (2, "this workbench's cluster test on the engine's cells")
    } else if source.starts_with("manylights-") {
        (1, "this workbench's strategies")
    } else if source.split('-').nth(1) == Some("gpu") {
        (4, "the engine's GPU clusterer")
    } else {
        (0, "the engine")
    }
}

/// Whether `maker`'s colour is an engine's clusterer (its knobs are numbered in the caption).
fn is_engine(colour: usize) -> bool {
    colour == 0 || colour == 4
}

/// The panels, in order: (title, setting, which clusterer: None for all sources, Some(gpu)
/// for one engine clusterer's sources beside this workbench's).
fn panels<'a>(settings: &[&'a str], paired: bool) -> Vec<(String, &'a str, Option<bool>)> {
    let mut out = Vec::new();
    for s in settings {
        if paired {
            out.push((format!("{s}: CPU clusterer"), *s, Some(false)));
            out.push((format!("{s}: GPU clusterer"), *s, Some(true)));
        } else {
            out.push(((*s).to_string(), *s, None));
        }
    }
    out
}

/// Whether a source is drawn in a panel of `clusterer` (see `panels`).
fn in_panel(source: &str, clusterer: Option<bool>) -> bool {
    match (clusterer, maker(source).0) {
        (None, _) | (_, 1) => true,
        (Some(gpu), c) => gpu == (c == 4),
    }
}

/// A source's grid: its marker and legend name; `label`: the short text beside the point.
fn grid_of(source: &str) -> (Shape, &'static str, String) {
    let s = source
        .trim_start_matches("manylights-on-")
        .trim_start_matches("manylights-");
    let tail = s.split_once('-').map_or(s, |(_, t)| t);
    // An engine's second clusterer: ENGINE-gpu-GRID.
    let tail = tail.strip_prefix("gpu-").unwrap_or(tail);
    if tail == "default" {
        (Shape::Square, "the engine's default grid", "default".into())
    } else if tail.starts_with("xyz") {
        (
            Shape::Circle,
            "a fixed XYZ grid",
            tail.trim_start_matches("xyz-").into(),
        )
    } else if s.starts_with("clusters") {
        (Shape::Diamond, "this workbench's clusters", s.into())
    } else if s.starts_with("gather") {
        (Shape::TriangleDown, "tiled gather", s.into())
    } else {
        (Shape::TriangleUp, "one of the engine's knobs", tail.into())
    }
}

const PANEL: (u32, u32) = (460, 340);
const COLUMNS: u32 = 3;
const TITLE_H: u32 = 34;
const CAPTION_H: u32 = 30;
const MISS: RGBColor = RGBColor(214, 39, 40);

/// Draws the chart of `rows` into `path` (written whole or not at all).
pub(crate) fn draw(rows: &[ScoreRow], path: &Path) -> Result<Layout, LabError> {
    super::register_font();
    let mut settings: Vec<&str> = Vec::new();
    for r in rows {
        if !settings.contains(&r.setting.as_str()) {
            settings.push(&r.setting);
        }
    }
    let shown: Vec<&ScoreRow> = rows
        .iter()
        .filter(|r| r.list_kib > 0.0 && r.evaluated_per_needed > 0.0)
        .collect();
    let x = Scale::fit_log(shown.iter().map(|r| r.list_kib));
    let y = Scale::fit_log(shown.iter().map(|r| r.evaluated_per_needed));
    // The legend: makers by colour, grids by shape, and the ring.
    let mut entries: Vec<(String, Mark)> = Vec::new();
    let mut makers = BTreeMap::new();
    let mut grids = BTreeMap::new();
    for r in &shown {
        let (c, name) = maker(&r.source);
        makers.insert(c, name);
        let (shape, name, _) = grid_of(&r.source);
        grids.insert(shape, name);
    }
    for (c, name) in &makers {
        entries.push(((*name).into(), Mark::Block(PALETTE[*c])));
    }
    for (shape, name) in &grids {
        entries.push((
            (*name).into(),
            Mark::Shape(*shape, RGBColor(90, 90, 90), true),
        ));
    }
    if shown.iter().any(|r| r.false_negatives > 0) {
        entries.push((
            "red ring: misses lights (false negatives)".into(),
            Mark::Line(MISS),
        ));
    }
    // The knobs are numbered in the order they first appear, the same number in every panel,
    // and named in the caption: their points lie close together, where labels would overlap.
    let mut knobs: Vec<String> = Vec::new();
    for r in &shown {
        let (shape, _, text) = grid_of(&r.source);
        if shape == Shape::TriangleUp && is_engine(maker(&r.source).0) && !knobs.contains(&text) {
            knobs.push(text);
        }
    }
    let caption = (!knobs.is_empty()).then(|| {
        let named: Vec<String> = knobs
            .iter()
            .enumerate()
            .map(|(i, k)| format!("{} {k}", i + 1))
            .collect();
        format!("The engine's knobs (triangles, numbered): {}. Green points: the same grids as the blue square and circle.", named.join(", "))
    });
    let labels: Vec<String> = entries.iter().map(|e| e.0.clone()).collect();
    let lw = legend_width(&labels);
    let paired = makers.contains_key(&4);
    let panels = panels(&settings, paired);
    let columns = if paired { 2 } else { COLUMNS };
    let rows_n = (panels.len() as u32).div_ceil(columns);
    let caption_h = if caption.is_some() { CAPTION_H } else { 0 };
    let (w, h) = (
        PANEL.0 * columns + lw,
        TITLE_H + PANEL.1 * rows_n + caption_h,
    );
    let mut svg = String::new();
    let mut layout = Layout::default();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (top, body) = root.split_vertically(TITLE_H);
        top.draw(&Text::new(
            "Lights evaluated per light needed against the lists' memory, by list source",
            (10, 10),
            (FONT, 15).into_font(),
        ))
        .map_err(err)?;
        let (body, bottom) = body.split_vertically(PANEL.1 * rows_n);
        if let Some(c) = &caption {
            bottom
                .draw(&Text::new(c.as_str(), (10, 8), (FONT, 12).into_font()))
                .map_err(err)?;
        }
        let (plots, side) = body.split_horizontally(PANEL.0 * columns);
        let areas = plots.split_evenly((rows_n as usize, columns as usize));
        for (k, (title, setting, clusterer)) in panels.iter().enumerate() {
            let area = &areas[k];
            let chart = axes::chart(
                area,
                title,
                (x, "lists, KiB"),
                (y, "lights evaluated / needed"),
            )?;
            let (bx, by) = area.get_base_pixel();
            let label =
                TextStyle::from((FONT, 10).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
            for r in shown
                .iter()
                .filter(|r| r.setting == *setting && in_panel(&r.source, *clusterer))
            {
                let (px, py) =
                    chart.backend_coord(&(x.map(r.list_kib), y.map(r.evaluated_per_needed)));
                let (lx, ly) = (px - bx, py - by);
                let (c, _) = maker(&r.source);
                let (shape, _, text) = grid_of(&r.source);
                if r.false_negatives > 0 {
                    area.draw(&Circle::new((lx, ly), 9, MISS.stroke_width(2)))
                        .map_err(err)?;
                }
                draw_marker(area, (lx, ly), 5, shape, PALETTE[c], true)?;
                let text = match knobs.iter().position(|k| *k == text) {
                    Some(i) if is_engine(c) => (i + 1).to_string(),
                    // This workbench's test on the engine's cells: colour and shape say it.
                    _ if c == 2 => String::new(),
                    _ => text,
                };
                if !text.is_empty() {
                    area.draw(&Text::new(text, (lx + 8, ly - 8), label.clone()))
                        .map_err(err)?;
                }
                layout.points.push((px, py));
            }
        }
        let b = legend(&side, &entries)?;
        layout.legend = Some(b);
        layout.legend_entries = entries.len();
        root.present().map_err(err)?;
    }
    write_svg(path, &svg, layout.legend)?;
    Ok(layout)
}
