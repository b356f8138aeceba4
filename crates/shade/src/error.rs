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
    /// Shadows asked of a scene whose BVH is not built.
    #[error(
        "shadows {}: the scene has no BVH of its opaque triangles to trace shadow rays through; \
         build it after the upload (GpuScene::build_bvh)",
        shadows.name()
    )]
    NoBvh {
        /// The renderer's shadows.
        shadows: crate::Shadows,
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
