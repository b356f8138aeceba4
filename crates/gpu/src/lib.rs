//! The GPU core of manylights.
//!
//! Owns: the headless wgpu device ([`GpuContext`]: adapter choice, feature negotiation, limits),
//! per-pass GPU timing with timestamp queries ([`timing`]), buffer and texture readback
//! ([`readback`]), the composition of WGSL from the files under `shaders/` ([`shaders`]), the
//! host-side mirrors of the shader structs ([`layout`]), the scene on the GPU ([`GpuScene`]),
//! moving its lights each frame ([`motion`]), stochastic light culling's ranges drawn each frame ([`stochastic`]), the depth prepass ([`prepass`]) that culling strategies and shading backends share, and the depth culling takes its bounds from where lists are looked up off the depth buffer's samples ([`lookup_bounds`]: MSAA, transparent surfaces).
//!
//! Depends on the scene crate and wgpu; knows nothing of culling strategies or backends.

pub mod bvh;
pub mod context;
pub mod hierarchy;
pub mod layout;
pub mod light_model;
pub mod lookup_bounds;
pub mod motion;
pub mod pipeline;
pub mod prepass;
pub mod readback;
pub mod scene;
pub mod shaders;
pub mod stochastic;
pub mod timing;

pub use context::{GpuContext, GpuError, GpuOptions};
pub use light_model::{LightModel, LightPath};
pub use scene::{GpuScene, ShadowFrames};
