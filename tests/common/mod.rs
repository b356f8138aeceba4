//! Shared helpers of the integration tests.

#![allow(dead_code, reason = "each test binary uses a different subset")]

use manylights_gpu::{GpuContext, GpuOptions};

/// The test device. A test that needs a GPU and finds none fails with the adapter list and how
/// to install lavapipe; it never passes silently.
pub fn gpu() -> GpuContext {
    GpuContext::new(&GpuOptions::default()).unwrap_or_else(|e| {
        panic!("this test needs a Vulkan adapter (lavapipe is enough: `apt-get install mesa-vulkan-drivers libvulkan1`): {e}")
    })
}
