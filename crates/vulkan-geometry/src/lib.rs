//! The `vulkan` silhouette backend: the paper's geometry-shader path on Vulkan (ash), headless.
//!
//! * [`VulkanBackend`] implements [`SilhouetteBackend`]: one point per (edge, light) goes through
//!   `shaders/silhouette_gs.geom`, which reads the edge, its opposite vertices, the positions and
//!   the object-space light from storage buffers, computes the multiplicity `m` in any
//!   [`shadowvol_robust_math::Accuracy`] mode, and writes it to a storage buffer. Exact mode uses a
//!   certified `f64` filter on the device (the `f32` one without `shaderFloat64`) and decides the
//!   pairs it cannot certify on the host with `orient_exact`; the result is bit-identical to the
//!   `cpu` backend. The filter's precision is
//!   [`ExactFilter`](shadowvol_silhouette::gpu::ExactFilter), as on the other GPU backends.
//! * [`twin`] is the CPU twin of the shader logic, for pinning down device differences in tests;
//!   the backend never calls it.
//!
//! Shadow volumes are drawn by `shadowvol-renderer` from this backend's multiplicities (its host
//! pipeline), like any backend's.
//!
//! The Vulkan library is loaded at run time (`ash::Entry::load`): the crate builds without it, and
//! [`create_backend`] returns [`BackendError::Unavailable`] naming what is missing. Set
//! `SHADOWVOL_VULKAN_VALIDATION=1` to run under `VK_LAYER_KHRONOS_validation`.
//!
//! Lights that do not fit the device's buffers in one pass are split into batches
//! ([`VulkanOptions::max_lights_per_batch`] caps them further); every wait for the device is bounded by
//! `SHADOWVOL_GPU_TIMEOUT` ([`shadowvol_silhouette::gpu::wait_limit`]), and a timeout is a
//! [`BackendError::Device`] (see the README's "Wait limit and timeouts").
//!
//! ```no_run
//! use shadowvol_silhouette::{extract_once, Accuracy};
//! use shadowvol_test_support::corpus;
//!
//! let case = &corpus::cases()[0];
//! let scene = case.scene()?;
//! let mut vk = shadowvol_vulkan_geometry::create_backend()?;
//! let (m, stats) = extract_once(vk.as_mut(), &scene, &case.lights, Accuracy::Exact)?;
//! println!("{} silhouette edges, {} uncertain pairs", m.silhouette(0).len(), stats.uncertain);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod backend;
mod device;
mod dispatch;
mod layout;
mod pipeline;
mod resolve;
pub mod twin;

pub use backend::VulkanBackend;

/// The backend's registry name.
pub const NAME: &str = "vulkan";

/// The crate README, compiled and run as a doctest.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
pub use device::{VulkanOptions, VALIDATION_ENV};

use shadowvol_silhouette::{BackendError, SilhouetteBackend};

/// Starts the `vulkan` backend with [`VulkanOptions::from_env`] (validation when
/// `SHADOWVOL_VULKAN_VALIDATION=1`).
///
/// # Errors
/// [`BackendError::Unavailable`] naming what is missing (Vulkan loader, device, Vulkan 1.1,
/// `geometryShader`, `vertexPipelineStoresAndAtomics`, or the validation layer when requested);
/// [`BackendError::Build`] when a pipeline cannot be built.
pub fn create_backend() -> Result<Box<dyn SilhouetteBackend>, BackendError> {
    Ok(Box::new(VulkanBackend::new(VulkanOptions::from_env())?))
}
