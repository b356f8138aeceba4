//! The vendored real scenes (`scenes/`): their checksums are the committed ones, each loads by
//! name, compressed, with the triangles, materials and extent `scenes/NOTICE.md` gives and a
//! camera of its own; a damaged file and an unknown name are errors that say which and why.

use std::path::Path;

use manylights_scene::SceneError;
use manylights_scene::gltf_import::{self, GltfOptions};
use manylights_scene::real::{self, REAL_SCENES};

fn scenes() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes"))
}

#[test]
fn checksums_are_the_committed_ones_and_every_file_is_a_scene() {
    let sums = std::fs::read_to_string(scenes().join("SHA256SUMS")).unwrap();
    let listed: Vec<(&str, &str)> = sums
        .lines()
        .filter_map(|l| l.split_once("  "))
        .map(|(sum, file)| (file, sum))
        .collect();
    assert_eq!(listed.len(), REAL_SCENES.len(), "{sums}");
    for s in &REAL_SCENES {
        assert!(listed.contains(&(s.file, s.sha256)), "{}: {sums}", s.file);
    }
    for e in std::fs::read_dir(scenes()).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        if name.ends_with(".xz") {
            assert!(
                REAL_SCENES.iter().any(|s| s.file == name),
                "scenes/{name} is no RealScene"
            );
        }
    }
}

#[test]
fn every_real_scene_loads_by_name_as_its_notice_describes_it() {
    // (name, triangles, materials, box in metres) from scenes/NOTICE.md.
    let expected = [
        ("sponza", 66_445, 19, [34.8, 16.6, 15.6]),
        ("staircase", 249_941, 23, [6.6, 7.3, 10.3]),
        ("dining-room", 269_536, 15, [12.0, 9.3, 15.2]),
        ("bathroom", 579_386, 31, [5.2, 2.8, 2.5]),
        ("kitchen", 1_404_393, 81, [6.9, 3.4, 8.7]),
    ];
    for (name, triangles, materials, size) in expected {
        let (scene, report) = real::load(name, &GltfOptions::default()).unwrap();
        assert!(!report.framed_camera, "{name}: no camera of its own");
        assert_eq!(scene.name, name);
        assert_eq!(scene.triangle_count(), triangles, "{name}");
        // One primitive a material (the importer adds a default material besides).
        assert_eq!(scene.primitives.len(), materials, "{name}");
        let b = scene.bounds();
        let extent = b.max - b.min;
        let mut sorted_got = extent.to_array();
        let mut sorted_want = size;
        sorted_got.sort_by(f32::total_cmp);
        sorted_want.sort_by(f32::total_cmp);
        for (g, w) in sorted_got.iter().zip(sorted_want) {
            assert!(
                (g - w).abs() < 0.1,
                "{name}: extent {extent} against {size:?}"
            );
        }
        assert!(scene.lights.is_empty(), "{name}: lights are generated");
        scene.validate().unwrap();
    }
}

#[test]
fn a_compressed_path_loads_as_the_named_scene() {
    let by_path = gltf_import::load(&scenes().join("sponza.glb.xz"), &GltfOptions::default())
        .unwrap()
        .0;
    let by_name = real::load("sponza", &GltfOptions::default()).unwrap().0;
    assert_eq!(by_path.triangle_count(), by_name.triangle_count());
    assert_eq!(by_path.camera.position, by_name.camera.position);
}

#[test]
fn a_damaged_file_fails_its_checksum_and_an_unknown_name_lists_the_names() {
    let tmp = tempfile::tempdir().unwrap();
    let s = real::find("sponza").unwrap();
    let mut bytes = std::fs::read(scenes().join(s.file)).unwrap();
    let k = bytes.len() / 2;
    bytes[k] ^= 1;
    std::fs::write(tmp.path().join(s.file), &bytes).unwrap();
    let err = real::load_from(tmp.path(), s, &GltfOptions::default()).unwrap_err();
    assert!(matches!(err, SceneError::Checksum { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.contains("sponza.glb.xz") && msg.contains(s.sha256) && msg.contains("SHA256SUMS"),
        "{msg}"
    );
    let err = real::load("sponsa", &GltfOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("sponsa") && err.contains("sponza, staircase"),
        "{err}"
    );
}
