//! A figure's method families, from the radius part of each cell's name
//! (`crate::cells::radius_label`): cut-off thresholds, fixed radii, stochastic light culling in
//! one frame, accumulated or interleaved, and the lighting grid hierarchy a finest spacing (and
//! a first sampled level); each row's place in its family's sweep, and which way that sweep
//! runs.

use crate::results::Row;

/// The cell's name parts that set the radius rule: `threshold=`, `radius=`, `stochastic=` or
/// `hierarchy=`.
pub(super) fn radius_part(cell: &str) -> Option<&str> {
    cell.split(',').find(|p| {
        crate::cells::RADIUS_PREFIXES
            .iter()
            .any(|k| p.starts_with(k))
    })
}

/// A row's method family and its place in the family's sweep (the threshold, radius or error
/// bound), from the radius part of its cell name (`crate::cells::radius_label`).
pub(crate) fn family(r: &Row) -> (String, Option<f64>) {
    let Some(part) = radius_part(&r.cell) else {
        let name = match r.radius_rule.as_str() {
            "threshold" => "cut-off thresholds",
            "stochastic" => "stochastic",
            "hierarchy" => "lighting grid hierarchy",
            _ => "fixed radius",
        };
        return (name.into(), None);
    };
    let (kind, value) = part.split_once('=').unwrap_or((part, ""));
    let mut pieces = value.split('/');
    let v = pieces.next().and_then(|v| v.parse::<f64>().ok());
    match kind {
        "threshold" => ("cut-off thresholds".into(), v),
        "radius" => ("fixed radii".into(), v),
        // `hierarchy=A/hH[/nR][/gK][/cC][/sL]`: a family a finest spacing (and finest grid
        // rule, growth of the bands, ramps, and first sampled level), swept over alpha.
        "hierarchy" => {
            let h = pieces.next().and_then(|p| p.strip_prefix('h'));
            let mut name = match h {
                Some(h) => format!("lighting grid hierarchy, spacing {h} m"),
                None => "lighting grid hierarchy".into(),
            };
            for p in pieces {
                if let Some(n) = p.strip_prefix('n') {
                    name += &format!(", {n} nodes a light");
                } else if let Some(k) = p.strip_prefix('g') {
                    name += &format!(", growth {k}");
                } else if let Some(c) = p.strip_prefix('c') {
                    name += &format!(", ramps {c}");
                } else if let Some(l) = p.strip_prefix('s') {
                    name += &format!(", sampled from level {l}");
                }
            }
            (name, v)
        }
        _ => {
            let (mut acc, mut il, mut extra) = (None, None, Vec::new());
            for p in pieces {
                if let Some(k) = p.strip_prefix("acc") {
                    acc = Some(k.to_owned());
                } else if let Some(n) = p.strip_prefix("il") {
                    il = Some(n.to_owned());
                } else {
                    extra.push(p.to_owned());
                }
            }
            let mut name = match (acc, il) {
                (None, None) => "stochastic, one frame".to_owned(),
                (Some(k), None) => format!("stochastic, {k} frames accumulated"),
                (None, Some(n)) => format!("stochastic, {n}x{n} interleaved"),
                (Some(k), Some(n)) => format!("stochastic, {n}x{n} interleaved, {k} frames"),
            };
            for e in extra {
                name += &format!(" ({e})");
            }
            (name, v)
        }
    }
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

    fn row(cell: &str, strategy: &str, backend: &str) -> Row {
        let mut r = crate::results::tests::sample_row();
        r.cell = cell.into();
        r.strategy = strategy.into();
        r.backend = backend.into();
        r
    }

    #[test]
    fn families_and_sweeps_come_from_the_cell_name() {
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
