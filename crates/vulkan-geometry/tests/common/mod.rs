//! Shared test helpers: starting the backend, with a visible skip where no driver exists.

#![allow(dead_code)]

use shadowvol_silhouette::BackendError;
use shadowvol_vulkan_geometry::{VulkanBackend, VulkanOptions};

/// True when running in CI (`CI=true`): a missing driver is then a failure, not a skip.
pub fn in_ci() -> bool {
    shadowvol_silhouette::ci::is_ci()
}

/// Starts the backend, or prints a visible SKIPPED line and returns `None` when Vulkan is not
/// available here. Under `CI=true` an unavailable backend fails the test.
pub fn backend(options: VulkanOptions, test: &str) -> Option<VulkanBackend> {
    match VulkanBackend::new(options) {
        Ok(b) => Some(b),
        Err(e @ BackendError::Unavailable { .. }) => {
            assert!(
                !in_ci(),
                "{test}: the vulkan backend must run in CI, but: {e}"
            );
            eprintln!("SKIPPED {test}: {e}");
            None
        }
        Err(e) => panic!("{test}: starting the vulkan backend failed: {e}"),
    }
}
