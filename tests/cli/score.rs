//! `manylights score`: another program's lists against the exact oracle. Our own gather lists,
//! exported and rewritten in the external format (a tile grid, CSR arrays), score as `cull`
//! measured them; a light taken out of one tile's list is found missing at a pixel of that tile;
//! a light added to a list shows as evaluated beyond need there; bad lists are clear errors.

use std::path::Path;

use npyz::WriterBuilder;

use super::{manylights, succeeds};

fn write_npy<T: npyz::AutoSerialize + Copy>(path: &Path, shape: &[u64], data: &[T]) {
    let mut bytes = Vec::new();
    let mut w = npyz::WriteOptions::new()
        .default_dtype()
        .shape(shape)
        .writer(&mut bytes)
        .begin_nd()
        .unwrap();
    w.extend(data.iter().copied()).unwrap();
    w.finish().unwrap();
    std::fs::write(path, bytes).unwrap();
}

fn read_npy<T: npyz::Deserialize>(path: &Path) -> Vec<T> {
    let bytes = std::fs::read(path).unwrap();
    npyz::NpyFile::new(&bytes[..]).unwrap().into_vec().unwrap()
}

/// Our export's lists as external lists: CSR over the tiles in x-fastest order.
fn lists_of(export: &Path) -> (Vec<u32>, Vec<u32>) {
    let off: Vec<u32> = read_npy(&export.join("bin_offsets.npy"));
    let cnt: Vec<u32> = read_npy(&export.join("bin_counts.npy"));
    let idx: Vec<u32> = read_npy(&export.join("light_indices.npy"));
    let mut offsets = vec![0u32];
    let mut indices = Vec::new();
    for (o, c) in off.iter().zip(&cnt) {
        indices.extend_from_slice(&idx[*o as usize..(o + c) as usize]);
        offsets.push(indices.len() as u32);
    }
    (offsets, indices)
}

fn write_lists(dir: &Path, grid: &str, offsets: &[u32], indices: &[u32]) {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("grid.json"), grid).unwrap();
    write_npy(&dir.join("offsets.npy"), &[offsets.len() as u64], offsets);
    write_npy(&dir.join("indices.npy"), &[indices.len() as u64], indices);
}

fn score(export: &Path, lists: &Path, out: &Path) -> serde_json::Value {
    succeeds(
        &[
            "score",
            "--export",
            export.to_str().unwrap(),
            "--lists",
            lists.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        "score",
    );
    serde_json::from_slice(&std::fs::read(out.join("score.json")).unwrap()).unwrap()
}

#[test]
fn score_reproduces_our_lists_and_finds_planted_errors_where_they_are() {
    let tmp = tempfile::tempdir().unwrap();
    let export = tmp.path().join("export");
    let (w, h) = (96u32, 64u32);
    succeeds(
        &[
            "cull",
            "--scene",
            "atrium",
            "--lights",
            "300",
            "--strategy",
            "tiled-gather",
            "--tile-size",
            "16",
            "--width",
            "96",
            "--height",
            "64",
            "--export",
            export.to_str().unwrap(),
            "--out",
            tmp.path().join("cull").to_str().unwrap(),
        ],
        "cull --export",
    );
    let grid = format!(
        r#"{{"format": "manylights-lists/1", "source": "gather", "width": {w}, "height": {h},
            "dims": [6, 4, 1], "screen": {{"kind": "tiles", "tile_size": [16, 16]}},
            "slicing": {{"kind": "none"}}, "order": "x_fastest"}}"#
    );
    let (offsets, indices) = lists_of(&export);
    assert_eq!(offsets.len(), 6 * 4 + 1);
    let ours = tmp.path().join("ours");
    write_lists(&ours, &grid, &offsets, &indices);
    let s = score(&export, &ours, &tmp.path().join("s0"));
    // The export's own per-pixel counts (the GPU oracle, f32) against the scorer's (f64): the
    // lists are the same; the needed sets may differ in pairs within a hair of a radius.
    let evaluated: Vec<u32> = read_npy(&export.join("evaluated.npy"));
    let needed: Vec<u32> = read_npy(&export.join("needed.npy"));
    let sum = |v: &[u32]| v.iter().map(|&n| u64::from(n)).sum::<u64>();
    assert_eq!(s["false_negatives"], 0, "{s}");
    assert_eq!(s["evaluated"].as_u64().unwrap(), sum(&evaluated), "{s}");
    let n = s["needed"].as_u64().unwrap();
    assert!(
        n > 0 && n.abs_diff(sum(&needed)) <= sum(&needed) / 1000,
        "{s}"
    );
    // Plant a false negative: a light that some pixel of tile (2, 1) needs, taken out of it.
    let pixel_bin: Vec<i32> = read_npy(&export.join("pixel_bin.npy"));
    let tile = 6 + 2;
    let (a, b) = (offsets[tile] as usize, offsets[tile + 1] as usize);
    let mut planted = None;
    for drop in a..b {
        let mut idx = indices.clone();
        let light = idx.remove(drop);
        let mut off = offsets.clone();
        for o in &mut off[tile + 1..] {
            *o -= 1;
        }
        let dir = tmp.path().join("missing");
        write_lists(&dir, &grid, &off, &idx);
        let s = score(&export, &dir, &tmp.path().join("s1"));
        if s["false_negatives"].as_u64().unwrap() > 0 {
            planted = Some((light, s));
            break;
        }
    }
    let (light, s) = planted.expect("some light of the tile's list is needed in it");
    let first = &s["first_false_negatives"][0];
    let (x, y) = (first["x"].as_u64().unwrap(), first["y"].as_u64().unwrap());
    assert_eq!(first["light"].as_u64().unwrap(), u64::from(light), "{s}");
    assert!(
        (32..48).contains(&x) && (16..32).contains(&y),
        "missed at ({x}, {y}), outside the tile"
    );
    // Plant an extra light: one no pixel of tile (2, 1) needs, added to its list, is evaluated
    // beyond need at each of its covered pixels and nowhere else.
    let covered = (0..(w * h) as usize)
        .filter(|&k| pixel_bin[k] == tile as i32)
        .count() as u64;
    let listed: Vec<u32> = indices[a..b].to_vec();
    let extra = (0..300u32).find(|l| !listed.contains(l)).unwrap();
    let mut idx = indices.clone();
    idx.insert(b, extra);
    let mut off = offsets.clone();
    for o in &mut off[tile + 1..] {
        *o += 1;
    }
    let dir = tmp.path().join("extra");
    write_lists(&dir, &grid, &off, &idx);
    let s2 = score(&export, &dir, &tmp.path().join("s2"));
    assert_eq!(s2["false_negatives"], 0);
    assert_eq!(
        s2["evaluated"].as_u64().unwrap(),
        sum(&evaluated) + covered,
        "the extra light counts once at each covered pixel of its tile"
    );
    // Bad lists: an id past the lights, the wrong dtype, a grid for another image.
    let bad = tmp.path().join("bad");
    let mut idx = indices.clone();
    idx[0] = 300;
    write_lists(&bad, &grid, &offsets, &idx);
    let fails = |what: &str, want: &[&str]| {
        let o = manylights(&[
            "score",
            "--export",
            export.to_str().unwrap(),
            "--lists",
            bad.to_str().unwrap(),
            "--out",
            tmp.path().join("s3").to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{what}: {err}");
        for w in want {
            assert!(err.contains(w), "{what}: {err}");
        }
        assert!(
            !tmp.path().join("s3").join("score.json").exists(),
            "{what}: nothing written"
        );
    };
    fails(
        "an id out of range",
        &["indices.npy", "entry 0 is light id 300", "0 to 299"],
    );
    let as_i64: Vec<i64> = indices.iter().map(|&i| i64::from(i)).collect();
    write_npy(&bad.join("indices.npy"), &[as_i64.len() as u64], &as_i64);
    fails("the wrong dtype", &["indices.npy", "dtype <i8", "<u4"]);
    write_lists(
        &bad,
        &grid.replace("\"width\": 96", "\"width\": 128"),
        &offsets,
        &indices,
    );
    fails(
        "another image",
        &["grid.json", "width x height = 128 x 64", "96 x 64"],
    );
}

/// Every strategy's export carries its lists in the scoring format (`lists/`): tiles, and
/// clusters and z-binning's cells sliced as the run sliced them (exponentially and linearly);
/// scored, they give back the run's own figures: no false negatives, the lights each pixel
/// evaluated, and the lights it needs within the f32 oracle's borderline pairs.
#[test]
fn every_strategys_export_scores_as_its_run_measured_it() {
    let tmp = tempfile::tempdir().unwrap();
    for (k, args) in [
        &["--strategy", "tiled-gather", "--tile-size", "16"][..],
        &["--strategy", "depth-mask", "--tile-size", "8"],
        &[
            "--strategy",
            "clustered",
            "--tile-size",
            "16",
            "--slices",
            "12",
        ],
        &[
            "--strategy",
            "clustered",
            "--tile-size",
            "16",
            "--slices",
            "12",
            "--slicing",
            "linear",
        ],
        &["--strategy", "zbin", "--tile-size", "8", "--bins", "32"],
    ]
    .iter()
    .enumerate()
    {
        let export = tmp.path().join(format!("export{k}"));
        let mut cmd = vec![
            "cull",
            "--scene",
            "atrium",
            "--lights",
            "400",
            "--spot-fraction",
            "0.3",
            "--width",
            "80",
            "--height",
            "48",
            "--export",
            export.to_str().unwrap(),
            "--out",
        ];
        let out = tmp.path().join(format!("cull{k}"));
        cmd.push(out.to_str().unwrap());
        cmd.extend_from_slice(args);
        succeeds(&cmd, &format!("{args:?}"));
        let grid: serde_json::Value =
            serde_json::from_slice(&std::fs::read(export.join("lists/grid.json")).unwrap())
                .unwrap();
        let s = score(
            &export,
            &export.join("lists"),
            &tmp.path().join(format!("s{k}")),
        );
        let evaluated: Vec<u32> = read_npy(&export.join("evaluated.npy"));
        let needed: Vec<u32> = read_npy(&export.join("needed.npy"));
        let sum = |v: &[u32]| v.iter().map(|&n| u64::from(n)).sum::<u64>();
        assert_eq!(s["false_negatives"], 0, "{args:?}: {s}");
        assert_eq!(
            s["evaluated"].as_u64().unwrap(),
            sum(&evaluated),
            "{args:?}: {s}\n{grid}"
        );
        let n = s["needed"].as_u64().unwrap();
        assert!(
            n > 0 && n.abs_diff(sum(&needed)) <= sum(&needed) / 1000,
            "{args:?}: {s}"
        );
    }
}
