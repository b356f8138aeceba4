//! Typed errors of the scene crate. Each names the offending input and what is accepted.

use std::path::PathBuf;

/// Everything that can go wrong while building, generating or importing a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A procedural scene name that does not exist.
    #[error("unknown scene `{name}`; accepted: {accepted}")]
    UnknownScene {
        /// The name that was asked for.
        name: String,
        /// The accepted names, comma separated.
        accepted: String,
    },
    /// A value outside its accepted range.
    #[error("invalid {field} = {value}: {accepted}")]
    InvalidValue {
        /// Which field (for example `lights[3].radius` or `camera.fov_y_deg`).
        field: String,
        /// The value as given.
        value: String,
        /// What is accepted.
        accepted: String,
    },
    /// A glTF file that could not be imported.
    #[error("glTF import of {}: {problem}", path.display())]
    Gltf {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        problem: String,
    },
    /// A vendored scene whose file is not the one committed.
    #[error(
        "{}: SHA-256 {found}, but scenes/SHA256SUMS has {expected}: the file is damaged or \
         another one (restore it from the repository)",
        path.display()
    )]
    Checksum {
        /// The file.
        path: PathBuf,
        /// The committed checksum.
        expected: String,
        /// The file's.
        found: String,
    },
}

impl SceneError {
    /// Shorthand for [`SceneError::InvalidValue`].
    pub fn invalid(
        field: impl Into<String>,
        value: impl ToString,
        accepted: impl Into<String>,
    ) -> Self {
        Self::InvalidValue {
            field: field.into(),
            value: value.to_string(),
            accepted: accepted.into(),
        }
    }
}
