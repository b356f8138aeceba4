//! Shading for manylights.
//!
//! Owns: the brute-force reference renderer ([`reference`]), the accuracy reference of every
//! strategy and backend, and the infinite-range reference as a compute pass ([`infinite`]); the shading backends ([`backends`]: forward, deferred, naive forward, visibility; the
//! visibility buffer's CPU oracle in [`visibility`])
//! over any culling strategy; image error metrics ([`accuracy`]: max abs error, RMSE, PSNR,
//! FLIP); and HDR images with their output to EXR and tonemapped PNG ([`image_out`]).
//! Depends on the scene, GPU and culling crates.

pub mod accuracy;
pub mod backends;
mod error;
pub mod frame_plan;
pub mod image_out;
pub mod infinite;
pub mod kinds;
pub mod pipelines;
mod raster;
pub mod reference;
pub mod shade_pass;
pub mod shaders;
pub mod vis_compute;
pub mod visibility;

pub use backends::{Backend, HdrFormat, Renderer, ShadeOutput, VisibilityPass};
pub use error::ShadeError;
pub use image_out::HdrImage;
pub use infinite::InfiniteReference;
pub use kinds::Shadows;
pub use reference::{ReferenceFrame, ReferenceRenderer};
pub use shade_pass::ShadePass;

/// Every shader this crate defines (validated by naga in `tests/shaders.rs`).
pub const SHADERS: &[manylights_gpu::shaders::ShaderDef] = &[
    reference::SHADER,
    reference::SAMPLES_SHADER,
    infinite::SHADER,
    shaders::FORWARD,
    shaders::GBUFFER,
    shaders::GBUFFER_IDS,
    shaders::DEFERRED,
    shaders::DEFERRED_MSAA,
    shaders::VISIBILITY,
    vis_compute::VISIBILITY_COMPUTE,
    vis_compute::VISIBILITY_RESOLVE,
    vis_compute::VISIBILITY_DEPTH,
];
