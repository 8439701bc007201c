//! The renderer's errors.

use crate::InvalidCamera;
use shadowvol_mesh_topology::MeshError;
use shadowvol_silhouette::BackendError;

/// Errors from rendering.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// No usable GPU adapter (install a Vulkan driver, for example Mesa lavapipe).
    #[error("no GPU adapter: {0}")]
    NoAdapter(String),
    /// The device failed (out of memory, validation, lost).
    #[error("GPU device error: {0}")]
    Device(String),
    /// The silhouette backend failed.
    #[error("silhouette backend: {0}")]
    Backend(#[from] BackendError),
    /// An object's mesh is invalid.
    #[error("object {object:?}: {source}")]
    Mesh {
        /// Object name.
        object: String,
        /// What is wrong.
        source: MeshError,
    },
    /// The device lacks a feature, capability or limit the GPU pipeline (or the map pipeline's
    /// PCSS) needs (named).
    #[error("unsupported device: {0}")]
    Unsupported(String),
    /// Bad parameters (size, camera, light).
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// The scene does not fit a buffer or storage binding of the device (both numbers named).
    /// The map pipeline returns it for surfaces beyond one buffer. The resident pass returns it
    /// for a scene array beyond one binding, and the GPU pipeline then uploads the scene in
    /// parts; the host pipeline draws from several buffers, so it only refuses a device whose
    /// buffers cannot hold one triangle.
    #[error("too large for the device: {0}")]
    TooLarge(String),
    /// Writing an image failed.
    #[error("image {path}: {message}")]
    Image {
        /// The file.
        path: String,
        /// What failed.
        message: String,
    },
}

impl From<InvalidCamera> for RenderError {
    fn from(e: InvalidCamera) -> Self {
        RenderError::InvalidInput(e.0)
    }
}
