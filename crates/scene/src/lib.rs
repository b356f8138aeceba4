//! The scene model of manylights: everything culling and shading read, and nothing more.
//!
//! This crate owns the camera (with its matrix conventions), triangle meshes with one material
//! index per primitive, materials (a base colour and one of five material models, [`Brdf`],
//! with their f64 definitions in [`brdf`]), point and spot lights with the one falloff function of
//! the project, deterministic light generators, moving lights ([`motion`]), the procedural scenes (`atrium`, `pillars`,
//! `topdown`, `city`, `cis5650`) and glTF import. It must not depend on wgpu or any GPU crate: the CPU
//! oracles of every GPU pass are written against these types alone.

pub mod brdf;
mod builder;
pub mod camera;
pub mod error;
pub mod exposure;
pub mod generate;
pub mod gltf_import;
pub mod hierarchy;
pub mod light;
pub mod material;
pub mod mesh;
pub mod motion;
pub mod occluders;
mod placement;
pub mod procedural;
pub mod radius;
pub mod ray;
pub mod shadow_estimate;
pub mod real;
pub mod stochastic;

pub use camera::{Camera, Projection};
pub use error::SceneError;
pub use generate::{LightGenerator, LightSpec, RadiusRule};
pub use light::{Light, LightKind};
pub use material::{Brdf, Material, Model};
pub use mesh::{Aabb, Primitive, Scene};
pub use motion::Motion;
