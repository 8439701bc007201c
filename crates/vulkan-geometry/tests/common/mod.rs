//! Shared test helpers: starting the backend, with a visible skip where no driver exists.

use shadowvol_test_support::Skip;
use shadowvol_vulkan_geometry::{VulkanBackend, VulkanOptions};

/// Starts the backend, or a visible skip (`ignored (vulkan backend unavailable: ...)`; a failure under
/// CI, see [`shadowvol_test_support::skip`]) when Vulkan, or a layer `options` asks for, is not
/// available here. Any other start error fails the test.
pub fn backend(options: VulkanOptions) -> Result<VulkanBackend, Skip> {
    shadowvol_test_support::started("vulkan", VulkanBackend::new(options))
}
