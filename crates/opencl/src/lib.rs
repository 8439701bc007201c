//! The `opencl` silhouette backend: OpenCL C kernels from `kernels/silhouette.cl`, built at run
//! time for the selected device with `opencl3`.
//!
//! * **One enqueue per extraction.** Every object of a prepared scene and every light go into a
//!   single 2-D NDRange (edges × lights). Each edge carries its object index, and the lights are
//!   uploaded per (object, light) in object space, computed by
//!   [`shadowvol_silhouette::object_lights`] so that every backend sees the same `f32` inputs.
//!   There is no per-object synchronisation.
//! * **Many lights.** When the per-light buffers of all lights would exceed the device's largest
//!   allocation or the kernel's 32-bit indices (or [`OpenClOptions::max_lights_per_batch`] is
//!   set), the lights are split into batches of one launch each, with the same result as one
//!   launch; only a scene where one light alone does not fit is a [`BackendError::Limit`].
//! * **Uploaded once.** Positions, edges, OV lists and offsets are uploaded at `prepare`; an
//!   `extract` uploads only the lights (and zeroes the counters).
//! * **Compact output.** The kernel appends `(light * edges + edge, m)` for each silhouette edge
//!   of every light to one list with an atomic counter; only that list (one read, whatever the
//!   number of lights) is read back, scattered and split per light on the host.
//! * **All four modes.** `original`, `robust` and `ordered` evaluate robust-math's `sign_f32`
//!   expression exactly as written (`#pragma OPENCL FP_CONTRACT OFF`), with the canonical order
//!   and parity rules. `exact` runs a certified filter on the device (the `f64` filter of
//!   `orient_filter_f64` when the device has `cl_khr_fp64`, otherwise the `f32` filter of
//!   `orient_filter_f32`: [`ExactFilter`](shadowvol_silhouette::gpu::ExactFilter), as on the other
//!   GPU backends); the (edge, OV, light) triples it cannot certify are appended to a
//!   buffer and decided on the host with `orient_exact`, so exact results are bit-identical to the
//!   `cpu` backend. [`ExtractStats::uncertain`](shadowvol_silhouette::ExtractStats::uncertain) counts them.
//! * **A CPU twin.** [`twin`] is the kernel's logic in Rust, loop for loop, run through the same
//!   layout and host code, for tests (the backend never calls it).
//! * **Bounded waits.** Nothing waits for the device without a limit (no `clFinish`, no blocking
//!   reads or writes): every command is enqueued non-blocking and its event waited for within
//!   [`shadowvol_silhouette::gpu::wait_limit`] (`SHADOWVOL_GPU_TIMEOUT` seconds, default 600; read
//!   at every `extract`), woken by a completion callback and checked by status reads between.
//!   A command that fails is a [`BackendError::Device`] naming it and its decoded status; one
//!   that does not end in time is a `Device` error naming `SHADOWVOL_GPU_TIMEOUT`. The work that
//!   was still running is then *abandoned*: the host memory it uses stays with the backend, and
//!   the next `extract` first waits (within the limit again) for that work to end. If it has,
//!   the backend carries on as usual; if not, that `extract` is a `Device` error saying so.
//!   Dropping the backend never waits (see its `Drop`).
//!
//! # Device selection
//! The first GPU, otherwise the first CPU device, over all platforms in ICD order. The
//! environment variable [`DEVICE_ENV`] (`SHADOWVOL_OPENCL_DEVICE`) chooses explicitly: `P:D`
//! (platform and device indices, as `clinfo -l` lists them) or a case-insensitive substring of
//! `"platform name / device name type platform-version"` (so `pocl`, `cuda`, `gpu` work).
//! [`KERNEL_ENV`] (`SHADOWVOL_OPENCL_KERNEL`) loads the kernel source from a file instead of the
//! built-in copy.
//!
//! # Example
//! ```no_run
//! use shadowvol_opencl::OpenClBackend;
//! use shadowvol_silhouette::{extract_once, Accuracy, SilhouetteBackend};
//! use shadowvol_test_support::corpus;
//!
//! let mut cl = OpenClBackend::new()?; // BackendError::Unavailable says what is missing
//! println!("{}", cl.info().device);
//! let case = &corpus::cases()[0];
//! let scene = case.scene().expect("corpus meshes are valid");
//! let (m, stats) = extract_once(&mut cl, &scene, &case.lights, Accuracy::Exact)?;
//! println!("{} silhouette edges, {} uncertain", m.silhouette(0).len(), stats.uncertain);
//! # Ok::<(), shadowvol_silhouette::BackendError>(())
//! ```

mod backend;
mod device;
mod dispatch;
pub mod layout;
mod pipeline;
pub mod resolve;
pub mod twin;
mod wait;

pub use backend::OpenClBackend;
pub use device::{list_devices, select_device, DeviceDesc, OpenClOptions, DEVICE_ENV};
pub use pipeline::{KernelSource, KERNEL_ENV, KERNEL_NAME, KERNEL_SOURCE};

use shadowvol_silhouette::{BackendError, SilhouetteBackend};

/// The backend's registry name.
pub const NAME: &str = "opencl";

/// Starts the `opencl` backend with [`OpenClOptions::from_env`].
///
/// # Errors
/// [`BackendError::Unavailable`] naming what is missing (the ICD loader `libOpenCL.so.1`, a
/// platform, a device, or a device matching [`DEVICE_ENV`]); [`BackendError::Build`] with the
/// compiler's log if the kernel does not build; otherwise as [`OpenClBackend::with_options`].
pub fn create_backend() -> Result<Box<dyn SilhouetteBackend>, BackendError> {
    Ok(Box::new(OpenClBackend::with_options(
        OpenClOptions::from_env(),
    )?))
}

/// Compiles the README's example as a doctest.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
