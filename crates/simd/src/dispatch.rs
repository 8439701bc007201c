//! Per-level entry points. A kernel pass is written once, generic over the lane [`Level`]
//! ([`Pass::run`]); [`run`] instantiates it at the backend's [`SimdLevel`]. The AVX2 entry point
//! is compiled with the feature enabled, so the generic kernels and their lane operations are
//! inlined into AVX2 code.

use crate::lanes::{Level, Wide};
use crate::SimdLevel;

/// One kernel pass over one work item.
pub(crate) trait Pass: Sized {
    /// What the pass returns.
    type Out;

    /// The pass with the lanes of `Lv`; `#[inline(always)]` in every implementation, so that it
    /// is compiled inside the entry point of its level.
    fn run<Lv: Level>(self) -> Self::Out;

    /// The pass at the AVX2 level: [`Pass::run`] with the AVX2 lanes, unless the pass has a
    /// kernel of its own written with AVX2 intrinsics.
    ///
    /// # Safety
    /// The CPU must support AVX2 (called only from the AVX2 entry point).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn run_avx2(self) -> Self::Out {
        self.run::<crate::lanes::Avx2>()
    }
}

/// Runs `pass` at `level`.
///
/// # Panics
/// Where the pass panics (a slice shorter than the pass describes).
pub(crate) fn run<P: Pass>(level: SimdLevel, pass: P) -> P::Out {
    match level {
        #[cfg(target_arch = "x86_64")]
        SimdLevel::Avx2 => {
            // SAFETY: a backend at level Avx2 is only constructed after
            // `is_x86_feature_detected!("avx2")` (see `SimdBackend::with_level`).
            unsafe { run_avx2(pass) }
        }
        _ => pass.run::<Wide>(),
    }
}

/// The AVX2 entry point.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn run_avx2<P: Pass>(pass: P) -> P::Out {
    // SAFETY: forwarded from the caller.
    unsafe { pass.run_avx2() }
}
