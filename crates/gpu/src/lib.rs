//! The GPU code the `wgpu` silhouette backend and the renderer share, below both, so that the
//! renderer depends on no backend:
//!
//! * [`shaders`]: the WGSL sources from the workspace's `shaders/` folder, their constants, and
//!   how modules are composed (the exact filter for the device, the integer exact sign);
//! * [`twin`]: the CPU twin of the WGSL functions both run, statement for statement;
//! * [`tables`]: a scene's edge tables packed into one storage buffer, uploaded in bounded
//!   chunks ([`TableBuffers`]);
//! * [`ErrorScopes`]: wgpu errors as values instead of the default panic;
//! * [`requirements`]: the limits and capabilities each set of kernels needs of a device.
//!
//! ```
//! use shadowvol_gpu::requirements::{RESIDENT, SILHOUETTE};
//!
//! // WebGPU's guaranteed limits (8 storage buffers per stage) are enough for both.
//! let webgpu = wgpu::Limits::default();
//! for needs in [SILHOUETTE, RESIDENT] {
//!     assert_eq!(needs.check_limits(&webgpu), Ok(()), "{}", needs.who);
//! }
//! ```

pub mod requirements;
mod scopes;
pub mod shaders;
pub mod tables;
pub mod twin;

pub use scopes::ErrorScopes;
pub use tables::{Extras, TableBuffers, TableOffsets, TablePacking};

/// Compiles the README's examples as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
