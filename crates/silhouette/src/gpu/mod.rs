//! What the GPU backends (`wgpu`, `opencl`, `vulkan`) share, in one place:
//!
//! * [`SceneLayout`]: the flattened scene every kernel reads (all objects concatenated, global
//!   vertex ids, one `(a, b, first OV slot, object)` record per edge plus a sentinel, CSR opposite
//!   vertices);
//! * [`TriangleLayout`]: the triangles of that scene, for two-step kernels (one sign per
//!   triangle, then one sum per edge);
//! * [`mode_code`]: the accuracy-mode code sent to the shaders;
//! * [`UncertainRecord`]: the `(edge, OV slot, light)` triple a kernel appends when its exact-mode
//!   filter cannot certify a sign, and [`resolve_uncertain`], the host's exact decision of those
//!   records;
//! * [`wait_limit`]: the bound on every wait for a device;
//! * [`lights_per_batch`] and [`batches`]: how the lights of one `extract` are split into batches
//!   (a dispatch, a kernel launch, a geometry-shader pass) when they do not fit one.
//!
//! It is a module of the trait crate rather than a crate of its own: it depends on nothing but
//! the trait's types ([`TopologyScene`](crate::TopologyScene), [`Multiplicities`](crate::Multiplicities),
//! [`BackendError`](crate::BackendError)) and robust-math, every GPU backend already depends on
//! this crate, and the CPU twins and tests use it without a GPU. A separate crate would add a
//! dependency edge and a README for the same ~400 lines.

mod batches;
mod layout;
mod resolve;
mod triangles;
mod wait;

pub use batches::{batches, lights_per_batch};
pub use layout::SceneLayout;
pub use resolve::{check_batch, resolve_uncertain, UncertainRecord};
pub use triangles::{TriangleLayout, NEGATIVE};
pub use wait::{describe_wait_limit, wait_limit, DEFAULT_TIMEOUT, TIMEOUT_ENV};

use shadowvol_robust_math::Accuracy;

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
