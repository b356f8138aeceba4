//! Shading for manylights.
//!
//! Owns: the brute-force reference renderer ([`reference`]), the accuracy reference of every
//! later strategy and backend; and the images it produces with their output to EXR and
//! tonemapped PNG ([`image_out`]). The forward and deferred backends join this crate later.
//! Depends on the scene and GPU crates.

pub mod image_out;
pub mod reference;

pub use image_out::HdrImage;
pub use reference::{ReferenceFrame, ReferenceRenderer};

/// Every shader this crate defines (validated by naga in `tests/shaders.rs`).
pub const SHADERS: &[manylights_gpu::shaders::ShaderDef] = &[reference::SHADER];
