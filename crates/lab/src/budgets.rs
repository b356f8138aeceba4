//! Reports' findings on accuracy against infinite range: for each setting (scene, light count,
//! resolution, samples) and each error budget of [`BUDGETS`] (mean FLIP against the
//! infinite-range reference, `flip_mean_infinite`), the fastest conservative configuration
//! (a radius rule that cuts light off) and the fastest stochastic one (stochastic light
//! culling) within it, by culling and shading in steady state (`gpu_ms_cull_shade`), and how
//! they compare. A configuration with a false negative or a dropped light never counts.

use std::collections::BTreeMap;

use crate::Row;

/// The error budgets: mean FLIP against infinite range.
pub const BUDGETS: [f64; 3] = [0.1, 0.05, 0.02];

/// The fastest row of `rows` within `budget` whose radius rule is (`stochastic`) or is not
/// stochastic, by `gpu_ms_cull_shade`.
pub fn fastest_within<'a>(rows: &[&'a Row], budget: f64, stochastic: bool) -> Option<&'a Row> {
    rows.iter()
        .copied()
        .filter(|r| (r.radius_rule == "stochastic") == stochastic)
        .filter(|r| r.false_negatives.unwrap_or(0) == 0 && r.dropped_lights == 0)
        .filter(|r| r.flip_mean_infinite.is_some_and(|f| f <= budget))
        .filter_map(|r| Some((r.gpu_ms_cull_shade?, r)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, r)| r)
}

/// The findings lines (none where no row was measured against infinite range).
pub(crate) fn findings(rows: &[Row]) -> Vec<String> {
    let mut settings: BTreeMap<(String, u64, u32, u32, u32), Vec<&Row>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.flip_mean_infinite.is_some()) {
        settings
            .entry((r.scene.clone(), r.lights, r.width, r.height, r.msaa))
            .or_default()
            .push(r);
    }
    let mut out = Vec::new();
    for ((scene, lights, w, h, msaa), rs) in &settings {
        let setting = if *msaa > 1 {
            format!("{scene}, {lights} lights, {w}x{h}, {msaa} samples")
        } else {
            format!("{scene}, {lights} lights, {w}x{h}")
        };
        let best_error = rs
            .iter()
            .filter_map(|r| r.flip_mean_infinite)
            .fold(f64::INFINITY, f64::min);
        let mut parts = Vec::new();
        for b in BUDGETS {
            let name = |r: Option<&Row>| match r {
                Some(r) => format!(
                    "`{}` ({:.3} ms, FLIP {:.3})",
                    r.cell,
                    r.gpu_ms_cull_shade.unwrap_or(f64::NAN),
                    r.flip_mean_infinite.unwrap_or(f64::NAN)
                ),
                None => "none".into(),
            };
            let (c, s) = (fastest_within(rs, b, false), fastest_within(rs, b, true));
            let ratio = match (
                c.and_then(|r| r.gpu_ms_cull_shade),
                s.and_then(|r| r.gpu_ms_cull_shade),
            ) {
                (Some(c), Some(s)) if s > 0.0 => {
                    format!("; stochastic takes {:.2}x the conservative time", s / c)
                }
                _ => String::new(),
            };
            parts.push(format!(
                "FLIP <= {b}: conservative {}, stochastic {}{ratio}",
                name(c),
                name(s)
            ));
        }
        out.push(format!(
            "Against infinite range at {setting} (mean FLIP at the reference's exposure; the fastest by culling + shading, `gpu_ms_cull_shade`; lowest error reached {best_error:.3}): {}.",
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
            // Every column the JSON requires; the rest default.
            let json = r#"{"experiment": "e", "cell": "", "scene": "s", "lights": 1, "width": 1,
                "height": 1, "strategy": "x", "backend": "forward", "params": "",
                "gpu_ms_total": null, "gpu_ms_cull": null, "gpu_ms_shade": null,
                "gpu_ms_prepass": null, "cpu_ms_encode": 0.0, "false_negatives": null,
                "false_positive_ratio": null, "lights_per_pixel_mean": null,
                "max_lights_per_tile": null, "dropped_lights": 0, "list_bytes": 0,
                "gbuffer_bytes": 0, "psnr_db": null, "flip_mean": null, "max_abs_error": null,
                "adapter": "", "driver": "", "commit": "", "gpu_ms_total_p10": null,
                "gpu_ms_total_p90": null, "gpu_ms_cull_p10": null, "gpu_ms_cull_p90": null,
                "gpu_ms_shade_p10": null, "gpu_ms_shade_p90": null, "gpu_ms_prepass_p10": null,
                "gpu_ms_prepass_p90": null, "gpu_ms_raster": null, "gpu_ms_compute": null,
                "psnr_db_infinite": null, "flip_mean_infinite": null,
                "max_abs_error_infinite": null, "exact_stride": 1, "frames": 1, "passes": {},
                "index": 0, "id": "", "finished_unix": 0}"#;
            let mut r: Row = serde_json::from_str(json).unwrap();
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
        ];
        let refs: Vec<&Row> = rows.iter().collect();
        assert_eq!(fastest_within(&refs, 0.05, false).unwrap().cell, "slow");
        assert_eq!(fastest_within(&refs, 0.05, true).unwrap().cell, "stoch");
        assert!(fastest_within(&refs, 0.02, true).is_none());
        let f = findings(&rows);
        assert_eq!(f.len(), 1);
        assert!(
            f[0].contains("FLIP <= 0.05: conservative `slow`"),
            "{}",
            f[0]
        );
        assert!(f[0].contains("stochastic takes 0.50x"), "{}", f[0]);
    }
}
