//! The real scenes vendored in the repository's `scenes/` (`scenes/NOTICE.md`: authors,
//! sources, licences): Sponza and four interiors that rendering papers use, as xz-compressed
//! glTF binaries, read by name ([`load`]) with each file's checksum checked against the one
//! committed beside it (`scenes/SHA256SUMS`, the same values as [`REAL_SCENES`]).
//!
//! The folder is found at run time, so that a binary built elsewhere (the GPU machine's copy of
//! the tree) finds it: `MANYLIGHTS_SCENES` where it is set, else `scenes/` in the working
//! directory, else the repository this crate was built from.

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use crate::Scene;
use crate::error::SceneError;
use crate::gltf_import::{self, GltfOptions, ImportReport};

/// The environment variable naming the folder of the real scenes.
pub const SCENES_ENV: &str = "MANYLIGHTS_SCENES";

/// A vendored scene.
#[derive(Clone, Copy, Debug)]
pub struct RealScene {
    /// Its name (`Real("sponza")`, `--scene sponza`).
    pub name: &'static str,
    /// Its file in `scenes/`.
    pub file: &'static str,
    /// The file's SHA-256, as `scenes/SHA256SUMS` has it.
    pub sha256: &'static str,
    /// The scene's title and author (`scenes/NOTICE.md`).
    pub credit: &'static str,
}

/// The five vendored scenes, smallest first.
pub const REAL_SCENES: [RealScene; 5] = [
    RealScene {
        name: "sponza",
        file: "sponza.glb.xz",
        sha256: "9e1c5f92e8d4b19af0e154cd3b681671137ea9acdd0368c6be50d1deb780d255",
        credit: "Sponza atrium by Marko Dabrovic",
    },
    RealScene {
        name: "staircase",
        file: "staircase.glb.xz",
        sha256: "1f5dffbbb180563ffe61e26d5ac08051b70f3cf5153879d4e17f36b52613f670",
        credit: "The Wooden Staircase by Wig42 (CC BY 3.0)",
    },
    RealScene {
        name: "dining-room",
        file: "dining-room.glb.xz",
        sha256: "3b67ff4831e63b1b92c6ab3eeb2bb52ad8b7744bf24d6db0e9f6692e82ccb3c0",
        credit: "The Breakfast Room by Wig42 (CC BY 3.0)",
    },
    RealScene {
        name: "bathroom",
        file: "bathroom.glb.xz",
        sha256: "e10658b99eb357dca1c610551b9daddab2c64659f65c36db7a8c993d5dd641ee",
        credit: "Contemporary Bathroom by Mareck (CC0)",
    },
    RealScene {
        name: "kitchen",
        file: "kitchen.glb.xz",
        sha256: "6f666d0a1acca82ee969cd7ec86944eb49247db9f56fa347d0173e870c78a2f0",
        credit: "Country Kitchen by Jay-Artist (CC BY 3.0)",
    },
];

/// The vendored scene called `name`.
pub fn find(name: &str) -> Option<&'static RealScene> {
    REAL_SCENES.iter().find(|s| s.name == name)
}

/// The real scenes' names, comma separated (for errors that list what is accepted).
pub fn names() -> String {
    REAL_SCENES.map(|s| s.name).join(", ")
}

/// The folder of the real scenes: `MANYLIGHTS_SCENES`, else `scenes/` here, else the
/// repository's; an error naming each place tried where none holds the scenes' checksums.
pub fn scenes_dir() -> Result<PathBuf, SceneError> {
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let tried: Vec<PathBuf> = match std::env::var_os(SCENES_ENV).filter(|v| !v.is_empty()) {
        // A folder named on purpose is the only one tried.
        Some(v) => vec![PathBuf::from(v)],
        None => vec![PathBuf::from("scenes"), built],
    };
    tried
        .iter()
        .find(|d| d.join("SHA256SUMS").is_file())
        .cloned()
        .ok_or_else(|| SceneError::Gltf {
            path: tried[0].clone(),
            problem: format!(
                "no folder of real scenes (with SHA256SUMS) at {}: run from the repository \
                 root or set {SCENES_ENV}",
                tried
                    .iter()
                    .map(|d| d.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })
}

/// The path of the vendored scene `name`.
pub fn path(name: &str) -> Result<PathBuf, SceneError> {
    let s = find(name).ok_or_else(|| SceneError::UnknownScene {
        name: name.into(),
        accepted: names(),
    })?;
    Ok(scenes_dir()?.join(s.file))
}

/// The vendored scene `name`, its file's checksum checked first.
pub fn load(name: &str, options: &GltfOptions) -> Result<(Scene, ImportReport), SceneError> {
    let s = find(name).ok_or_else(|| SceneError::UnknownScene {
        name: name.into(),
        accepted: names(),
    })?;
    load_from(&scenes_dir()?, s, options)
}

/// The vendored scene `s` from the folder `dir`, its file's checksum checked first.
pub fn load_from(
    dir: &Path,
    s: &RealScene,
    options: &GltfOptions,
) -> Result<(Scene, ImportReport), SceneError> {
    let path = dir.join(s.file);
    let bytes = std::fs::read(&path).map_err(|e| SceneError::Gltf {
        path: path.clone(),
        problem: format!("cannot read: {e}"),
    })?;
    let found = hex(&Sha256::digest(&bytes));
    if found != s.sha256 {
        return Err(SceneError::Checksum {
            path,
            expected: s.sha256.into(),
            found,
        });
    }
    gltf_import::load_bytes(&path, &bytes, options)
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}
