//! Result rows on disk: a cell's row as `cells/<id>.json` when it finishes, every row in
//! `results.csv` (the columns of [`COLUMNS`] in order) and `results.json`, reading them back,
//! and merging the shards of one experiment.

use std::collections::BTreeMap;
use std::path::Path;

use crate::results::{COLUMNS, Row};
use crate::{LabError, write_atomic};

fn csv_field(v: &serde_json::Value) -> String {
    let s = match v {
        serde_json::Value::Null => String::new(),
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Number(n) => n.to_string(),
        other => other.to_string(),
    };
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s
    }
}

/// The rows as CSV text with a header.
pub fn to_csv(rows: &[Row]) -> String {
    let mut out = COLUMNS.join(",");
    out.push('\n');
    for r in rows {
        let v = serde_json::to_value(r).expect("rows serialise");
        let fields: Vec<String> = COLUMNS.iter().map(|c| csv_field(&v[*c])).collect();
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    out
}

/// The rows of a run directory: its cells, or where it has none (a copy kept for the record),
/// its `results.json`.
pub fn load_rows(dir: &Path) -> Result<Vec<Row>, LabError> {
    let rows = load_cells(dir)?;
    if !rows.is_empty() {
        return Ok(rows);
    }
    let path = dir.join("results.json");
    match std::fs::read_to_string(&path) {
        Ok(text) => serde_json::from_str(&text).map_err(|e| LabError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        }),
        Err(_) => Ok(Vec::new()),
    }
}

/// Reads every persisted cell of `dir` (`dir/cells/*.json`), sorted by index.
pub fn load_cells(dir: &Path) -> Result<Vec<Row>, LabError> {
    let cells = dir.join("cells");
    let mut rows = Vec::new();
    let entries = match std::fs::read_dir(&cells) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(rows),
        Err(e) => {
            return Err(LabError::Io {
                path: cells.display().to_string(),
                message: e.to_string(),
            });
        }
    };
    for e in entries {
        let path = e
            .map_err(|e| LabError::Io {
                path: cells.display().to_string(),
                message: e.to_string(),
            })?
            .path();
        // Only finished cells: temporary files of an interrupted write are ignored.
        if path.extension().is_some_and(|x| x == "json") {
            let text = std::fs::read_to_string(&path).map_err(|e| LabError::Io {
                path: path.display().to_string(),
                message: e.to_string(),
            })?;
            let row: Row = serde_json::from_str(&text).map_err(|e| LabError::Io {
                path: path.display().to_string(),
                message: format!("not a result cell: {e}"),
            })?;
            rows.push(row);
        }
    }
    rows.sort_by(|a, b| (a.index, &a.id).cmp(&(b.index, &b.id)));
    Ok(rows)
}

/// Writes one finished cell.
pub fn save_cell(dir: &Path, row: &Row) -> Result<(), LabError> {
    let path = dir.join("cells").join(format!("{}.json", row.id));
    write_atomic(
        &path,
        serde_json::to_string_pretty(row)
            .expect("rows serialise")
            .as_bytes(),
    )
}

/// Writes `results.csv` and `results.json` for `rows`.
pub fn write_results(dir: &Path, rows: &[Row]) -> Result<(), LabError> {
    write_atomic(&dir.join("results.csv"), to_csv(rows).as_bytes())?;
    write_atomic(
        &dir.join("results.json"),
        serde_json::to_string_pretty(rows)
            .expect("rows serialise")
            .as_bytes(),
    )
}

/// Joins the cells of several run directories (shards of one experiment) into `out`: copies
/// `experiment.ron` and `meta.json` from the first (its `shard` replaced by `merged_shards`, the
/// inputs' shards), every cell file, and writes the results.
/// Two shards holding the same cell with different contents is an error.
pub fn merge(inputs: &[&Path], out: &Path) -> Result<Vec<Row>, LabError> {
    let first = inputs
        .first()
        .ok_or_else(|| LabError::refused("merge", "no input directories"))?;
    let mut by_id: BTreeMap<String, Row> = BTreeMap::new();
    let mut experiment: Option<String> = None;
    for dir in inputs {
        let exp =
            std::fs::read_to_string(dir.join("experiment.ron")).map_err(|e| LabError::Io {
                path: dir.join("experiment.ron").display().to_string(),
                message: format!("{e} (is this a run directory?)"),
            })?;
        match &experiment {
            None => experiment = Some(exp),
            Some(e) if *e != exp => {
                return Err(LabError::refused(
                    "merge",
                    format!(
                        "{} ran a different experiment file than {}",
                        dir.display(),
                        first.display()
                    ),
                ));
            }
            Some(_) => {}
        }
        for row in load_cells(dir)? {
            if let Some(prev) = by_id.get(&row.id) {
                if prev.cell != row.cell {
                    return Err(LabError::refused(
                        "merge",
                        format!(
                            "cell id {} names `{}` and `{}`",
                            row.id, prev.cell, row.cell
                        ),
                    ));
                }
            }
            by_id.insert(row.id.clone(), row);
        }
    }
    let mut rows: Vec<Row> = by_id.into_values().collect();
    rows.sort_by_key(|r| r.index);
    write_atomic(
        &out.join("experiment.ron"),
        experiment.unwrap_or_default().as_bytes(),
    )?;
    if let Ok(meta) = std::fs::read(first.join("meta.json")) {
        // The first input's meta, with the shards joined in place of its own.
        let meta = match serde_json::from_slice::<serde_json::Value>(&meta) {
            Ok(serde_json::Value::Object(mut m)) => {
                let shards: Vec<serde_json::Value> = inputs
                    .iter()
                    .filter_map(|d| std::fs::read(d.join("meta.json")).ok())
                    .filter_map(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
                    .filter_map(|v| v.get("shard").cloned())
                    .filter(|v| !v.is_null())
                    .collect();
                m.remove("shard");
                m.insert("merged_shards".into(), shards.into());
                serde_json::to_vec_pretty(&m).unwrap_or(meta)
            }
            _ => meta,
        };
        write_atomic(&out.join("meta.json"), &meta)?;
    }
    for r in &rows {
        save_cell(out, r)?;
    }
    for dir in inputs {
        let images = dir.join("images");
        if let Ok(entries) = std::fs::read_dir(&images) {
            for e in entries.flatten() {
                if let Ok(bytes) = std::fs::read(e.path()) {
                    write_atomic(&out.join("images").join(e.file_name()), &bytes)?;
                }
            }
        }
    }
    write_results(out, &rows)?;
    Ok(rows)
}
