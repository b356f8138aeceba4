//! The one-light reproduction of the row class of Bevy's misses (docs/reports/referee-bevy):
//! bevy_light 0.20.1's sphere refinement drops a row that the light's sphere reaches. A point
//! light at view (-4.273, 6.774, -15.94), range 2.5; 60 degrees vertical field of view, 1280 x
//! 720; Bevy's default grid (17 x 9 x 24, first slice 5 m) with its far bound at 29.05 m (the
//! Forward+ frame's, given as a constant, since one light would move it). Cluster (5, 0, 13)
//! holds the view point of pixel (442, 47) at depth 13.5006 m, 0.976 of the range from the
//! light, yet its list lacks the light; (5, 1, 13) and (5, 0, 14) list it. This test pins the
//! finding to the pinned version: if Bevy's lists change, it fails and the report must be
//! checked again.

use std::path::Path;
use std::process::Command;

use npyz::WriterBuilder;

fn npy<T: npyz::AutoSerialize + Copy>(path: &Path, shape: &[u64], data: &[T]) {
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

fn read_u32(path: &Path) -> Vec<u32> {
    let bytes = std::fs::read(path).unwrap();
    npyz::NpyFile::new(&bytes[..]).unwrap().into_vec().unwrap()
}

const W: u32 = 1280;
const H: u32 = 720;
const LIGHT: [f64; 3] = [-4.273, 6.774, -15.94];
const RANGE: f64 = 2.5;

/// An export of one point light seen by a camera at the origin looking down -z.
fn export(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    let (near, far) = (0.1f32, 100.0f32);
    let f = 1.0 / 30f32.to_radians().tan();
    // Row-major, right-handed, NDC z in [0, 1] (the export's convention).
    let clip_from_view: [f32; 16] = [
        f * H as f32 / W as f32,
        0.0,
        0.0,
        0.0,
        0.0,
        f,
        0.0,
        0.0,
        0.0,
        0.0,
        far / (near - far),
        near * far / (near - far),
        0.0,
        0.0,
        -1.0,
        0.0,
    ];
    let identity: [f32; 16] = std::array::from_fn(|k| if k % 5 == 0 { 1.0 } else { 0.0 });
    npy(
        &dir.join("depth.npy"),
        &[u64::from(H), u64::from(W)],
        &vec![0.5f32; (W * H) as usize],
    );
    npy(&dir.join("clip_from_view.npy"), &[4, 4], &clip_from_view);
    npy(&dir.join("clip_from_world.npy"), &[4, 4], &clip_from_view);
    npy(&dir.join("view_from_world.npy"), &[4, 4], &identity);
    npy(
        &dir.join("light_position.npy"),
        &[1, 3],
        &LIGHT.map(|v| v as f32),
    );
    npy(&dir.join("light_radius.npy"), &[1], &[RANGE as f32]);
    npy(&dir.join("light_kind.npy"), &[1], &[0u32]);
    npy(
        &dir.join("light_direction.npy"),
        &[1, 3],
        &[0.0f32, 0.0, -1.0],
    );
    npy(&dir.join("light_cos_inner.npy"), &[1], &[1.0f32]);
    npy(&dir.join("light_cos_outer.npy"), &[1], &[1.0f32]);
}

#[test]
fn bevys_sphere_refinement_drops_a_row_the_light_reaches() {
    let tmp = std::env::temp_dir().join(format!("bevy-repro-{}", std::process::id()));
    let dir = tmp.join("export");
    export(&dir);
    let out = tmp.join("lists");
    let o = Command::new(env!("CARGO_BIN_EXE_manylights-bevy-referee"))
        .args([dir.as_os_str(), out.as_os_str()])
        .args(["--far-z", "29.05"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let grid: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("grid.json")).unwrap()).unwrap();
    assert_eq!(grid["dims"], serde_json::json!([17, 9, 24]));
    let (near, far) = (
        grid["slicing"]["near"].as_f64().unwrap(),
        grid["slicing"]["far"].as_f64().unwrap(),
    );
    assert!(
        (near - 5.0).abs() < 1e-5 && (far - 29.05).abs() < 1e-4,
        "{grid}"
    );

    // The pixel's view point at its depth, and its cluster as Bevy's shader looks it up.
    let (px, py, depth) = (442u32, 47u32, 13.5006f64);
    let t = 30f64.to_radians().tan();
    let ndc = (
        (f64::from(px) + 0.5) / f64::from(W) * 2.0 - 1.0,
        1.0 - (f64::from(py) + 0.5) / f64::from(H) * 2.0,
    );
    let p = [
        ndc.0 * t * f64::from(W) / f64::from(H) * depth,
        ndc.1 * t * depth,
        -depth,
    ];
    let dist = (0..3)
        .map(|k| (p[k] - LIGHT[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(dist < 0.98 * RANGE, "the point is {dist} m from the light");
    let cx = (2 * px + 1) * 17 / (2 * W);
    let cy = (2 * py + 1) * 9 / (2 * H);
    let cz = 1 + ((depth / near).ln() * 23.0 / (far / near).ln()).floor() as u32;
    assert_eq!((cx, cy, cz), (5, 0, 13));

    let offsets = read_u32(&out.join("offsets.npy"));
    let lists = |x: u32, y: u32, z: u32| {
        let c = ((y * 17 + x) * 24 + z) as usize;
        offsets[c + 1] > offsets[c]
    };
    assert!(
        !lists(5, 0, 13),
        "Bevy now lists the light in (5, 0, 13): the row class may be fixed; check the report"
    );
    assert!(lists(5, 1, 13) && lists(5, 0, 14), "the neighbours list it");
    let _ = std::fs::remove_dir_all(&tmp);
}
