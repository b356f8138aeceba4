//! Scatter figures in small multiples, as papers draw speed against accuracy (Tokuyoshi and
//! Harada 2016: a panel a scene, a line a method; STYLE.md, "Figures"):
//!
//! - a panel a setting (the cell's `setting=` part, else what varies of scene, light count and
//!   resolution), every panel on the same axes, logarithmic where the values span a decade;
//! - a colour a method family (cut-off thresholds, stochastic light culling in one frame,
//!   accumulated, interleaved, ...), or, where a report has one family, a colour for each of
//!   the few other things its cells vary (MSAA, materials, ...);
//! - a line through each configuration's sweep in order (thresholds, error bounds), so one
//!   configuration reads as one curve; the caption lists the sweep values in that order;
//! - marker shape for the strategy, fill for the backend (filled: deferred or visibility; open:
//!   forward);
//!   where one strategy ran and colours are the families, shape for the few other things the
//!   cells vary (the material models, say);
//! - the Pareto front of each panel in black;
//! - one legend of at most [`MAX_LEGEND`] entries beside the panels; points that colour,
//!   shape, fill and a line cannot tell apart carry a number, listed in the caption.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::axes::{self, Scale};
use super::families::{family, grows_tighter};
use super::legend::{LABEL_CHARS, Mark, clip_label, clip_to, legend, legend_width};
use super::{Axis, FONT, Layout, PALETTE, err, pareto};
use crate::LabError;
use crate::cells::RADIUS_AXES;
use crate::results::Row;

/// The most entries a figure's legend holds.
pub(crate) const MAX_LEGEND: usize = 12;

/// A panel's size in pixels, axes included.
const PANEL: (u32, u32) = (420, 320);
/// The strip above the panels that holds the figure's title.
const TITLE_H: u32 = 34;

/// A marker shape: the strategy a point's lists came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Shape {
    Circle,
    Square,
    Diamond,
    TriangleUp,
    TriangleDown,
    Cross,
}

impl Shape {
    fn of_strategy(strategy: &str) -> Shape {
        match strategy {
            "tiled_gather" => Shape::Circle,
            "tiled_scatter" => Shape::TriangleUp,
            "depth_mask" => Shape::Square,
            "clustered" => Shape::Diamond,
            "zbin" => Shape::TriangleDown,
            _ => Shape::Cross,
        }
    }

    fn name(strategy: &str) -> String {
        match strategy {
            "tiled_gather" => "tiled gather".into(),
            "tiled_scatter" => "tiled scatter".into(),
            "depth_mask" => "2.5D depth masks".into(),
            "clustered" => "clusters".into(),
            "zbin" => "z-binning".into(),
            "none" | "" => "no culling".into(),
            s => s.replace('_', " "),
        }
    }
}

/// Draws a marker of `shape` centred at `(x, y)` (pixels of `area`), `r` pixels in radius,
/// filled with `colour` or open (white inside, `colour` around).
pub(super) fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x, y): (i32, i32),
    r: i32,
    shape: Shape,
    colour: RGBColor,
    filled: bool,
) -> Result<(), LabError> {
    let pts: Vec<(i32, i32)> = match shape {
        Shape::Circle => {
            let fill = if filled {
                colour.filled()
            } else {
                WHITE.filled()
            };
            area.draw(&Circle::new((x, y), r, fill)).map_err(err)?;
            return area
                .draw(&Circle::new((x, y), r, colour.stroke_width(2)))
                .map_err(err);
        }
        Shape::Square => vec![
            (x - r, y - r),
            (x + r, y - r),
            (x + r, y + r),
            (x - r, y + r),
        ],
        Shape::Diamond => vec![
            (x, y - r - 1),
            (x + r + 1, y),
            (x, y + r + 1),
            (x - r - 1, y),
        ],
        Shape::TriangleUp => vec![(x, y - r - 1), (x + r + 1, y + r), (x - r - 1, y + r)],
        Shape::TriangleDown => vec![(x - r - 1, y - r), (x + r + 1, y - r), (x, y + r + 1)],
        Shape::Cross => {
            for (a, b) in [
                ((x - r, y - r), (x + r, y + r)),
                ((x - r, y + r), (x + r, y - r)),
            ] {
                area.draw(&PathElement::new(vec![a, b], colour.stroke_width(2)))
                    .map_err(err)?;
            }
            return Ok(());
        }
    };
    let fill = if filled {
        colour.filled()
    } else {
        WHITE.filled()
    };
    area.draw(&Polygon::new(pts.clone(), fill)).map_err(err)?;
    let mut ring = pts.clone();
    ring.push(pts[0]);
    area.draw(&PathElement::new(ring, colour.stroke_width(2)))
        .map_err(err)
}

/// Parameters that only say which panel a cell is in, or its strategy and backend (shown by
/// marker and fill).
fn is_panel_or_marker(name: &str) -> bool {
    [
        "setting", "scene", "lights", "seed", "variant", "strategy", "backend",
    ]
    .contains(&name)
}

/// The row's parameters but its light range's, as `name=value` parts.
fn without_range(r: &Row) -> impl Iterator<Item = (&str, String)> {
    r.sweep
        .parameters
        .iter()
        .filter(|(k, _)| !RADIUS_AXES.contains(&k.as_str()))
        .map(|(k, v)| (k.as_str(), format!("{k}={v}")))
}

/// What a point is, for drawing.
struct Pt<'r> {
    row: &'r Row,
    x: f64,
    y: f64,
    panel: usize,
    colour: usize,
    shape: Shape,
    /// Deferred backends' points are filled; forward's and naive forward's open.
    filled: bool,
    /// The method family ([`family`]) and the point's place in its sweep.
    family: String,
    order: Option<f64>,
    /// Points of one line: the same panel and cell name but for the sweep's value.
    line: String,
}

/// What the colours and shapes of a figure's points stand for, in legend order.
struct Keys {
    colours: Vec<String>,
    /// A label and shape each: the strategies', or the other things the cells vary.
    shapes: Vec<(String, Shape)>,
    /// Whether filled (deferred) points, open ones, or both are drawn.
    fills: BTreeSet<bool>,
}

/// A figure's title and axes; `front`: draw each panel's Pareto front (smaller is better on
/// both axes).
pub(crate) struct Spec<'a> {
    pub(crate) title: &'a str,
    pub(crate) x: Axis<'a>,
    pub(crate) y: Axis<'a>,
    pub(crate) front: bool,
}

/// The panels of `rows`: each row's panel index and the panels' titles.
fn panels_of(rows: &[&Row]) -> (Vec<usize>, Vec<String>) {
    let setting = |r: &Row| (!r.sweep.setting.is_empty()).then(|| r.sweep.setting.clone());
    let scene = |r: &Row| {
        r.sweep
            .parameters
            .get("scene")
            .map_or_else(|| r.scene.clone(), String::clone)
    };
    let lights = |r: &Row| format!("{} lights", r.setting_lights());
    let res = |r: &Row| format!("{}x{}", r.width, r.height);
    let varies =
        |f: &dyn Fn(&Row) -> String| rows.iter().map(|r| f(r)).collect::<BTreeSet<_>>().len() > 1;
    let (vs, vl, vr) = (varies(&scene), varies(&lights), varies(&res));
    let key = |r: &Row| -> String {
        if let Some(s) = setting(r) {
            return s;
        }
        let mut parts = Vec::new();
        if vs {
            parts.push(scene(r));
        }
        if vl {
            parts.push(lights(r));
        }
        if vr {
            parts.push(res(r));
        }
        parts.join(", ")
    };
    let mut titles: Vec<String> = Vec::new();
    let idx = rows
        .iter()
        .map(|r| {
            let k = key(r);
            titles.iter().position(|t| *t == k).unwrap_or_else(|| {
                titles.push(k);
                titles.len() - 1
            })
        })
        .collect();
    (idx, titles)
}

/// Draws `spec` over `rows` into `path` (written whole, or not at all); `None` where fewer
/// than two rows have both values.
pub(crate) fn draw(rows: &[Row], path: &Path, spec: &Spec<'_>) -> Result<Option<Layout>, LabError> {
    let shown: Vec<&Row> = rows
        .iter()
        .filter(|r| {
            matches!(((spec.x.1)(r), (spec.y.1)(r)), (Some(x), Some(y)) if x.is_finite() && y.is_finite())
        })
        .collect();
    if shown.len() < 2 {
        return Ok(None);
    }
    let (panel_of, titles) = panels_of(&shown);
    let (pts, keys) = points(&shown, &panel_of, spec);
    let entries = legend_entries(&keys, spec.front);
    let numbered = numbered(&pts);
    let labels: Vec<String> = entries.iter().map(|e| e.0.clone()).collect();
    let lw = legend_width(&labels);
    let n = titles.len() as u32;
    let cols = match n {
        1..=3 => n,
        4 => 2,
        _ => 3,
    };
    let grid_rows = n.div_ceil(cols);
    let title_w = (spec.title.chars().count() as u32) * 8 + 40;
    let width = (cols * PANEL.0 + lw).max(title_w);
    let legend_h = 60 + 16 * entries.len() as u32;
    let height = (TITLE_H + grid_rows * PANEL.1).max(legend_h);
    let axes = (
        Scale::fit_log(pts.iter().map(|p| p.x)),
        Scale::fit_log(pts.iter().map(|p| p.y)),
    );
    let mut svg = String::new();
    let mut layout = Layout::default();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (head, body) = root.split_vertically(TITLE_H);
        let style = TextStyle::from((FONT, 15).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
        head.draw(&Text::new(
            spec.title.to_owned(),
            (12, TITLE_H as i32 / 2),
            style,
        ))
        .map_err(err)?;
        let (plots, side) = body.split_horizontally(cols * PANEL.0);
        let areas = plots.split_evenly((grid_rows as usize, cols as usize));
        for (k, title) in titles.iter().enumerate() {
            let panel = Panel {
                index: k,
                title,
                axes,
            };
            draw_panel(&root, &areas[k], &panel, &pts, spec, &numbered, &mut layout)?;
        }
        layout.legend = Some(legend(&side, &entries)?);
        root.present().map_err(err)?;
    }
    layout.notes = notes(&pts, &numbered);
    layout.legend_entries = entries.len();
    super::write_svg(path, &svg, layout.legend)?;
    Ok(Some(layout))
}

/// The cell's parameters less its light range and those that say its panel, strategy or
/// backend: what else the cells vary (materials, MSAA, ...).
fn rest(r: &Row) -> String {
    without_range(r)
        .filter(|(k, _)| !is_panel_or_marker(k))
        .map(|(_, p)| p)
        .collect::<Vec<_>>()
        .join(",")
}

/// Each row's point and what its colour and shape stand for. Colours: the method families
/// where there are several; else the few other things the cells vary; else one colour.
/// Shapes: the strategies where there are several; else, where colours are the families, the
/// other things the cells vary if few enough.
fn points<'r>(shown: &[&'r Row], panel_of: &[usize], spec: &Spec<'_>) -> (Vec<Pt<'r>>, Keys) {
    let families: Vec<(String, Option<f64>)> = shown.iter().map(|r| family(r)).collect();
    let distinct_families: BTreeSet<&String> = families.iter().map(|f| &f.0).collect();
    let strategies: BTreeSet<&str> = shown.iter().map(|r| r.strategy.as_str()).collect();
    let fills: BTreeSet<bool> = shown.iter().map(|r| is_filled(r)).collect();
    let room = MAX_LEGEND - strategies.len() - fills.len() - usize::from(spec.front);
    let rests: Vec<String> = shown
        .iter()
        .map(|r| rest(r))
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    let colour_by_family =
        distinct_families.len() > 1 || !(rests.len() > 1 && rests.len() <= room.min(PALETTE.len()));
    let shape_by_rest = colour_by_family
        && strategies.len() == 1
        && rests.len() > 1
        && rests.len() <= SHAPES.len()
        && distinct_families.len() + rests.len() + fills.len() + usize::from(spec.front)
            <= MAX_LEGEND;
    let shapes: Vec<(String, Shape)> = if shape_by_rest {
        rests.iter().cloned().zip(SHAPES).collect()
    } else {
        strategies
            .iter()
            .map(|s| (Shape::name(s), Shape::of_strategy(s)))
            .collect()
    };
    let mut colours: Vec<String> = Vec::new();
    let mut pts = Vec::with_capacity(shown.len());
    for (i, r) in shown.iter().enumerate() {
        let key = if colour_by_family {
            families[i].0.clone()
        } else {
            rest(r)
        };
        let colour = colours.iter().position(|k| *k == key).unwrap_or_else(|| {
            colours.push(key);
            colours.len() - 1
        });
        let shape = if shape_by_rest {
            let k = rest(r);
            SHAPES[rests.iter().position(|x| *x == k).unwrap_or(0)]
        } else {
            Shape::of_strategy(&r.strategy)
        };
        let cell: Vec<String> = without_range(r).map(|(_, p)| p).collect();
        pts.push(Pt {
            row: r,
            x: (spec.x.1)(r).unwrap_or(0.0),
            y: (spec.y.1)(r).unwrap_or(0.0),
            panel: panel_of[i],
            colour,
            shape,
            filled: is_filled(r),
            line: format!("{}|{}|{}", panel_of[i], families[i].0, cell.join(",")),
            family: families[i].0.clone(),
            order: families[i].1,
        });
    }
    (
        pts,
        Keys {
            colours,
            shapes,
            fills,
        },
    )
}

/// The legend: colours, then shapes, then fills, then the front.
fn legend_entries(keys: &Keys, front: bool) -> Vec<(String, Mark)> {
    let mut entries: Vec<(String, Mark)> = keys
        .colours
        .iter()
        .enumerate()
        .map(|(c, k)| (k.clone(), Mark::Line(palette(c))))
        .collect();
    for (label, shape) in &keys.shapes {
        entries.push((label.clone(), Mark::Shape(*shape, GREY_MARK, true)));
    }
    for &filled in &keys.fills {
        let label = if filled {
            "filled: deferred or visibility"
        } else {
            "open: forward (or no culling)"
        };
        entries.push((label.into(), Mark::Shape(Shape::Circle, GREY_MARK, filled)));
    }
    if front {
        entries.push(("Pareto front (per panel)".into(), Mark::Line(BLACK)));
    }
    entries
}

/// The number of each point nothing else tells apart (panel, colour, shape, fill, and a place
/// along a drawn line): point index to its number, from 1.
fn numbered(pts: &[Pt<'_>]) -> BTreeMap<usize, usize> {
    let mut line_sizes: BTreeMap<&str, usize> = BTreeMap::new();
    for p in pts.iter().filter(|p| p.order.is_some()) {
        *line_sizes.entry(p.line.as_str()).or_default() += 1;
    }
    let on_drawn_line = |p: &Pt<'_>| p.order.is_some() && line_sizes[p.line.as_str()] > 1;
    let mut seen: BTreeMap<(usize, usize, Shape, bool, &str), Vec<usize>> = BTreeMap::new();
    for (i, p) in pts.iter().enumerate() {
        let line = if on_drawn_line(p) {
            p.line.as_str()
        } else {
            ""
        };
        seen.entry((p.panel, p.colour, p.shape, p.filled, line))
            .or_default()
            .push(i);
    }
    let mut numbered = BTreeMap::new();
    for group in seen.values().filter(|g| g.len() > 1) {
        // A line's points are told apart by their order along it, unless two share a sweep
        // value.
        let orders: BTreeSet<u64> = group
            .iter()
            .filter_map(|&i| pts[i].order.map(f64::to_bits))
            .collect();
        if group.iter().all(|&i| on_drawn_line(&pts[i])) && orders.len() == group.len() {
            continue;
        }
        for &i in group {
            let n = numbered.len() + 1;
            numbered.insert(i, n);
        }
    }
    numbered
}

/// One panel: its index among the panels, its title and the axes every panel shares.
struct Panel<'a> {
    index: usize,
    title: &'a str,
    axes: (Scale, Scale),
}

/// Draws panel `panel` into `area`: its axes, its lines through each sweep, its Pareto front
/// and its points (with their numbers), recording where the points landed in `layout`.
fn draw_panel<'b>(
    root: &DrawingArea<SVGBackend<'b>, Shift>,
    area: &DrawingArea<SVGBackend<'b>, Shift>,
    panel: &Panel<'_>,
    pts: &[Pt<'_>],
    spec: &Spec<'_>,
    numbered: &BTreeMap<usize, usize>,
    layout: &mut Layout,
) -> Result<(), LabError> {
    let (xs, ys) = panel.axes;
    let k = panel.index;
    let chart = axes::chart(
        area,
        &clip_label(panel.title),
        (xs, spec.x.0),
        (ys, spec.y.0),
    )?;
    let at = |x: f64, y: f64| chart.backend_coord(&(xs.map(x), ys.map(y)));
    // Lines first, markers over them.
    let mut lines: BTreeMap<&str, Vec<&Pt<'_>>> = BTreeMap::new();
    for p in pts.iter().filter(|p| p.panel == k && p.order.is_some()) {
        lines.entry(p.line.as_str()).or_default().push(p);
    }
    for line in lines.values_mut().filter(|l| l.len() > 1) {
        // From the loosest bound to the tightest: thresholds and error bounds fall, alpha rises.
        let rising = grows_tighter(&line[0].family);
        line.sort_by(|a, b| {
            let (a, b) = (a.order.unwrap_or(0.0), b.order.unwrap_or(0.0));
            if rising {
                a.total_cmp(&b)
            } else {
                b.total_cmp(&a)
            }
        });
        let c = palette(line[0].colour);
        let path: Vec<(i32, i32)> = line.iter().map(|p| at(p.x, p.y)).collect();
        root.draw(&PathElement::new(path, c.mix(0.7).stroke_width(1)))
            .map_err(err)?;
    }
    if spec.front {
        let own: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.panel == k)
            .map(|p| (p.x, p.y))
            .collect();
        let front: Vec<(i32, i32)> = pareto(&own).into_iter().map(|(x, y)| at(x, y)).collect();
        root.draw(&PathElement::new(front.clone(), BLACK.stroke_width(2)))
            .map_err(err)?;
        for p in front {
            root.draw(&Circle::new(p, 8, BLACK.stroke_width(1)))
                .map_err(err)?;
        }
    }
    let number_style =
        TextStyle::from((FONT, 10).into_font()).pos(Pos::new(HPos::Left, VPos::Bottom));
    for (i, p) in pts.iter().enumerate().filter(|(_, p)| p.panel == k) {
        let c = at(p.x, p.y);
        draw_marker(root, c, 4, p.shape, palette(p.colour), p.filled)?;
        if let Some(n) = numbered.get(&i) {
            root.draw(&Text::new(
                n.to_string(),
                (c.0 + 5, c.1 - 3),
                number_style.clone(),
            ))
            .map_err(err)?;
        }
        layout.points.push(c);
    }
    Ok(())
}

/// What the caption must add: each family's sweep values in the order its lines run, and
/// the numbered points' cells.
fn notes(pts: &[Pt<'_>], numbered: &BTreeMap<usize, usize>) -> Vec<String> {
    let mut sweeps: BTreeMap<&str, BTreeSet<u64>> = BTreeMap::new();
    for p in pts {
        if let Some(v) = p.order {
            sweeps
                .entry(p.family.as_str())
                .or_default()
                .insert(v.to_bits());
        }
    }
    let mut notes = Vec::new();
    for (family, values) in &sweeps {
        let mut v: Vec<f64> = values.iter().map(|b| f64::from_bits(*b)).collect();
        if grows_tighter(family) {
            v.sort_by(f64::total_cmp);
        } else {
            v.sort_by(|a, b| b.total_cmp(a));
        }
        let what = if family.starts_with("stochastic") {
            "error bounds"
        } else if family.starts_with("fixed") {
            "radii"
        } else if grows_tighter(family) {
            "alpha"
        } else {
            "thresholds"
        };
        notes.push(format!(
            "{family}: {what} {} (along each line, left to right as drawn)",
            v.iter()
                .map(|x| format!("{x}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    for (i, n) in numbered {
        notes.push(format!(
            "point {n}: {}",
            clip_to(&pts[*i].row.cell, LABEL_CHARS * 2)
        ));
    }
    notes
}

/// The colour of colour key `c`.
fn palette(c: usize) -> RGBColor {
    PALETTE[c % PALETTE.len()]
}

/// The shapes in the order other keys than the strategy take them.
const SHAPES: [Shape; 6] = [
    Shape::Circle,
    Shape::Square,
    Shape::Diamond,
    Shape::TriangleUp,
    Shape::TriangleDown,
    Shape::Cross,
];

/// Grey: the legend's markers for shape and fill, whose colour means nothing.
const GREY_MARK: RGBColor = RGBColor(90, 90, 90);

/// The points of backends that light in a compute pass (deferred, the visibility buffer) are
/// filled; forward's and naive forward's open. Deferred and visibility points that nothing else
/// tells apart are numbered in the caption.
fn is_filled(r: &Row) -> bool {
    r.backend.starts_with("deferred") || r.backend == "visibility"
}
