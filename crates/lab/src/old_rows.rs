//! Rows written by earlier builds, read back by `report` and the budgets: what they lack, made
//! from what they have. Their cell names are the only place that says their swept parameters
//! and light-range settings; the columns of later rows say them instead, and nothing else reads
//! a cell's name for its parameters.

use std::collections::BTreeMap;

use manylights_gpu::timing::Category;

use crate::cells::RADIUS_AXES;
use crate::results::Row;

/// Fills what rows written before them lack: `parameters` and the light-range columns
/// (`radius_value`, `hierarchy_*`, `stochastic_*`, `interleave`) from the cell name, `setting`
/// from its `setting=` part, `shadows` from its `params`, then `scene_lights`
/// ([`backfill_scene_lights`]).
pub fn backfill(rows: &mut [Row]) {
    for r in rows.iter_mut().filter(|r| r.sweep.parameters.is_empty()) {
        if r.cell != "base" {
            r.sweep.parameters = r
                .cell
                .split(',')
                .map(|p| {
                    let (k, v) = p.split_once('=').unwrap_or((p, ""));
                    (k.to_owned(), v.to_owned())
                })
                .collect();
        }
        if let Some(s) = r.sweep.parameters.get("setting") {
            r.sweep.setting = s.clone();
        }
        if r.sweep.radius_value.is_none() {
            range_columns(r);
        }
    }
    for r in rows.iter_mut().filter(|r| r.shadow.shadows.is_empty()) {
        // Rows before the column: `shadows=exact` in their params where they cast rays.
        r.shadow.shadows = if r.params.contains("shadows=exact") {
            "exact"
        } else {
            "off"
        }
        .to_owned();
    }
    backfill_scene_lights(rows);
}

/// The light-range columns of an old row from its cell's range parameter, as
/// `cells::radius_label` wrote it then: `V`, `V/hH[/nR][/gK][/cC][/sL]` for a hierarchy,
/// `V[/albedo][/independent][/accK][/ilN][/exposureX]` for stochastic culling.
fn range_columns(r: &mut Row) {
    let Some((axis, value)) = RADIUS_AXES
        .iter()
        .find_map(|k| r.sweep.parameters.get(*k).map(|v| (*k, v.clone())))
    else {
        return;
    };
    // The name's rule (rows before `radius_rule` have none).
    r.radius_rule = if axis == "radius" { "fixed" } else { axis }.to_owned();
    let mut pieces = value.split('/');
    r.sweep.radius_value = pieces.next().and_then(|v| v.parse().ok());
    let defaults = r.radius_rule == "hierarchy";
    if defaults {
        use manylights_scene::hierarchy::{FINEST_NODES, GROWTH, RAMP};
        r.sweep.hierarchy_finest_nodes = Some(FINEST_NODES);
        r.sweep.hierarchy_growth = Some(GROWTH);
        r.sweep.hierarchy_ramp = Some(RAMP);
    }
    let pieces: Vec<String> = pieces.map(str::to_owned).collect();
    for p in &pieces {
        let num = |prefix: &str| p.strip_prefix(prefix).and_then(|v| v.parse::<f64>().ok());
        if r.radius_rule == "hierarchy" {
            if let Some(h) = num("h") {
                r.sweep.hierarchy_spacing = Some(h);
            } else if let Some(n) = num("n") {
                r.sweep.hierarchy_finest_nodes = Some(n);
            } else if let Some(k) = num("g") {
                r.sweep.hierarchy_growth = Some(k);
            } else if let Some(c) = num("c") {
                r.sweep.hierarchy_ramp = Some(c);
            } else if let Some(l) = num("s") {
                r.sweep.hierarchy_sample_from = Some(l as u32);
            } else if let Some(b) = num("b") {
                r.sweep.hierarchy_spot_bins = Some(b as u32);
            }
        } else if let Some(k) = num("acc") {
            r.accumulate = Some(k as u32);
        } else if let Some(n) = num("il") {
            r.sweep.interleave = Some(n as u32);
        } else if let Some(x) = num("exposure") {
            r.sweep.stochastic_exposure = Some(x);
        } else if p == "albedo" {
            r.sweep.stochastic_bound = Some(p.clone());
        } else if p == "independent" {
            r.sweep.stochastic_draw = Some(p.clone());
        }
    }
}

/// Rows written before `scene_lights` existed: a hierarchy's row takes the light count of a
/// row of another light range whose parameters are the same once the range's is left out
/// (`setting=hall,hierarchy=1/h0.25,variant=v` and `setting=hall,threshold=1,variant=v`).
pub fn backfill_scene_lights(rows: &mut [Row]) {
    fn without_range(r: &Row) -> Vec<(&String, &String)> {
        r.sweep
            .parameters
            .iter()
            .filter(|(k, _)| !RADIUS_AXES.contains(&k.as_str()))
            .collect()
    }
    let known: BTreeMap<(String, Vec<(String, String)>), u64> = rows
        .iter()
        .filter(|r| r.radius_rule != "hierarchy")
        .map(|r| {
            let rest = without_range(r)
                .into_iter()
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect();
            ((r.scene.clone(), rest), r.lights)
        })
        .collect();
    for r in rows.iter_mut() {
        if r.radius_rule != "hierarchy" || r.scene_lights.is_some() {
            continue;
        }
        let rest = without_range(r)
            .into_iter()
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        r.scene_lights = known.get(&(r.scene.clone(), rest)).copied();
    }
}

/// The category of a pass of a row written before rows recorded their passes' categories
/// (`Row::pass_categories`), from its name as the passes were named then.
pub(crate) fn category_before_plans(label: &str) -> Category {
    let surfaces = label == "shade.gbuffer"
        || label == "shade.visibility"
        || label.starts_with("shade.visibility_compute.");
    if label.starts_with("prepass.") || surfaces {
        Category::Prepass
    } else if ["cull.", "scan.", "sort."]
        .iter()
        .any(|p| label.starts_with(p))
    {
        Category::Cull
    } else if label.starts_with("lights.") {
        Category::LightUpdate
    } else {
        Category::Shade
    }
}

#[cfg(test)]
mod tests {
    use crate::results::tests::sample_row;

    /// Rows written before the `shadows` column take it from their `params`.
    #[test]
    fn old_rows_take_shadows_from_their_params() {
        let mut rows = vec![sample_row(), sample_row()];
        rows[0].params = "tile=16;shadows=exact".into();
        rows[1].params = "tile=16".into();
        super::backfill(&mut rows);
        assert_eq!(rows[0].shadow.shadows, "exact");
        assert_eq!(rows[1].shadow.shadows, "off");
    }
}
