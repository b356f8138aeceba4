//! The report's figures, drawn with plotters into SVG with the embedded DejaVu Sans (no system
//! fonts needed): GPU time against light count per configuration, per-pass stacked bars (raster
//! and compute labelled, every bar named), and speed against accuracy with the Pareto front
//! marked. As a paper's figures: legends beside the data, never over it; axes fitted to the
//! points, logarithmic where the values span decades.

use std::collections::BTreeMap;
use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::LabError;
use crate::results::Row;
use manylights_gpu::timing::Category;

mod axes;
mod families;
mod legend;
pub(crate) mod panels;
pub(crate) mod scores;

use axes::Scale;
pub(crate) use legend::Layout;
use legend::{Mark, clip_label, legend, legend_width};

const FONT: &str = "sans-serif";

pub(crate) fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../../assets/DejaVuSans.ttf");
        // Registered under the family every figure asks for; failure only means plotters'
        // own font path is used.
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, bytes);
    });
}

fn err(e: impl std::fmt::Display) -> LabError {
    LabError::Figure(e.to_string())
}

const PALETTE: [RGBColor; 12] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(31, 31, 120),
    RGBColor(184, 134, 11),
];

/// Writes a figure drawn into `svg` to `path`, through a temporary file and a rename, with the
/// legend's box marked for checks that read the SVG (an invisible `rect` of class
/// `legend-box`: tests count the text drawn inside it).
pub(crate) fn write_svg(
    path: &Path,
    svg: &str,
    legend: Option<(i32, i32, i32, i32)>,
) -> Result<(), LabError> {
    let mut out = svg.to_owned();
    if let (Some((x0, y0, x1, y1)), Some(end)) = (legend, out.rfind("</svg>")) {
        out.insert_str(
            end,
            &format!(
                "<rect class=\"legend-box\" x=\"{x0}\" y=\"{y0}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"none\"/>\n",
                x1 - x0,
                y1 - y0
            ),
        );
    }
    crate::write_atomic(path, out.as_bytes())
}

/// The configuration of a row without its light count: one series of the scaling figure.
pub(crate) fn series_key(r: &Row) -> String {
    let parts: Vec<String> = r
        .sweep
        .parameters
        .iter()
        .filter(|(k, _)| *k != "lights" && *k != "seed")
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    if parts.is_empty() {
        format!("{}+{}", r.backend, r.strategy)
    } else {
        parts.join(",")
    }
}

pub(crate) fn time_vs_lights(rows: &[Row], path: &Path) -> Result<Option<Layout>, LabError> {
    let mut series: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for r in rows {
        if let Some(t) = r.gpu_ms_total {
            series
                .entry(series_key(r))
                .or_default()
                .push((r.setting_lights() as f64, t));
        }
    }
    // A line needs two light counts: configurations measured at one (a setting's own count)
    // are no line, and a report with no line has no such figure.
    series.retain(|_, pts| {
        pts.iter()
            .map(|p| p.0.to_bits())
            .collect::<std::collections::BTreeSet<_>>()
            .len()
            > 1
    });
    let counts: std::collections::BTreeSet<u64> = rows.iter().map(|r| r.setting_lights()).collect();
    if counts.len() < 2 || series.is_empty() {
        return Ok(None);
    }
    // More configurations than a legend holds (a sweep over settings, strategies and
    // backends): small multiples, a panel a setting, marker and fill for strategy and backend.
    if series.len() > panels::MAX_LEGEND {
        return panels::draw(
            rows,
            path,
            &panels::Spec {
                title: "GPU time per frame against light count",
                x: ("lights", &|r| Some(r.setting_lights() as f64)),
                y: ("GPU ms, median", &|r| r.gpu_ms_total),
                front: false,
            },
        );
    }
    let x = Scale::fit(counts.iter().map(|c| *c as f64));
    let y = Scale::fit(series.values().flatten().map(|p| p.1));
    let labels: Vec<String> = series.keys().cloned().collect();
    let lw = legend_width(&labels);
    let height = 460.max(60 + 16 * labels.len() as u32);
    let mut svg = String::new();
    let mut layout = Layout::default();
    {
        let root = SVGBackend::with_string(&mut svg, (700 + lw, height)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (plot, side) = root.split_horizontally(700);
        let mut chart = axes::chart(
            &plot,
            "GPU time per frame against light count",
            (x, "lights"),
            (y, "GPU ms, median"),
        )?;
        let mut entries = Vec::new();
        for (i, (name, mut pts)) in series.into_iter().enumerate() {
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            let pts: Vec<(f64, f64)> = pts.iter().map(|p| (x.map(p.0), y.map(p.1))).collect();
            let c = PALETTE[i % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
                .map_err(err)?;
            layout
                .points
                .extend(pts.iter().map(|p| chart.backend_coord(p)));
            chart
                .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, c.filled())))
                .map_err(err)?;
            entries.push((name, Mark::Line(c)));
        }
        layout.legend = Some(legend(&side, &entries)?);
        layout.legend_entries = entries.len();
        root.present().map_err(err)?;
    }
    write_svg(path, &svg, layout.legend)?;
    Ok(Some(layout))
}

/// Where the bars of `totals` are cut: at five times the median where the longest is longer,
/// else at the longest.
fn bar_cut(totals: &[f64]) -> f64 {
    let max = totals.iter().copied().fold(0.0, f64::max);
    let mut sorted = totals.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
    if median > 0.0 && max > 5.0 * median {
        5.0 * median
    } else {
        max
    }
}

/// The cells' per-pass GPU times as stacked bars, each bar named beside it and its total at its
/// end; bars past five times the median are cut there.
pub(crate) fn passes(rows: &[Row], path: &Path) -> Result<Option<Layout>, LabError> {
    let shown: Vec<&Row> = rows
        .iter()
        .filter(|r| r.gpu_ms_total.is_some())
        .take(40)
        .collect();
    if shown.is_empty() {
        return Ok(None);
    }
    // In steady state where every bar has it (the passes of the back-to-back runs, at the
    // clock the GPU runs at under load); else the single frame's (moving lights' update is
    // timed only there).
    let steady = shown.iter().all(|r| !r.passes_steady.is_empty())
        && shown.iter().all(|r| r.gpu_ms_light_update.is_none());
    let parts = |r: &Row| {
        if steady {
            let part = |c: Category| -> f64 {
                r.passes_steady
                    .iter()
                    .filter(|(l, _)| r.pass_category(l) == Some(c))
                    .map(|(_, ms)| ms)
                    .sum()
            };
            [
                0.0,
                part(Category::Prepass),
                part(Category::Cull),
                part(Category::Shade),
            ]
        } else {
            [
                r.gpu_ms_light_update.unwrap_or(0.0),
                r.gpu_ms_prepass.unwrap_or(0.0),
                r.gpu_ms_cull.unwrap_or(0.0),
                r.gpu_ms_shade.unwrap_or(0.0),
            ]
        }
    };
    // Moving lights' update, where a row has one, as a fourth part before the others.
    let moving = shown.iter().any(|r| r.gpu_ms_light_update.is_some());
    // Bars far longer than the others (forward at a million lights beside a visibility buffer
    // at 3,000) are cut at five times the median bar, so that the rest stay readable; every
    // bar's total is written at its end.
    let totals: Vec<f64> = shown.iter().map(|r| parts(r).iter().sum()).collect();
    let cut = bar_cut(&totals);
    let xmax = cut.max(1e-6) * 1.18;
    let n = shown.len();
    let labels: Vec<String> = shown.iter().map(|r| clip_label(&r.cell)).collect();
    let names = [
        "moving the lights (lights.animate / lights.upload)",
        "geometry (prepass / G-buffer / visibility buffer, lookup bounds)",
        "culling (compute)",
        "shading",
    ];
    // The parts' colours: the geometry pass, culling and shading as before moving lights.
    let colours = [PALETTE[3], PALETTE[0], PALETTE[1], PALETTE[2]];
    let shown_parts: Vec<usize> = (usize::from(!moving)..names.len()).collect();
    let label_w = legend_width(&labels) - 30;
    let lw = legend_width(
        &shown_parts
            .iter()
            .map(|&k| names[k].to_owned())
            .collect::<Vec<_>>(),
    );
    let height = 110 + 24 * n as u32;
    let mut svg = String::new();
    let mut layout = Layout::default();
    {
        let root =
            SVGBackend::with_string(&mut svg, (label_w + 520 + lw, height)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (plot, side) = root.split_horizontally(label_w + 520);
        let mut chart = ChartBuilder::on(&plot)
        .caption(
            if moving {
                "Per-pass GPU time (median): moving the lights | geometry pass (raster) | culling | shading"
            } else if steady {
                "Per-pass GPU time in steady state (median): geometry | culling (compute) | shading"
            } else {
                "Per-pass GPU time (median): geometry pass (raster) | culling (compute) | shading"
            },
            (FONT, 15),
        )
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(label_w)
        .build_cartesian_2d(0.0..xmax, 0.0..n as f64)
        .map_err(err)?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .y_labels(0)
            .bold_line_style(BLACK.mix(0.15))
            .light_line_style(TRANSPARENT)
            .x_label_formatter(&axes::linear_label)
            .x_desc("GPU ms")
            .label_style((FONT, 11))
            .draw()
            .map_err(err)?;
        for &k in &shown_parts {
            let c = colours[k];
            chart
                .draw_series(shown.iter().enumerate().map(|(i, r)| {
                    let p = parts(r);
                    let x0: f64 = p[..k].iter().sum::<f64>().min(cut);
                    let x1 = (x0 + p[k]).min(cut);
                    Rectangle::new([(x0, i as f64 + 0.15), (x1, i as f64 + 0.85)], c.filled())
                }))
                .map_err(err)?;
        }
        // Each bar's total at its end (a cut bar's marked as cut).
        let value = TextStyle::from((FONT, 10).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
        for (i, &total) in totals.iter().enumerate() {
            let (x, y) = chart.backend_coord(&(total.min(cut), i as f64 + 0.5));
            let text = format!(
                "{} ms{}",
                axes::linear_label(&total),
                if total > cut { ", cut" } else { "" }
            );
            root.draw(&Text::new(text, (x + 3, y), value.clone()))
                .map_err(err)?;
        }
        // Every bar named, beside it.
        let style =
            TextStyle::from((FONT, 11).into_font()).pos(Pos::new(HPos::Right, VPos::Center));
        for (i, (label, r)) in labels.iter().zip(&shown).enumerate() {
            let (x, y) = chart.backend_coord(&(0.0, i as f64 + 0.5));
            root.draw(&Text::new(label.clone(), (x - 6, y), style.clone()))
                .map_err(err)?;
            let total: f64 = parts(r).iter().sum::<f64>().min(cut);
            layout
                .points
                .push(chart.backend_coord(&(total, i as f64 + 0.5)));
        }
        let entries: Vec<(String, Mark)> = shown_parts
            .iter()
            .map(|&k| (names[k].to_owned(), Mark::Block(colours[k])))
            .collect();
        layout.legend = Some(legend(&side, &entries)?);
        layout.legend_entries = entries.len();
        root.present().map_err(err)?;
    }
    write_svg(path, &svg, layout.legend)?;
    Ok(Some(layout))
}

/// Points on the Pareto front (smaller is better on both axes), sorted by x.
fn pareto(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut front: Vec<(f64, f64)> = Vec::new();
    for q in p {
        if front.last().is_none_or(|l| q.1 < l.1) {
            front.push(q);
        }
    }
    front
}

/// One axis of a scatter: its name and its value in a row.
pub(crate) type Axis<'a> = (&'a str, &'a dyn Fn(&Row) -> Option<f64>);

/// Speed against accuracy: `time` against `accuracy` in small multiples
/// ([`panels`]), a panel a setting, each configuration's sweep a line, each panel's Pareto
/// front in black.
pub(crate) fn speed_accuracy(
    rows: &[Row],
    path: &Path,
    time: Axis<'_>,
    accuracy: Axis<'_>,
) -> Result<Option<Layout>, LabError> {
    let title = format!(
        "Speed against accuracy: {} against {} (black: Pareto front)",
        time.0, accuracy.0
    );
    panels::draw(
        rows,
        path,
        &panels::Spec {
            title: &title,
            x: time,
            y: accuracy,
            front: true,
        },
    )
}

/// What a loose list costs: the shading pass's time against the lights it evaluates per pixel,
/// one point per cell, in small multiples ([`panels`]).
pub(crate) fn shade_vs_lights(rows: &[Row], path: &Path) -> Result<Option<Layout>, LabError> {
    panels::draw(
        rows,
        path,
        &panels::Spec {
            title: "Shading time against lights evaluated per pixel",
            x: ("lights evaluated per pixel (mean)", &|r| {
                r.lights_per_pixel_mean
            }),
            y: ("shading pass, GPU ms (median)", &|r| r.gpu_ms_shade),
            front: false,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bars_far_past_the_median_are_cut() {
        assert_eq!(bar_cut(&[1.0, 2.0, 3.0]), 3.0);
        assert_eq!(bar_cut(&[0.6, 1.0, 1.4, 2.6, 114.8]), 7.0);
        assert_eq!(bar_cut(&[]), 0.0);
    }

    /// Every figure of every committed report (docs/reports/*), drawn again: no data point
    /// (a marker's centre, a bar's end, with a marker's radius) lies inside its legend's box,
    /// and every figure has its legend.
    #[test]
    fn no_legend_covers_a_data_point_in_any_committed_report() {
        register_font();
        let reports = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/reports");
        let tmp = tempfile::tempdir().unwrap();
        let svg = tmp.path().join("figure.svg");
        let mut checked = 0;
        for e in std::fs::read_dir(&reports).unwrap() {
            let dir = e.unwrap().path();
            if !dir.is_dir() {
                continue;
            }
            let rows = crate::results::load_rows(&dir).unwrap();
            if rows.is_empty() {
                continue;
            }
            let gpu: Axis<'_> = ("GPU ms", &|r| r.gpu_ms_total);
            let fp: Axis<'_> = ("false-positive ratio", &|r| r.false_positive_ratio);
            let frame: Axis<'_> = ("culling + shading", &|r| r.gpu_ms_cull_shade);
            let flip_inf: Axis<'_> = ("mean FLIP vs infinite range", &|r| r.flip_mean_infinite);
            let flip_shadowed: Axis<'_> = ("mean FLIP vs the shadowed light", &|r| {
                r.shadow.flip_mean_shadowed
            });
            let figures = [
                ("time_vs_lights", time_vs_lights(&rows, &svg).unwrap()),
                ("passes", passes(&rows, &svg).unwrap()),
                (
                    "speed_accuracy",
                    speed_accuracy(&rows, &svg, gpu, fp).unwrap(),
                ),
                (
                    "frame_infinite",
                    speed_accuracy(&rows, &svg, frame, flip_inf).unwrap(),
                ),
                (
                    "frame_shadowed",
                    speed_accuracy(&rows, &svg, frame, flip_shadowed).unwrap(),
                ),
                ("shade_vs_lights", shade_vs_lights(&rows, &svg).unwrap()),
            ];
            for (name, layout) in figures {
                let Some(layout) = layout else { continue };
                let (x0, y0, x1, y1) = layout.legend.expect("a legend");
                assert!(!layout.points.is_empty(), "{}: {name}", dir.display());
                assert!(
                    layout.legend_entries <= panels::MAX_LEGEND,
                    "{}: {name}: {} legend entries",
                    dir.display(),
                    layout.legend_entries
                );
                for &(x, y) in &layout.points {
                    let r = 6;
                    assert!(
                        x + r < x0 || x - r > x1 || y + r < y0 || y - r > y1,
                        "{}: {name}: the legend ({x0}, {y0})-({x1}, {y1}) covers the point ({x}, {y})",
                        dir.display()
                    );
                }
                checked += 1;
            }
        }
        assert!(checked >= 20, "only {checked} figures checked");
    }

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        let pts = [(3.0, 1.0), (1.0, 5.0), (2.0, 2.0), (2.5, 3.0), (4.0, 0.5)];
        assert_eq!(
            pareto(&pts),
            vec![(1.0, 5.0), (2.0, 2.0), (3.0, 1.0), (4.0, 0.5)]
        );
    }
}
