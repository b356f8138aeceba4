//! A figure's method families, from each row's light-range columns (`radius_rule`,
//! `radius_value`, `hierarchy_*`, `stochastic_*`, `accumulate`, `interleave`): cut-off
//! thresholds, fixed radii, stochastic light culling in one frame, accumulated or interleaved,
//! and the lighting grid hierarchy a finest spacing (and a first sampled level), each with
//! shadows a family apart; each row's place in its family's sweep, and which way that sweep
//! runs.

use crate::cells::RADIUS_AXES;
use crate::results::Row;

/// Whether the row's cell sweeps its light range (one of [`RADIUS_AXES`] among its parameters):
/// then its range's value is its place in its family's sweep.
pub(super) fn sweeps_range(r: &Row) -> bool {
    RADIUS_AXES
        .iter()
        .any(|k| r.sweep.parameters.contains_key(*k))
}

/// A row's method family and its place in the family's sweep (the threshold, radius, error
/// bound or alpha) where its cell sweeps the range; else the rule's family alone.
pub(crate) fn family(r: &Row) -> (String, Option<f64>) {
    let (name, place) = range_family(r);
    // A shadow mode is a family of its own (`shadowed: `, first, so that a legend that
    // shortens a long name keeps it): the same ranges cost more with rays.
    // Stochastic shadows are a family a ray count (`K rays: `).
    match r.shadow.shadows.as_str() {
        "exact" => (format!("shadowed: {name}"), place),
        "stochastic" => {
            let rays = r
                .params
                .split(';')
                .find_map(|p| p.strip_prefix("shadow_rays="))
                .unwrap_or("?");
            let plural = if rays == "1" { "" } else { "s" };
            (format!("{rays} ray{plural}: {name}"), place)
        }
        _ => (name, place),
    }
}

/// [`family`] by the light range alone.
fn range_family(r: &Row) -> (String, Option<f64>) {
    if !sweeps_range(r) {
        let name = match r.radius_rule.as_str() {
            "threshold" => "cut-off thresholds",
            "stochastic" => "stochastic",
            "hierarchy" => "lighting grid hierarchy",
            _ => "fixed radius",
        };
        return (name.into(), None);
    }
    let v = r.sweep.radius_value;
    match r.radius_rule.as_str() {
        "threshold" => ("cut-off thresholds".into(), v),
        "hierarchy" => (hierarchy_family(r), v),
        "stochastic" => (stochastic_family(r), v),
        _ => ("fixed radii".into(), v),
    }
}

/// A hierarchy's family: a finest spacing, and the finest grid's rule, growth of the bands,
/// ramps and first sampled level where they are not the defaults; swept over alpha.
fn hierarchy_family(r: &Row) -> String {
    use manylights_scene::hierarchy::{FINEST_NODES, GROWTH, RAMP};
    let mut name = match r.sweep.hierarchy_spacing {
        Some(h) => format!("lighting grid hierarchy, spacing {h} m"),
        None => "lighting grid hierarchy".into(),
    };
    let not = |v: Option<f64>, default: f64| v.filter(|&v| v != default);
    if let Some(n) = not(r.sweep.hierarchy_finest_nodes, FINEST_NODES) {
        name += &format!(", {n} nodes a light");
    }
    if let Some(k) = not(r.sweep.hierarchy_growth, GROWTH) {
        name += &format!(", growth {k}");
    }
    if let Some(c) = not(r.sweep.hierarchy_ramp, RAMP) {
        name += &format!(", ramps {c}");
    }
    if let Some(l) = r.sweep.hierarchy_sample_from {
        name += &format!(", sampled from level {l}");
    }
    name
}

/// Stochastic culling's family: one frame, accumulated, interleaved, or both; then its bound,
/// draw and exposure where they are not the defaults.
fn stochastic_family(r: &Row) -> String {
    let acc = r.accumulate.filter(|&k| k > 1);
    let il = r.sweep.interleave.filter(|&n| n > 1);
    let mut name = match (acc, il) {
        (None, None) => "stochastic, one frame".to_owned(),
        (Some(k), None) => format!("stochastic, {k} frames accumulated"),
        (None, Some(n)) => format!("stochastic, {n}x{n} interleaved"),
        (Some(k), Some(n)) => format!("stochastic, {n}x{n} interleaved, {k} frames"),
    };
    if let Some(b) = r
        .sweep
        .stochastic_bound
        .as_deref()
        .filter(|b| *b != "light")
    {
        name += &format!(" ({b})");
    }
    if let Some(d) = r
        .sweep
        .stochastic_draw
        .as_deref()
        .filter(|d| *d != "stratified")
    {
        name += &format!(" ({d})");
    }
    if let Some(x) = r.sweep.stochastic_exposure.filter(|&x| x != 1.0) {
        name += &format!(" (exposure{x})");
    }
    name
}

/// Whether a family's sweep value grows as its error falls: the hierarchy's alpha and a fixed
/// radius (a threshold or an error bound shrinks instead).
pub(super) fn grows_tighter(family: &str) -> bool {
    family.starts_with("lighting grid hierarchy") || family.starts_with("fixed")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::Row;

    /// A row written before rows carried their parameters: only its cell name says them, and
    /// the backfill makes its columns from it.
    fn row(cell: &str, strategy: &str, backend: &str) -> Row {
        let mut r = crate::results::tests::sample_row();
        r.cell = cell.into();
        r.strategy = strategy.into();
        r.backend = backend.into();
        let mut rows = [r];
        crate::results::backfill(&mut rows);
        let [r] = rows;
        r
    }

    #[test]
    fn families_come_from_the_columns() {
        let mut r = crate::results::tests::sample_row();
        r.radius_rule = "hierarchy".into();
        r.sweep.radius_value = Some(2.0);
        r.sweep.hierarchy_spacing = Some(0.25);
        r.sweep.hierarchy_finest_nodes = Some(2.0);
        r.sweep.hierarchy_growth = Some(1.15);
        // Not swept: the rule's family alone.
        assert_eq!(family(&r), ("lighting grid hierarchy".into(), None));
        r.sweep
            .parameters
            .insert("hierarchy".into(), "whatever the name says".into());
        assert_eq!(
            family(&r),
            (
                "lighting grid hierarchy, spacing 0.25 m, growth 1.15".into(),
                Some(2.0)
            )
        );
        r.radius_rule = "stochastic".into();
        r.sweep.parameters.clear();
        r.sweep
            .parameters
            .insert("stochastic".into(), String::new());
        r.sweep.radius_value = Some(0.5);
        r.sweep.interleave = Some(2);
        r.accumulate = Some(1);
        r.sweep.stochastic_draw = Some("independent".into());
        assert_eq!(
            family(&r),
            (
                "stochastic, 2x2 interleaved (independent)".into(),
                Some(0.5)
            )
        );
    }

    #[test]
    fn old_rows_families_come_from_the_cell_name() {
        let f = |cell: &str| family(&row(cell, "tiled_gather", "deferred"));
        assert_eq!(
            f("setting=hall,threshold=0.03,variant=x"),
            ("cut-off thresholds".into(), Some(0.03))
        );
        assert_eq!(
            f("stochastic=0.5,variant=x"),
            ("stochastic, one frame".into(), Some(0.5))
        );
        assert_eq!(
            f("stochastic=1/acc16,variant=x"),
            ("stochastic, 16 frames accumulated".into(), Some(1.0))
        );
        assert_eq!(
            f("stochastic=1/il2,variant=x"),
            ("stochastic, 2x2 interleaved".into(), Some(1.0))
        );
        assert_eq!(
            f("stochastic=1/albedo,variant=x").0,
            "stochastic, one frame (albedo)"
        );
        assert_eq!(
            f("setting=hall,hierarchy=2/h0.25,variant=x"),
            ("lighting grid hierarchy, spacing 0.25 m".into(), Some(2.0))
        );
        // Within a legend's LABEL_CHARS, so that sampled families stay apart.
        let (sampled, _) = f("setting=hall,hierarchy=2/h0.25/s1,variant=x");
        assert_eq!(
            sampled,
            "lighting grid hierarchy, spacing 0.25 m, sampled from level 1"
        );
        assert!(sampled.chars().count() <= crate::figures::legend::LABEL_CHARS);
        // The finest grid's rule where it is not the default, then the sampled level.
        let (both, _) = f("setting=hall,hierarchy=2/h0.25/n0.25/s1,variant=x");
        assert_eq!(
            both,
            "lighting grid hierarchy, spacing 0.25 m, 0.25 nodes a light, sampled from level 1"
        );
        let (coarse, _) = f("setting=hall,hierarchy=2/h0.25/n0.25,variant=x");
        assert_eq!(
            coarse,
            "lighting grid hierarchy, spacing 0.25 m, 0.25 nodes a light"
        );
        assert!(coarse.chars().count() <= crate::figures::legend::LABEL_CHARS);
        // Growing bands and narrow ramps are families of their own.
        let (narrow, _) = f("hierarchy=0.7/h0.25/g1.15/c1.25,variant=x");
        assert_eq!(
            narrow,
            "lighting grid hierarchy, spacing 0.25 m, growth 1.15, ramps 1.25"
        );
        assert!(narrow.chars().count() <= crate::figures::legend::LABEL_CHARS);
    }
}
