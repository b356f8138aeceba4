//! glTF import against real files that no one here wrote: Debian's `assimp-testmodels`.
//!
//! The expected triangle count of `2CylinderEngine.glb` (121,496) was computed independently
//! from the file's JSON chunk: the index-accessor counts / 3 of every mesh primitive, summed over
//! the node instances reached from the default scene (29 meshes, 75,730 unique triangles).

use std::path::{Path, PathBuf};

use manylights_scene::gltf_import::{GltfOptions, load};

const MODELS: &str = "/usr/share/assimp/models/glTF2";

fn model(rel: &str) -> PathBuf {
    let p = Path::new(MODELS).join(rel);
    assert!(
        p.exists(),
        "{} is missing: install Debian's assimp-testmodels (`apt-get install assimp-testmodels`), as .ci/run does",
        p.display()
    );
    p
}

#[test]
fn good_file_imports_with_its_real_triangle_count() {
    let path = model("2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
    let (scene, report) = load(&path, &GltfOptions::default()).unwrap();
    assert_eq!(scene.triangle_count(), 121_496);
    assert_eq!(report.skipped_primitives, 0);
    scene.validate().unwrap();
    let b = scene.bounds();
    assert!(b.is_valid() && b.extent().max_element() > 0.0);
}

#[test]
fn malformed_files_give_an_error_naming_file_and_problem() {
    let cases = [
        ("IndexOutOfRange/IndexOutOfRange.gltf", "out of range"),
        ("IndexOutOfRange/AllIndicesOutOfRange.gltf", "out of range"),
        ("MissingBin/BoxTextured.gltf", "buffer"),
        ("SchemaFailures/sceneWrongType.gltf", "cannot parse"),
        (
            "BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb",
            "non-finite position",
        ),
        ("RecursiveNodes/RecursiveNodes.gltf", "cycle"),
        ("IncorrectVertexArrays/Cube.gltf", "not a multiple of 3"),
    ];
    for (rel, problem) in cases {
        let path = model(rel);
        let err = match load(&path, &GltfOptions::default()) {
            Ok((s, _)) => panic!(
                "{rel} imported ({} triangles) but is malformed",
                s.triangle_count()
            ),
            Err(e) => e.to_string(),
        };
        assert!(
            err.contains(&path.display().to_string()),
            "{rel}: error does not name the file: {err}"
        );
        assert!(
            err.contains(problem),
            "{rel}: expected `{problem}` in: {err}"
        );
    }
}

#[test]
fn missing_file_is_an_error() {
    let err = load(Path::new("/nonexistent/scene.glb"), &GltfOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("/nonexistent/scene.glb") && err.contains("no such file"),
        "{err}"
    );
}
