//! The report's figures, drawn with plotters into SVG with the embedded DejaVu Sans (no system
//! fonts needed): GPU time against light count per configuration, per-pass stacked bars (raster
//! and compute labelled), and speed against accuracy with the Pareto front marked.

use std::collections::BTreeMap;
use std::path::Path;

use plotters::prelude::*;

use crate::LabError;
use crate::results::Row;

const FONT: &str = "sans-serif";

pub(crate) fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../assets/DejaVuSans.ttf");
        // Registered under the family every figure asks for; failure only means plotters'
        // own font path is used.
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, bytes);
    });
}

fn err(e: impl std::fmt::Display) -> LabError {
    LabError::Other(format!("report figure: {e}"))
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// The configuration of a row without its light count: one series of the scaling figure.
pub(crate) fn series_key(r: &Row) -> String {
    let parts: Vec<&str> = r
        .cell
        .split(',')
        .filter(|p| !p.starts_with("lights=") && !p.starts_with("seed="))
        .collect();
    if parts.is_empty() || parts == ["base"] {
        format!("{}+{}", r.backend, r.strategy)
    } else {
        parts.join(",")
    }
}

pub(crate) fn time_vs_lights(rows: &[Row], path: &Path) -> Result<bool, LabError> {
    let mut series: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for r in rows {
        if let Some(t) = r.gpu_ms_total {
            series
                .entry(series_key(r))
                .or_default()
                .push((r.lights as f64, t));
        }
    }
    let counts: std::collections::BTreeSet<u64> = rows.iter().map(|r| r.lights).collect();
    if counts.len() < 2 || series.is_empty() {
        return Ok(false);
    }
    let (xmin, xmax) = (
        *counts.first().unwrap() as f64,
        *counts.last().unwrap() as f64,
    );
    let ymax = series.values().flatten().map(|p| p.1).fold(0.0, f64::max) * 1.1;
    let ymin = series
        .values()
        .flatten()
        .map(|p| p.1)
        .fold(f64::INFINITY, f64::min)
        .max(1e-4)
        * 0.8;
    let root = SVGBackend::new(path, (760, 460)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption("GPU time per frame against light count", (FONT, 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (xmin * 0.9..xmax * 1.1).log_scale(),
            (ymin..ymax.max(ymin * 10.0)).log_scale(),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("lights")
        .y_desc("GPU ms (median)")
        .label_style((FONT, 12))
        .draw()
        .map_err(err)?;
    for (i, (name, mut pts)) in series.into_iter().enumerate() {
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let c = PALETTE[i % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
            .map_err(err)?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
        chart
            .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, c.filled())))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 11))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(true)
}

pub(crate) fn passes(rows: &[Row], path: &Path) -> Result<bool, LabError> {
    let shown: Vec<&Row> = rows
        .iter()
        .filter(|r| r.gpu_ms_total.is_some())
        .take(40)
        .collect();
    if shown.is_empty() {
        return Ok(false);
    }
    let parts = |r: &Row| {
        [
            r.gpu_ms_prepass.unwrap_or(0.0),
            r.gpu_ms_cull.unwrap_or(0.0),
            r.gpu_ms_shade.unwrap_or(0.0),
        ]
    };
    let xmax = shown
        .iter()
        .map(|r| parts(r).iter().sum::<f64>())
        .fold(0.0, f64::max)
        .max(1e-6)
        * 1.05;
    let n = shown.len();
    let root = SVGBackend::new(path, (860, 120 + 22 * n as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let labels: Vec<String> = shown
        .iter()
        .map(|r| r.cell.chars().take(60).collect())
        .collect();
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Per-pass GPU time (median): geometry pass (raster) | culling (compute) | shading",
            (FONT, 16),
        )
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(330)
        .build_cartesian_2d(0.0..xmax, 0.0..n as f64)
        .map_err(err)?;
    let labels2 = labels.clone();
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(n)
        .y_label_formatter(&move |y| {
            let i = y.floor() as usize;
            if (y - i as f64 - 0.5).abs() < 0.26 || y.fract() == 0.0 {
                labels2.get(i).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .x_desc("GPU ms")
        .label_style((FONT, 11))
        .draw()
        .map_err(err)?;
    let names = [
        "geometry pass (prepass / G-buffer, raster)",
        "culling (compute)",
        "shading",
    ];
    for (k, name) in names.iter().enumerate() {
        let c = PALETTE[k];
        chart
            .draw_series(shown.iter().enumerate().map(|(i, r)| {
                let p = parts(r);
                let x0: f64 = p[..k].iter().sum();
                Rectangle::new(
                    [(x0, i as f64 + 0.15), (x0 + p[k], i as f64 + 0.85)],
                    c.filled(),
                )
            }))
            .map_err(err)?
            .label(*name)
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], c.filled()));
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 11))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(true)
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

/// Speed against accuracy: `time` against `accuracy`, one point per cell, the configurations
/// apart, the Pareto front in black.
pub(crate) fn speed_accuracy(
    rows: &[Row],
    path: &Path,
    time: Axis<'_>,
    accuracy: Axis<'_>,
) -> Result<bool, LabError> {
    let caption = format!(
        "Speed against accuracy: {} and {} (Pareto front in black)",
        time.0, accuracy.0
    );
    scatter(rows, path, &caption, time, accuracy, &series_key, true)
}

/// A scatter of `x` against `y`, one point per row that has both, coloured by `series`, with
/// the Pareto front (smaller is better on both axes) where `front`.
fn scatter(
    rows: &[Row],
    path: &Path,
    caption: &str,
    (x_name, x): Axis<'_>,
    (y_name, y): Axis<'_>,
    series: &dyn Fn(&Row) -> String,
    front: bool,
) -> Result<bool, LabError> {
    let pts: Vec<(f64, f64, String)> = rows
        .iter()
        .filter_map(|r| Some((x(r)?, y(r)?, series(r))))
        .collect();
    if pts.len() < 2 {
        return Ok(false);
    }
    let xmax = pts.iter().map(|p| p.0).fold(0.0, f64::max) * 1.1;
    let ymin = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let ymax = pts.iter().map(|p| p.1).fold(0.0, f64::max);
    let pad = ((ymax - ymin) * 0.1).max(ymax.abs() * 0.05).max(1e-9);
    let root = SVGBackend::new(path, (760, 460)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, (FONT, 16))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..xmax.max(1e-6), (ymin - pad)..(ymax + pad))
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_name)
        .y_desc(y_name)
        .label_style((FONT, 12))
        .draw()
        .map_err(err)?;
    let keys: Vec<String> = {
        let mut k: Vec<String> = pts.iter().map(|p| p.2.clone()).collect();
        k.sort();
        k.dedup();
        k
    };
    for (i, key) in keys.iter().enumerate() {
        let c = PALETTE[i % PALETTE.len()];
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| &p.2 == key)
                    .map(|p| Circle::new((p.0, p.1), 4, c.filled())),
            )
            .map_err(err)?
            .label(key.clone())
            .legend(move |(x, y)| Circle::new((x + 6, y), 4, c.filled()));
    }
    if front {
        let front = pareto(&pts.iter().map(|p| (p.0, p.1)).collect::<Vec<_>>());
        chart
            .draw_series(LineSeries::new(front.clone(), BLACK.stroke_width(2)))
            .map_err(err)?;
        chart
            .draw_series(
                front
                    .into_iter()
                    .map(|p| Circle::new(p, 6, BLACK.stroke_width(2))),
            )
            .map_err(err)?;
    }
    if keys.len() <= 12 {
        chart
            .configure_series_labels()
            .label_font((FONT, 11))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(true)
}

/// What a loose list costs: the shading pass's time against the lights it evaluates per pixel,
/// one point per cell, coloured by strategy (and backend, whose shading passes differ).
pub(crate) fn shade_vs_lights(rows: &[Row], path: &Path) -> Result<bool, LabError> {
    scatter(
        rows,
        path,
        "Shading time against lights evaluated per pixel",
        ("lights evaluated per pixel (mean)", &|r| {
            r.lights_per_pixel_mean
        }),
        ("shading pass, GPU ms (median)", &|r| r.gpu_ms_shade),
        &|r| format!("{}+{}", r.backend, r.strategy),
        false,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        let pts = [(3.0, 1.0), (1.0, 5.0), (2.0, 2.0), (2.5, 3.0), (4.0, 0.5)];
        assert_eq!(
            pareto(&pts),
            vec![(1.0, 5.0), (2.0, 2.0), (3.0, 1.0), (4.0, 0.5)]
        );
    }
}
