//! What the GPU backends (`wgpu`, `opencl`, `vulkan`) share, in one place:
//!
//! * [`SceneLayout`]: the flattened scene the `opencl` and `vulkan` kernels read (all objects
//!   concatenated, global vertex ids, one `(a, b, first OV slot, object)` record per edge plus a
//!   sentinel, CSR opposite vertices);
//! * [`TableLayout`]: the scene's edge tables concatenated in their own form, for the two-step
//!   kernels (one sign per triangle, then one sum per edge: `wgpu` and the renderer's
//!   GPU-resident pass), and [`TableWriter`], which writes any range of them straight from the
//!   tables, so a backend uploads them in chunks with no host copy;
//! * [`mode_code`]: the accuracy-mode code sent to the shaders, and [`ExactFilter`]: the
//!   precision of the certified filter their exact mode runs;
//! * [`UncertainRecord`]: the `(edge, OV slot, light)` triple a kernel appends when its exact-mode
//!   filter cannot certify a sign, and [`resolve_uncertain`], the host's exact decision of those
//!   records, over a [`HostScene`]: the layout itself, or a [`SceneIndex`] that reads the edge
//!   tables (so a backend need not keep its layouts once they are uploaded);
//! * [`wait_limit`]: the bound on every wait for a device;
//! * [`quiet_without_display`]: Mesa's Vulkan device-select layer turned off where there is no
//!   display, so that it prints no `error:` line when nothing failed;
//! * [`lights_per_batch`] and [`batches`]: how the lights of one `extract` are split into batches
//!   (a dispatch, a kernel launch, a geometry-shader pass) when they do not fit one;
//! * [`twin`]: the per-edge loop the CPU twins of the `opencl` and `vulkan` kernels share.
//!
//! It is a module of the trait crate rather than a crate of its own: it depends on nothing but
//! the trait's types ([`TopologyScene`](crate::TopologyScene), [`Multiplicities`](crate::Multiplicities),
//! [`BackendError`](crate::BackendError)) and robust-math, every GPU backend already depends on
//! this crate, and the CPU twins and tests use it without a GPU. A separate crate would add a
//! dependency edge and a README for the same ~400 lines.

mod batches;
mod display;
mod host;
mod layout;
mod resolve;
mod tables;
pub mod twin;
mod wait;

pub use batches::{batches, lights_per_batch};
pub use display::{device_select_value, quiet_without_display, NODEVICE_SELECT};
pub use host::{HostScene, SceneIndex, TableRange};
pub use layout::SceneLayout;
pub use resolve::{check_batch, resolve_uncertain, UncertainRecord};
pub use tables::{
    object_of, TableBuffer, TableLayout, TableWriter, FIRST_EDGE, FIRST_SLOT, FIRST_TRIANGLE,
    FIRST_VERTEX,
};
pub use wait::{describe_wait_limit, wait_limit, DEFAULT_TIMEOUT, TIMEOUT_ENV};

use shadowvol_robust_math::Accuracy;

/// Vertex `id`'s `xyz` in a flat `f32` position array (3 values a vertex), as every GPU layout
/// stores positions.
///
/// # Panics
/// Panics if `id` is out of range.
fn xyz(positions: &[f32], id: u32) -> [f32; 3] {
    let i = id as usize * 3;
    [positions[i], positions[i + 1], positions[i + 2]]
}

/// Shader code of [`Accuracy::Original`].
pub const MODE_ORIGINAL: u32 = 0;
/// Shader code of [`Accuracy::Robust`].
pub const MODE_ROBUST: u32 = 1;
/// Shader code of [`Accuracy::Ordered`].
pub const MODE_ORDERED: u32 = 2;
/// Shader code of [`Accuracy::Exact`].
pub const MODE_EXACT: u32 = 3;

/// The code of `mode` in every kernel of the workspace (`mode` uniform, push constant or
/// argument): [`MODE_ORIGINAL`], [`MODE_ROBUST`], [`MODE_ORDERED`] or [`MODE_EXACT`].
///
/// ```
/// use shadowvol_silhouette::{gpu, Accuracy};
/// assert_eq!(gpu::mode_code(Accuracy::Exact), gpu::MODE_EXACT);
/// ```
#[must_use]
pub fn mode_code(mode: Accuracy) -> u32 {
    match mode {
        Accuracy::Original => MODE_ORIGINAL,
        Accuracy::Robust => MODE_ROBUST,
        Accuracy::Ordered => MODE_ORDERED,
        Accuracy::Exact => MODE_EXACT,
    }
}

/// The certified filter a GPU kernel's exact mode runs before it leaves a sign to an exact
/// decision: the precision of its arithmetic. Every GPU backend and the renderer's GPU-resident
/// pass use this one type.
///
/// Both filters certify a sign only when it equals the exact sign of the determinant (each with
/// its own forward error bound and range checks); `F64` certifies far more near-degenerate
/// inputs, so fewer are left to the exact fallback.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ExactFilter {
    /// `f64` arithmetic from the `f32` inputs (devices with 64-bit floats in shaders: wgpu's
    /// `SHADER_F64`, Vulkan's `shaderFloat64`, OpenCL's `cl_khr_fp64`).
    F64,
    /// `f32` arithmetic with range checks (every device).
    F32,
}

impl ExactFilter {
    /// The filter a device runs: [`ExactFilter::F64`] when it has 64-bit floats in shaders
    /// (`device_f64`) and `force_f32` is not set, else [`ExactFilter::F32`].
    ///
    /// ```
    /// use shadowvol_silhouette::gpu::ExactFilter;
    /// assert_eq!(ExactFilter::for_device(true, false), ExactFilter::F64);
    /// assert_eq!(ExactFilter::for_device(true, true), ExactFilter::F32);
    /// assert_eq!(ExactFilter::for_device(false, false), ExactFilter::F32);
    /// ```
    #[must_use]
    pub fn for_device(device_f64: bool, force_f32: bool) -> Self {
        if device_f64 && !force_f32 {
            ExactFilter::F64
        } else {
            ExactFilter::F32
        }
    }

    /// `"f64"` or `"f32"`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            ExactFilter::F64 => "f64",
            ExactFilter::F32 => "f32",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mode_codes_are_distinct_and_stable() {
        let codes: Vec<u32> = Accuracy::ALL.iter().map(|&m| mode_code(m)).collect();
        // The kernels hard-code these values.
        assert_eq!(codes, [0, 1, 2, 3]);
    }
}
