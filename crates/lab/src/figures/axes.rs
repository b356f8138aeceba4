//! Axes fitted to a figure's values, logarithmic where they span decades. A logarithmic axis is
//! drawn as a linear one over log10 of the values, with its ticks at 1, 2, 5 (or 1, 3; or
//! every decade) times a power of ten, labelled in plain numbers: plotters' own logarithmic
//! mesh crowds its labels and its light lines into grey bands.

use std::ops::Range;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{FONT, err};
use crate::LabError;

/// One axis of a figure: the values' range (with a margin) and whether it is logarithmic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Scale {
    pub(super) lo: f64,
    pub(super) hi: f64,
    pub(super) log: bool,
}

/// Where values spanning this factor or more get a logarithmic axis.
const LOG_SPAN: f64 = 30.0;

impl Scale {
    /// An axis fitted to `values`: logarithmic where positive values span [`LOG_SPAN`] or more
    /// (with a margin of a factor 1.3), otherwise linear with a margin of a tenth of the span.
    pub(super) fn fit(values: impl Iterator<Item = f64> + Clone) -> Scale {
        let lo = values.clone().fold(f64::INFINITY, f64::min);
        let hi = values.fold(f64::NEG_INFINITY, f64::max);
        if lo > 0.0 && hi / lo >= LOG_SPAN {
            return Scale {
                lo: lo / 1.3,
                hi: hi * 1.3,
                log: true,
            };
        }
        let pad = ((hi - lo) * 0.1)
            .max(hi.abs().max(lo.abs()) * 0.05)
            .max(1e-9);
        Scale {
            lo: lo - pad,
            hi: hi + pad,
            log: false,
        }
    }

    /// An axis fitted to `values`, logarithmic wherever they are all positive and span a
    /// factor of 3 or more (speed and error axes, as papers draw them), else as [`Scale::fit`].
    pub(super) fn fit_log(values: impl Iterator<Item = f64> + Clone) -> Scale {
        let lo = values.clone().fold(f64::INFINITY, f64::min);
        let hi = values.clone().fold(f64::NEG_INFINITY, f64::max);
        if lo > 0.0 && hi / lo >= 3.0 {
            Scale {
                lo: lo / 1.3,
                hi: hi * 1.3,
                log: true,
            }
        } else {
            Scale::fit(values)
        }
    }

    /// A value's coordinate on the plot (log10 of it on a logarithmic axis).
    pub(super) fn map(&self, v: f64) -> f64 {
        if self.log { v.log10() } else { v }
    }

    /// The plot's coordinate range.
    pub(super) fn range(&self) -> Range<f64> {
        self.map(self.lo)..self.map(self.hi)
    }

    /// The axis's name, marked "(log)" where it is logarithmic.
    pub(super) fn desc(&self, name: &str) -> String {
        if self.log {
            format!("{name} (log)")
        } else {
            name.to_owned()
        }
    }
}

/// Ticks of a logarithmic axis from `lo` to `hi` (positive): every decade where that gives 4 or
/// more (at most 10, thinned to every other or further decade beyond that), else 1 and 3, else
/// 1, 2 and 5, else 1, 2, 3, 5 and 7 times each power of ten.
pub(super) fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let within = |set: &[f64]| -> Vec<f64> {
        (a..=b)
            .flat_map(|k| set.iter().map(move |m| m * 10f64.powi(k)))
            .filter(|v| *v >= lo * (1.0 - 1e-12) && *v <= hi * (1.0 + 1e-12))
            .collect()
    };
    let decades = within(&[1.0]);
    if decades.len() > 10 {
        let step = decades.len().div_ceil(10);
        return decades.into_iter().step_by(step).collect();
    }
    let mut best = decades;
    for set in [
        &[1.0, 3.0][..],
        &[1.0, 2.0, 5.0],
        &[1.0, 2.0, 3.0, 5.0, 7.0],
    ] {
        if best.len() >= 4 {
            break;
        }
        best = within(set);
    }
    best
}

/// A tick's label in plain numbers: 0.05, 2, 300, 5000, 2e5.
pub(super) fn tick_label(v: f64) -> String {
    if v >= 1e5 {
        let e = v.log10().floor();
        let m = (v / 10f64.powf(e) * 10.0).round() / 10.0;
        format!("{m}e{e}")
    } else if v >= 1.0 {
        format!("{}", v.round() as i64)
    } else {
        let digits = (-v.log10() - 1e-9).ceil().max(1.0) as usize;
        format!("{v:.digits$}")
    }
}

/// A linear axis's label: at most three decimals, no trailing zeros; below 0.001, one
/// significant digit in exponent form (2e-4), so small ticks do not all read 0 (under 1e-12:
/// a zero tick's rounding, 0).
pub(super) fn linear_label(v: &f64) -> String {
    if v.abs() >= 1e-12 && v.abs() < 1e-3 {
        let s = format!("{v:.0e}");
        return s.replace("e-0", "e-");
    }
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_owned()
    } else {
        s.to_owned()
    }
}

pub(super) type Chart<'a, 'b> =
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// A chart on `area` over the axes `x` and `y`, its mesh drawn: plotters' for a linear axis,
/// light lines and plain labels at [`log_ticks`] for a logarithmic one.
pub(super) fn chart<'a, 'b>(
    area: &'a DrawingArea<SVGBackend<'b>, Shift>,
    caption: &str,
    (x, x_name): (Scale, &str),
    (y, y_name): (Scale, &str),
) -> Result<Chart<'a, 'b>, LabError> {
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, 15))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x.range(), y.range())
        .map_err(err)?;
    let (xd, yd) = (x.desc(x_name), y.desc(y_name));
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(xd.as_str())
        .y_desc(yd.as_str())
        .label_style((FONT, 12))
        .bold_line_style(BLACK.mix(0.15))
        .light_line_style(TRANSPARENT)
        .x_label_formatter(&linear_label)
        .y_label_formatter(&linear_label);
    if x.log {
        mesh.disable_x_mesh().x_labels(0);
    }
    if y.log {
        mesh.disable_y_mesh().y_labels(0);
    }
    mesh.draw().map_err(err)?;
    let grid = BLACK.mix(0.15);
    let (xr, yr) = (x.range(), y.range());
    // The chart's coordinates are the backend's; `area`'s are its own, from its corner.
    let (bx, by) = area.get_base_pixel();
    let local = |(px, py): (i32, i32)| (px - bx, py - by);
    if x.log {
        let style = TextStyle::from((FONT, 12).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
        for t in log_ticks(x.lo, x.hi) {
            let c = x.map(t);
            chart
                .draw_series(LineSeries::new([(c, yr.start), (c, yr.end)], grid))
                .map_err(err)?;
            let (px, py) = local(chart.backend_coord(&(c, yr.start)));
            area.draw(&PathElement::new([(px, py), (px, py + 4)], BLACK))
                .map_err(err)?;
            area.draw(&Text::new(tick_label(t), (px, py + 6), style.clone()))
                .map_err(err)?;
        }
    }
    if y.log {
        let style =
            TextStyle::from((FONT, 12).into_font()).pos(Pos::new(HPos::Right, VPos::Center));
        for t in log_ticks(y.lo, y.hi) {
            let c = y.map(t);
            chart
                .draw_series(LineSeries::new([(xr.start, c), (xr.end, c)], grid))
                .map_err(err)?;
            let (px, py) = local(chart.backend_coord(&(xr.start, c)));
            area.draw(&PathElement::new([(px - 4, py), (px, py)], BLACK))
                .map_err(err)?;
            area.draw(&Text::new(tick_label(t), (px - 6, py), style.clone()))
                .map_err(err)?;
        }
    }
    Ok(chart)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_are_round_numbers_inside_the_range_and_few() {
        assert_eq!(log_ticks(0.5, 5000.0), vec![1.0, 10.0, 100.0, 1000.0]);
        assert_eq!(
            log_ticks(400.0, 6000.0),
            vec![500.0, 1000.0, 2000.0, 5000.0]
        );
        assert_eq!(log_ticks(1.2, 30.0), vec![2.0, 5.0, 10.0, 20.0]);
        let wide = log_ticks(1e-3, 1e12);
        assert!(wide.len() <= 10 && wide.len() >= 4, "{wide:?}");
        for (lo, hi) in [(0.013, 0.9), (1.0, 1e6), (37.0, 1234.0)] {
            let t = log_ticks(lo, hi);
            assert!(t.len() >= 2 && t.len() <= 12, "{lo}..{hi}: {t:?}");
            assert!(t.iter().all(|v| *v >= lo && *v <= hi), "{lo}..{hi}: {t:?}");
        }
    }

    #[test]
    fn tick_labels_are_plain_numbers() {
        let l: Vec<String> = [0.05, 0.1, 0.3, 2.0, 300.0, 5000.0, 2e5, 1e6]
            .into_iter()
            .map(tick_label)
            .collect();
        assert_eq!(l, ["0.05", "0.1", "0.3", "2", "300", "5000", "2e5", "1e6"]);
        assert_eq!(linear_label(&2.5), "2.5");
        assert_eq!(linear_label(&100.0), "100");
        assert_eq!(linear_label(&-0.0001), "-1e-4");
        assert_eq!(linear_label(&0.0002), "2e-4");
        assert_eq!(linear_label(&0.0), "0");
        assert_eq!(linear_label(&5.5e-17), "0");
        assert_eq!(linear_label(&-0.0), "0");
    }

    #[test]
    fn scales_go_logarithmic_only_over_decades() {
        assert!(Scale::fit([1.0, 100.0].into_iter()).log);
        assert!(!Scale::fit([1.0, 10.0].into_iter()).log);
        assert!(!Scale::fit([0.0, 1000.0].into_iter()).log);
        let s = Scale::fit([2.0, 3.0].into_iter());
        assert!(s.lo < 2.0 && s.hi > 3.0);
    }
}
