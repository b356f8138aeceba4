//! The stability suite's report: every case (an experiment of `experiments/stability/`) against
//! every configuration (backend and strategy), marked
//! - **fail**: false negatives not explained by a deliberate capacity, NaN or infinite pixels,
//!   stochastic ranges that make [`SPAN_FAIL`] of the scene's lights needed a pixel or more (the
//!   method turned brute force: case 18), or a case that did not run;
//! - **degraded**, with the measured cost: lights dropped by a capacity (counted), lists over
//!   10 times longer than needed (false-positive ratio), image error visible to FLIP (mean
//!   above 0.01), or flicker over a camera path (the image's error against the reference
//!   changing from one pose to the next by over 1% of the peak);
//! - **pass** otherwise.
//!
//! A configuration's verdict in a case is the worst over that case's cells.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use crate::results::Row;
use crate::{LabError, write_atomic};

/// Lists longer than this many times the lights needed count as degraded.
pub const FP_DEGRADED: f64 = 10.0;
/// Stochastic light culling whose drawn ranges make this fraction of the scene's lights needed
/// a pixel (the exact set's mean), or more, fails: its ranges span the scene.
pub const SPAN_FAIL: f64 = 0.5;
/// Mean FLIP above this counts as degraded.
pub const FLIP_DEGRADED: f64 = 0.01;
/// Temporal flicker (relative to the reference's peak) above this counts as degraded.
pub const FLICKER_DEGRADED: f64 = 0.01;

/// A verdict, ordered from best to worst.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verdict {
    /// Nothing wrong.
    Pass,
    /// A measured cost, described.
    Degraded(String),
    /// A failure, described.
    Fail(String),
}

/// The verdict of one cell.
pub fn verdict(r: &Row) -> Verdict {
    let fnegs = r.false_negatives.unwrap_or(0);
    if r.nonfinite_pixels > 0 {
        return Verdict::Fail(format!("{} NaN/Inf pixels", r.nonfinite_pixels));
    }
    if fnegs > 0 && r.dropped_lights == 0 {
        return Verdict::Fail(format!("{fnegs} false negatives"));
    }
    // The lights a pixel needs under the drawn ranges (the exact set, not a strategy's
    // coarser lists): ranges that span the scene make every light needed everywhere.
    if let Some(needed) = r.lights_needed_per_pixel_mean
        && r.radius_rule == "stochastic"
        && r.lights > 0
        && needed >= SPAN_FAIL * r.lights as f64
    {
        return Verdict::Fail(format!(
            "stochastic ranges span the scene: {needed:.0} of {} lights needed a pixel",
            r.lights
        ));
    }
    let mut costs = Vec::new();
    if r.dropped_lights > 0 {
        costs.push(format!("{} dropped, {fnegs} FN", r.dropped_lights));
    }
    if let Some(fp) = r.false_positive_ratio.filter(|&fp| fp > FP_DEGRADED) {
        costs.push(format!("FP ratio {fp:.1}"));
    }
    if let Some(f) = r.flip_mean.filter(|&f| f > FLIP_DEGRADED) {
        costs.push(format!("FLIP {f:.3}"));
    }
    if let Some(f) = r.temporal_flicker.filter(|&f| f > FLICKER_DEGRADED) {
        costs.push(format!("flicker {f:.3}"));
    }
    if costs.is_empty() {
        Verdict::Pass
    } else {
        Verdict::Degraded(costs.join(", "))
    }
}

/// One case: its name and its rows, or why it did not run.
pub type Case = (String, Result<Vec<Row>, String>);

/// Writes `stability.md` in `dir` for `cases`; returns the number of failing entries.
pub fn write_report(dir: &Path, cases: &[Case]) -> Result<usize, LabError> {
    let config = |r: &Row| {
        if r.backend == "naive_forward" {
            "naive_forward".to_string()
        } else {
            format!("{}+{}", r.backend, r.strategy)
        }
    };
    let mut configs: Vec<String> = cases
        .iter()
        .filter_map(|(_, r)| r.as_ref().ok())
        .flatten()
        .map(config)
        .collect();
    configs.sort();
    configs.dedup();
    let mut md = String::from("# Stability suite\n\n");
    let _ = writeln!(
        md,
        "Each case of `experiments/stability/` against each configuration: **pass**; **degraded** (with the measured cost: dropped lights, false-positive ratio over {FP_DEGRADED}, mean FLIP over {FLIP_DEGRADED}, temporal flicker over {FLICKER_DEGRADED} of the peak); **fail** (false negatives without a capacity, NaN/Inf pixels, or a case that did not run). The worst verdict over a case's cells; over a camera path, the worst pose (false negatives: their sum).\n\nTwo columns describe the case rather than a method: **cut-off**, the mean FLIP against lights of infinite range, the smallest over the case's cells (the cost of the lights' radius cut-off, which every method shares, however exact its culling), and **flicker**, the largest temporal flicker of any configuration over a camera path (`-` without one).\n"
    );
    let mut fails = 0;
    let mut not_run = Vec::new();
    let all: Vec<&Row> = cases
        .iter()
        .filter_map(|(_, r)| r.as_ref().ok())
        .flatten()
        .collect();
    if !all.is_empty() {
        let date = all.iter().map(|r| r.finished_unix).max().unwrap_or(0);
        let d = |f: fn(&Row) -> &str| crate::report::distinct(all.iter().map(|&r| f(r)));
        let _ = writeln!(
            md,
            "Adapter: {}; driver: {}; commit: {}; finished: {}.\n",
            d(|r| &r.adapter),
            d(|r| &r.driver),
            d(|r| &r.commit),
            crate::report::utc(date)
        );
    }
    let _ = writeln!(
        md,
        "| case | cut-off | flicker | {} |\n|---|---|---|{}",
        configs.join(" | "),
        "---|".repeat(configs.len())
    );
    for (name, rows) in cases {
        let cells: Vec<String> = match rows {
            Err(e) => {
                fails += configs.len().max(1);
                not_run.push((name, e));
                vec![
                    "**fail** (did not run: see below the table)".to_string();
                    configs.len().max(1)
                ]
            }
            Ok(rows) => {
                let mut worst: BTreeMap<String, Verdict> = BTreeMap::new();
                for r in rows {
                    let v = verdict(r);
                    let e = worst.entry(config(r)).or_insert(Verdict::Pass);
                    *e = match (std::mem::replace(e, Verdict::Pass), v) {
                        // Two measured costs: keep both (a capacity's drops and an FP ratio, say).
                        (Verdict::Degraded(a), Verdict::Degraded(b)) if a != b => {
                            let mut parts: Vec<String> = a
                                .split(", ")
                                .chain(b.split(", "))
                                .map(String::from)
                                .collect();
                            parts.sort();
                            parts.dedup();
                            Verdict::Degraded(parts.join(", "))
                        }
                        (old, new) => old.max(new),
                    };
                }
                configs
                    .iter()
                    .map(|c| match worst.get(c) {
                        None => "-".into(),
                        Some(Verdict::Pass) => "pass".into(),
                        Some(Verdict::Degraded(d)) => format!("degraded ({d})"),
                        Some(Verdict::Fail(f)) => {
                            fails += 1;
                            format!("**fail** ({f})")
                        }
                    })
                    .collect()
            }
        };
        let (cutoff, flicker) = match rows {
            Ok(rows) => (
                rows.iter()
                    .filter_map(|r| r.flip_mean_infinite)
                    .reduce(f64::min),
                rows.iter()
                    .filter_map(|r| r.temporal_flicker)
                    .reduce(f64::max),
            ),
            Err(_) => (None, None),
        };
        let show = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.3}"));
        let _ = writeln!(
            md,
            "| {name} | {} | {} | {} |",
            show(cutoff),
            show(flicker),
            cells.join(" | ")
        );
    }
    if !not_run.is_empty() {
        md.push_str("\nCases that did not run, and why:\n\n");
        for (name, e) in not_run {
            let _ = writeln!(md, "- `{name}`: {e}");
        }
    }
    write_atomic(&dir.join("stability.md"), md.as_bytes())?;
    Ok(fails)
}
