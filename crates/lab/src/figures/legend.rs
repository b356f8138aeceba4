//! Legends beside a figure's plot, never over its data, and where a figure's parts landed.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{FONT, err};
use crate::LabError;

/// Where a figure's parts landed, in pixels of its SVG: every data point (bar or marker
/// centre) and the legend's box (x0, y0, x1, y1).
#[derive(Debug, Default)]
pub(crate) struct Layout {
    pub(crate) points: Vec<(i32, i32)>,
    pub(crate) legend: Option<(i32, i32, i32, i32)>,
    /// Entries in the legend.
    pub(crate) legend_entries: usize,
    /// What the caption must add for a reader to name every point: each sweep's values in
    /// the order its lines run, and the numbered points' cells.
    pub(crate) notes: Vec<String>,
}

/// How a legend entry shows its series.
#[derive(Clone, Copy)]
pub(super) enum Mark {
    Line(RGBColor),
    Block(RGBColor),
    /// A marker's shape, colour and fill ([`super::panels::draw_marker`]).
    Shape(super::panels::Shape, RGBColor, bool),
}

/// The most characters of a label in a legend or beside a bar.
pub(super) const LABEL_CHARS: usize = 64;

pub(super) fn clip_label(s: &str) -> String {
    clip_to(s, LABEL_CHARS)
}

/// `s` in at most `n` characters, an ellipsis ending one that was cut.
pub(super) fn clip_to(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_owned()
    } else {
        let mut t: String = s.chars().take(n - 1).collect();
        t.push('…');
        t
    }
}

/// Pixels a legend beside the plot needs for `labels` (11-point text).
pub(super) fn legend_width(labels: &[String]) -> u32 {
    let chars = labels.iter().map(|l| l.chars().count()).max().unwrap_or(0);
    (40 + 7 * chars.min(LABEL_CHARS)) as u32
}

/// Draws the legend of `entries` into `area`, the strip beside the plot; returns its box in
/// the figure's pixels.
pub(super) fn legend(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    entries: &[(String, Mark)],
) -> Result<(i32, i32, i32, i32), LabError> {
    let (x0, y0) = (6, 44);
    let row = 16;
    let style = TextStyle::from((FONT, 11).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
    for (i, (label, mark)) in entries.iter().enumerate() {
        let y = y0 + row / 2 + row * i as i32;
        match *mark {
            Mark::Line(c) => area
                .draw(&PathElement::new(
                    vec![(x0, y), (x0 + 18, y)],
                    c.stroke_width(2),
                ))
                .map_err(err)?,
            Mark::Block(c) => area
                .draw(&Rectangle::new(
                    [(x0 + 3, y - 5), (x0 + 15, y + 5)],
                    c.filled(),
                ))
                .map_err(err)?,
            Mark::Shape(shape, c, filled) => {
                super::panels::draw_marker(area, (x0 + 9, y), 4, shape, c, filled)?
            }
        }
        area.draw(&Text::new(clip_label(label), (x0 + 26, y), style.clone()))
            .map_err(err)?;
    }
    let (bx, by) = area.get_base_pixel();
    let (w, _) = area.dim_in_pixel();
    Ok((
        bx + x0 - 2,
        by + y0,
        bx + w as i32,
        by + y0 + row * entries.len() as i32,
    ))
}
