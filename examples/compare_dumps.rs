//! Two builds side by side, part 2: compares two dumps of `tiny_dump` (A, the build before, and
//! B): each experiment's rows cell by cell (every column but times, ids and commits; numbers
//! within 1e-9 relative, below which a hierarchy's build varies from run to run), each cell's
//! lists as sets of lights (a light by its place, colour and radius bits, as a hierarchy's build
//! numbers its lights in no fixed order) and its images pixel for pixel; prints every
//! difference:
//!
//!     cargo run --release --example compare_dumps -- A B

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn rows(dir: &Path) -> Option<BTreeMap<String, serde_json::Value>> {
    let text = std::fs::read_to_string(dir.join("results.json")).ok()?;
    let v: Vec<serde_json::Value> = serde_json::from_str(&text).ok()?;
    Some(
        v.into_iter()
            .map(|r| (r["cell"].as_str().unwrap().to_owned(), r))
            .collect(),
    )
}

fn npy_u32(p: &Path) -> Option<Vec<u64>> {
    let bytes = std::fs::read(p).ok()?;
    let npy = npyz::NpyFile::new(&bytes[..]).ok()?;
    match npy.dtype() {
        npyz::DType::Plain(t) if t.size_field() == 8 => Some(npy.into_vec::<u64>().ok()?),
        _ => Some(
            npy.into_vec::<u32>()
                .ok()?
                .into_iter()
                .map(u64::from)
                .collect(),
        ),
    }
}

fn npy_f32(p: &Path) -> Option<Vec<f32>> {
    let bytes = std::fs::read(p).ok()?;
    npyz::NpyFile::new(&bytes[..]).ok()?.into_vec::<f32>().ok()
}

/// Each cell's lights as a sorted list of light keys (position, colour, radius bits).
fn lists(cell: &Path) -> Option<Vec<Vec<Vec<u32>>>> {
    let offsets = npy_u32(&cell.join("lists/offsets.npy"))?;
    let indices = npy_u32(&cell.join("lists/indices.npy"))?;
    let pos = npy_f32(&cell.join("light_position.npy"))?;
    let col = npy_f32(&cell.join("light_color.npy"))?;
    let rad = npy_f32(&cell.join("light_radius.npy"))?;
    let key = |i: usize| -> Vec<u32> {
        let mut k: Vec<u32> = pos[3 * i..3 * i + 3].iter().map(|x| x.to_bits()).collect();
        k.extend(col[3 * i..3 * i + 3].iter().map(|x| x.to_bits()));
        k.push(rad[i].to_bits());
        k
    };
    Some(
        offsets
            .windows(2)
            .map(|w| {
                let mut l: Vec<Vec<u32>> = indices[w[0] as usize..w[1] as usize]
                    .iter()
                    .map(|&i| key(i as usize))
                    .collect();
                l.sort();
                l
            })
            .collect(),
    )
}

fn skip(k: &str) -> bool {
    k.starts_with("gpu_ms")
        || k.starts_with("cpu_ms")
        || k.starts_with("ns_per")
        || matches!(
            k,
            "adapter"
                | "driver"
                | "commit"
                | "finished_unix"
                | "passes"
                | "passes_steady"
                | "pass_categories"
                | "index"
                | "id"
                | "reference_infinite_cached"
        )
}

fn close(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    match (a.as_f64(), b.as_f64()) {
        (Some(x), Some(y)) => x == y || (x - y).abs() <= 1e-9 * x.abs().max(y.abs()),
        _ => a == b,
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [a, b] = &args[..] else {
        panic!("usage: compare_dumps A B (two tiny_dump outputs)");
    };
    let (a, b) = (PathBuf::from(a), PathBuf::from(b));
    let mut exps: Vec<_> = std::fs::read_dir(&a)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().to_string()))
        .collect();
    exps.sort();
    let (mut n_rows, mut n_lists, mut n_images, mut diffs) = (0, 0, 0, Vec::new());
    for exp in exps {
        let (pa, pb) = (a.join(&exp), b.join(&exp));
        let (Some(ra), Some(rb)) = (rows(&pa), rows(&pb)) else {
            diffs.push(format!("{exp}: no results on one side"));
            continue;
        };
        if ra.keys().ne(rb.keys()) {
            diffs.push(format!("{exp}: the cells differ"));
        }
        for (cell, x) in &ra {
            let Some(y) = rb.get(cell) else { continue };
            n_rows += 1;
            for (k, v) in x.as_object().unwrap() {
                if skip(k) {
                    continue;
                }
                match y.get(k) {
                    Some(w) if close(v, w) => {}
                    Some(w) => diffs.push(format!("{exp} {cell}: {k}: {v} -> {w}")),
                    None => {}
                }
            }
            let (ia, ib) = (x["id"].as_str().unwrap(), y["id"].as_str().unwrap());
            let (ca, cb) = (pa.join("cells").join(ia), pb.join("cells").join(ib));
            match (lists(&ca), lists(&cb)) {
                (Some(la), Some(lb)) => {
                    n_lists += 1;
                    if la != lb {
                        let bins = la.iter().zip(&lb).filter(|(p, q)| p != q).count();
                        diffs.push(format!(
                            "{exp} {cell}: lists differ in {bins} of {} cells",
                            la.len()
                        ));
                    }
                }
                (None, None) => {}
                _ => diffs.push(format!("{exp} {cell}: lists on one side only")),
            }
            for kind in ["render", "heat"] {
                let fa = pa.join("images").join(format!("{ia}_{kind}.png"));
                let fb = pb.join("images").join(format!("{ib}_{kind}.png"));
                match (image::open(&fa), image::open(&fb)) {
                    (Ok(p), Ok(q)) => {
                        n_images += 1;
                        let (p, q) = (p.to_rgb8(), q.to_rgb8());
                        let differ = p.pixels().zip(q.pixels()).filter(|(s, t)| s != t).count();
                        if p.dimensions() != q.dimensions() || differ > 0 {
                            let max = p
                                .pixels()
                                .zip(q.pixels())
                                .flat_map(|(s, t)| (0..3).map(move |c| s[c].abs_diff(t[c])))
                                .max()
                                .unwrap_or(0);
                            diffs.push(format!("{exp} {cell}: {kind} image: {differ} pixels differ (at most {max} levels)"));
                        }
                    }
                    (Err(_), Err(_)) => {}
                    _ => diffs.push(format!("{exp} {cell}: {kind} image on one side only")),
                }
            }
        }
    }
    println!(
        "{n_rows} rows, {n_lists} cells' lists, {n_images} images compared; {} differences",
        diffs.len()
    );
    for d in &diffs {
        println!("{d}");
    }
}
