//! Why a frame could not be rendered.

use manylights_cull::CullError;
use manylights_gpu::{GpuError, LightPath};

/// Why [`crate::Renderer::render`] refused or failed a frame.
#[derive(Debug, thiserror::Error)]
pub enum ShadeError {
    /// The device refused or failed (a limit, a missing feature, a lost device).
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// Culling refused or failed.
    #[error(transparent)]
    Cull(#[from] CullError),
    /// The renderer's pipelines were built for another light path than the scene's.
    #[error(
        "a renderer built for {} cannot shade a scene of {}: build the renderer from a scene \
         uploaded for the same light model and lights (GpuScene::upload_with)",
        built.name(),
        scene.name()
    )]
    LightPath {
        /// The renderer's.
        built: LightPath,
        /// The scene's.
        scene: LightPath,
    },
    /// The backend cannot render this frame as asked.
    #[error("backend {backend}: {why}")]
    Backend {
        /// The backend's name.
        backend: &'static str,
        /// Why, and what would.
        why: String,
    },
}
