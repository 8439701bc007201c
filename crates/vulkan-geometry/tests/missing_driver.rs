//! With no Vulkan driver, starting fails with `Unavailable` naming what is missing.
//!
//! The loader is pointed at a driver manifest that does not exist (`VK_DRIVER_FILES` /
//! `VK_ICD_FILENAMES`), which is what a machine without a driver looks like. This binary has only
//! this test, so the environment change affects nothing else.

use shadowvol_silhouette::BackendError;

#[test]
fn no_driver_is_reported_as_unavailable() {
    let missing = "/nonexistent/shadowvol_no_driver_icd.json";
    std::env::set_var("VK_DRIVER_FILES", missing);
    std::env::set_var("VK_ICD_FILENAMES", missing);
    match shadowvol_vulkan_geometry::create_backend() {
        Err(BackendError::Unavailable { backend, reason }) => {
            assert_eq!(backend, "vulkan");
            assert!(
                reason.contains("no Vulkan loader") || reason.contains("no Vulkan device"),
                "the reason names the missing piece: {reason}"
            );
        }
        Err(e) => panic!("expected Unavailable, got {e}"),
        Ok(b) => panic!("started without a driver: {:?}", b.info()),
    }
}
