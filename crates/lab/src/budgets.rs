//! Reports' findings on accuracy against infinite range: for each setting (scene, light count,
//! resolution, samples) and each error budget of [`BUDGETS`] (mean FLIP against the
//! infinite-range reference, `flip_mean_infinite`), the fastest conservative configuration
//! (a radius rule that cuts light off) and the fastest stochastic one (stochastic light
//! culling) within it, and the fastest lighting grid hierarchy where the setting has one, by
//! culling and shading in steady state (`gpu_ms_cull_shade`), and how
//! they compare. Stochastic culling is named twice: in one frame (what a moving view sees; the
//! only fair comparison with a cut-off, one frame against one frame), and accumulated over K
//! frames (a static view: the cost a frame, and the K frames' total that the image took). A
//! configuration with a false negative or a dropped light never counts.

use std::collections::BTreeMap;

use crate::Row;

/// The error budgets: mean FLIP against infinite range.
pub const BUDGETS: [f64; 3] = [0.1, 0.05, 0.02];

/// Which rows a finding compares.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// Radius rules that cut light off.
    Conservative,
    /// Stochastic light culling, each image one frame.
    StochasticFrame,
    /// Stochastic light culling, each image K >= 2 frames accumulated.
    StochasticAccumulated,
    /// The lighting grid hierarchy (`radius: Hierarchy`): far lights from aggregates.
    Hierarchy,
}

impl Family {
    fn holds(self, r: &Row) -> bool {
        let stochastic = r.radius_rule == "stochastic";
        let hierarchy = r.radius_rule == "hierarchy";
        let accumulated = r.accumulate.unwrap_or(1) > 1;
        match self {
            Family::Conservative => !stochastic && !hierarchy,
            Family::Hierarchy => hierarchy,
            Family::StochasticFrame => stochastic && !accumulated,
            Family::StochasticAccumulated => stochastic && accumulated,
        }
    }
}

/// The fastest row of `rows` within `budget` of `family`, by a frame's culling and shading
/// (`gpu_ms_cull_shade`) and, for the hierarchy, its build (`crate::tune::cost`).
pub fn fastest_within<'a>(rows: &[&'a Row], budget: f64, family: Family) -> Option<&'a Row> {
    rows.iter()
        .copied()
        .filter(|r| family.holds(r))
        .filter(|r| r.false_negatives.unwrap_or(0) == 0 && r.dropped_lights == 0)
        .filter(|r| r.flip_mean_infinite.is_some_and(|f| f <= budget))
        .filter_map(|r| Some((crate::tune::cost(r)?, r)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, r)| r)
}

/// A finding's name of a row: its cell, time and error (with the hierarchy's build apart).
fn name(r: Option<&Row>) -> String {
    let Some(r) = r else {
        return "none".into();
    };
    let ms = r.gpu_ms_cull_shade.unwrap_or(f64::NAN);
    let time = match r.hierarchy_build_ms() {
        Some(b) => format!("{ms:.3} ms + {b:.3} ms build"),
        None => format!("{ms:.3} ms"),
    };
    format!(
        "`{}` ({time}, FLIP {:.3})",
        r.cell,
        r.flip_mean_infinite.unwrap_or(f64::NAN)
    )
}

/// The findings lines (none where no row was measured against infinite range).
pub(crate) fn findings(rows: &[Row]) -> Vec<String> {
    // A setting is its `setting=` label where the cell has one, else its light count (the
    // scene's: a hierarchy's cells count the nodes they shade, `Row::setting_lights`).
    let mut settings: BTreeMap<(String, String, u32, u32, u32), Vec<&Row>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.flip_mean_infinite.is_some()) {
        let label = if r.sweep.setting.is_empty() {
            format!("{:020}", r.setting_lights())
        } else {
            r.sweep.setting.clone()
        };
        settings
            .entry((r.scene.clone(), label, r.width, r.height, r.msaa))
            .or_default()
            .push(r);
    }
    // In the rows' order (the experiment's), not the labels'.
    let mut settings: Vec<_> = settings.into_iter().collect();
    settings.sort_by_key(|(_, rs)| rs.iter().map(|r| r.index).min());
    let mut out = Vec::new();
    for ((scene, _, w, h, msaa), rs) in &settings {
        let lights = rs.iter().map(|r| r.setting_lights()).min().unwrap_or(0);
        let lights = &lights;
        let setting = if *msaa > 1 {
            format!("{scene}, {lights} lights, {w}x{h}, {msaa} samples")
        } else {
            format!("{scene}, {lights} lights, {w}x{h}")
        };
        let best_error = rs
            .iter()
            .filter_map(|r| r.flip_mean_infinite)
            .fold(f64::INFINITY, f64::min);
        if best_error > BUDGETS[0] {
            out.push(format!(
                "Against infinite range at {setting} no configuration comes within mean FLIP {} (the lowest: {best_error:.3}, at the reference's exposure).",
                BUDGETS[0]
            ));
            continue;
        }
        let mut parts = Vec::new();
        for b in BUDGETS {
            let c = fastest_within(rs, b, Family::Conservative);
            let s = fastest_within(rs, b, Family::StochasticFrame);
            let a = fastest_within(rs, b, Family::StochasticAccumulated);
            let l = fastest_within(rs, b, Family::Hierarchy);
            let hierarchy = if rs.iter().any(|r| Family::Hierarchy.holds(r)) {
                format!("; lighting grid hierarchy {}", name(l))
            } else {
                String::new()
            };
            // One frame against one frame: the family a moving view is fastest with.
            let fastest = [
                (c, "cut-offs"),
                (s, "stochastic culling"),
                (l, "the lighting grid hierarchy"),
            ]
            .into_iter()
            .filter_map(|(r, f)| Some((crate::tune::cost(r?)?, f)))
            .min_by(|x, y| x.0.total_cmp(&y.0))
            .map_or_else(
                || "none in one frame".to_owned(),
                |(_, f)| format!("fastest in one frame: {f}"),
            );
            let ratio = match (
                c.and_then(|r| r.gpu_ms_cull_shade),
                s.and_then(|r| r.gpu_ms_cull_shade),
            ) {
                (Some(c), Some(s)) if s > 0.0 => {
                    format!(
                        " ({:.2}x the conservative time, one frame against one)",
                        s / c
                    )
                }
                _ => String::new(),
            };
            let static_view = match a {
                Some(r) => {
                    let k = r.accumulate.unwrap_or(1);
                    let ms = r.gpu_ms_cull_shade.unwrap_or(f64::NAN);
                    format!(
                        "`{}` ({ms:.3} ms a frame, {:.3} ms for its {k} frames, FLIP {:.3})",
                        r.cell,
                        ms * f64::from(k),
                        r.flip_mean_infinite.unwrap_or(f64::NAN)
                    )
                }
                None => "none".into(),
            };
            parts.push(format!(
                "FLIP <= {b}: {fastest}; conservative {}; stochastic in one frame {}{ratio}; static view, stochastic accumulated {static_view}{hierarchy}",
                name(c),
                name(s)
            ));
        }
        let build = if rs.iter().any(|r| Family::Hierarchy.holds(r)) {
            ", with the hierarchy's build (`gpu_ms_hierarchy_steady`, else `gpu_ms_hierarchy`)"
        } else {
            ""
        };
        out.push(format!(
            "Against infinite range at {setting} (mean FLIP at the reference's exposure; the fastest by culling + shading, `gpu_ms_cull_shade`{build}; lowest error reached {best_error:.3}): {}.",
            parts.join("; ")
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fastest_within_a_budget_skips_false_negatives_and_other_rules() {
        let row = |cell: &str, rule: &str, ms: f64, flip: f64, fns: u64| {
            let mut r = crate::results::tests::sample_row();
            r.cell = cell.into();
            r.false_negatives = Some(fns);
            r.flip_mean_infinite = Some(flip);
            r.radius_rule = rule.into();
            r.gpu_ms_cull_shade = Some(ms);
            r
        };
        let rows = [
            row("fast-but-missing", "threshold", 0.1, 0.01, 3),
            row("slow", "threshold", 2.0, 0.04, 0),
            row("fast-but-wrong", "threshold", 0.5, 0.2, 0),
            row("stoch", "stochastic", 1.0, 0.03, 0),
            {
                let mut r = row("stoch-acc4", "stochastic", 0.3, 0.01, 0);
                r.accumulate = Some(4);
                r
            },
        ];
        let refs: Vec<&Row> = rows.iter().collect();
        assert_eq!(
            fastest_within(&refs, 0.05, Family::Conservative)
                .unwrap()
                .cell,
            "slow"
        );
        assert_eq!(
            fastest_within(&refs, 0.05, Family::StochasticFrame)
                .unwrap()
                .cell,
            "stoch"
        );
        assert!(fastest_within(&refs, 0.02, Family::StochasticFrame).is_none());
        // Accumulated frames are their own family: not a one-frame result, named with the
        // K frames' total.
        assert_eq!(
            fastest_within(&refs, 0.05, Family::StochasticAccumulated)
                .unwrap()
                .cell,
            "stoch-acc4"
        );
        let f = findings(&rows);
        assert_eq!(f.len(), 1);
        assert!(
            f[0].contains(
                "FLIP <= 0.05: fastest in one frame: stochastic culling; conservative `slow`"
            ),
            "{}",
            f[0]
        );
        assert!(
            f[0].contains("stochastic in one frame `stoch` (1.000 ms, FLIP 0.030) (0.50x"),
            "{}",
            f[0]
        );
        assert!(
            f[0].contains("`stoch-acc4` (0.300 ms a frame, 1.200 ms for its 4 frames"),
            "{}",
            f[0]
        );
        assert!(!f[0].contains("hierarchy"), "{}", f[0]);
        // The hierarchy is its own family, never a cut-off; its cells count the lights they
        // shade, so a setting's label groups them with the rest.
        let mut rows = rows.to_vec();
        for r in &mut rows {
            r.cell = format!("setting=hall,{}", r.cell);
        }
        let mut h = row("setting=hall,hierarchy=1/h0.25", "hierarchy", 0.2, 0.04, 0);
        h.lights += 1000;
        rows.push(h);
        // Rows written before their parameters were columns: the report backfills them.
        crate::results::backfill(&mut rows);
        let refs: Vec<&Row> = rows.iter().collect();
        assert_eq!(
            fastest_within(&refs, 0.05, Family::Conservative)
                .unwrap()
                .cell,
            "setting=hall,slow"
        );
        let f = findings(&rows);
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(
            f[0].contains("lighting grid hierarchy `setting=hall,hierarchy=1/h0.25` (0.200 ms"),
            "{}",
            f[0]
        );
        assert!(
            f[0].contains("FLIP <= 0.05: fastest in one frame: the lighting grid hierarchy;"),
            "{}",
            f[0]
        );
        // Its build counts: 0.2 + 1.0 ms is slower than the stochastic frame's 1.0 ms.
        rows.last_mut().unwrap().gpu_ms_hierarchy = Some(1.0);
        let f = findings(&rows);
        assert!(
            f[0].contains("FLIP <= 0.05: fastest in one frame: stochastic culling;"),
            "{}",
            f[0]
        );
        assert!(
            f[0].contains("(0.200 ms + 1.000 ms build, FLIP 0.040)"),
            "{}",
            f[0]
        );
        assert!(
            f[0].contains("FLIP <= 0.02: none in one frame;"),
            "{}",
            f[0]
        );
        // The build in steady state, where it was timed so, is what counts: 0.2 + 0.5 ms.
        rows.last_mut().unwrap().gpu_ms_hierarchy_steady = Some(0.5);
        let f = findings(&rows);
        assert!(
            f[0].contains("FLIP <= 0.05: fastest in one frame: the lighting grid hierarchy;")
                && f[0].contains("(0.200 ms + 0.500 ms build, FLIP 0.040)"),
            "{}",
            f[0]
        );
    }

    #[test]
    fn a_hierarchy_without_a_setting_label_joins_its_scenes_setting() {
        let row = |cell: &str, rule: &str, lights: u64| {
            let mut r = crate::results::tests::sample_row();
            r.cell = cell.into();
            r.lights = lights;
            r.false_negatives = Some(0);
            r.flip_mean_infinite = Some(0.04);
            r.radius_rule = rule.into();
            r.gpu_ms_cull_shade = Some(1.0);
            r
        };
        // Rows of a run before `scene_lights`: the backfill finds the scene's count.
        let mut rows = vec![
            row("threshold=1", "threshold", 1000),
            row("hierarchy=1/h0.25", "hierarchy", 1234),
        ];
        crate::results::backfill(&mut rows);
        assert_eq!(rows[1].scene_lights, Some(1000));
        assert_eq!(rows[1].setting_lights(), 1000);
        let f = findings(&rows);
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(f[0].contains("1000 lights"), "{}", f[0]);
        // A row that says its scene's count keeps it.
        rows[1].scene_lights = Some(999);
        crate::results::backfill(&mut rows);
        assert_eq!(rows[1].setting_lights(), 999);
    }
}
