//! The `opencl` silhouette backend (work in progress: see its issue).

use shadowvol_silhouette::{BackendError, SilhouetteBackend};

/// Starts the `opencl` backend.
///
/// # Errors
/// [`BackendError::Unavailable`] naming what is missing.
pub fn create_backend() -> Result<Box<dyn SilhouetteBackend>, BackendError> {
    Err(BackendError::Unavailable {
        backend: "opencl",
        reason: "not implemented in this build yet".to_owned(),
    })
}
