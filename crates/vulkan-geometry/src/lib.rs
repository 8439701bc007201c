//! The `vulkan` silhouette backend (work in progress: see its issue).

use shadowvol_silhouette::{BackendError, SilhouetteBackend};

/// Starts the `vulkan` backend.
///
/// # Errors
/// [`BackendError::Unavailable`] naming what is missing.
pub fn create_backend() -> Result<Box<dyn SilhouetteBackend>, BackendError> {
    Err(BackendError::Unavailable {
        backend: "vulkan",
        reason: "not implemented in this build yet".to_owned(),
    })
}
