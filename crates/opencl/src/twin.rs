//! The CPU twin of `kernels/silhouette.cl`, for tests: the same functions, the same loop over
//! (edge, light) work items and OVs, the same atomic-append outputs, in Rust. Nothing in the
//! backend calls it.
//!
//! When the device and the `cpu` backend disagree, run the twin: if it agrees with `cpu`, the
//! fault is in the kernel build or the driver; if not, in the logic shared by both. [`extract`]
//! runs it through the same layout ([`SceneLayout`](shadowvol_silhouette::gpu::SceneLayout)) and host finishing ([`finish`]) as the
//! device path.
//!
//! The twins of the three GPU backends have the same shape: [`filter_f32`] and [`filter_f64`]
//! (the device filters of exact mode, here as [`FILTERS`]), the per-work-item function
//! ([`edge_multiplicity`](shadowvol_silhouette::gpu::twin::edge_multiplicity), the loop this twin shares with the other per-edge kernel's),
//! [`run_kernel`] (one launch: the device's raw output) and [`extract`] (the whole extraction on the CPU).
//!
//! ```
//! use shadowvol_silhouette::gpu::ExactFilter;
//! use shadowvol_silhouette::{Accuracy, Multiplicities};
//! use shadowvol_test_support::corpus;
//! use shadowvol_opencl::twin;
//!
//! let case = &corpus::cases()[0];
//! let scene = case.scene().unwrap();
//! let mut m = Multiplicities::default();
//! let _uncertain = twin::extract(&scene, &case.lights, Accuracy::Exact, ExactFilter::F32, &mut m).unwrap();
//! assert_eq!(m.edge_count(), scene.total_edges());
//! ```

use crate::resolve::{finish, KernelOutput};
use crate::NAME;
use shadowvol_robust_math::filter::{self, TermsF32};
use shadowvol_robust_math::{orient_filter_f64, Accuracy, Light, F32_FILTER_EPS};
use shadowvol_silhouette::gpu::twin::{DeviceFilters, TwinInputs};
use shadowvol_silhouette::gpu::{ExactFilter, UncertainRecord};
use shadowvol_silhouette::{BackendError, Multiplicities, TopologyScene};

const F32_PRODUCT_MIN: f32 = f32::from_bits(27 << 23); // 2^-100
const F32_PERM_MIN: f32 = f32::from_bits(31 << 23); // 2^-96

/// `sv_is_subnormal`: a subnormal `f32`, tested on the bits (robust-math's
/// [`is_subnormal`](shadowvol_robust_math::filter::is_subnormal)).
#[must_use]
pub fn is_subnormal(x: f32) -> bool {
    filter::is_subnormal(x)
}

/// `sv_sign_f32`: `((A − B) × V)·(O − A)` in f32, robust-math's
/// [`sign_f32`](shadowvol_robust_math::sign_f32) op order.
#[must_use]
pub fn sign_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i32 {
    i32::from(shadowvol_robust_math::sign_f32(a, b, l, o))
}

/// `sv_filter_f32`: robust-math's `orient_filter_f32` plus the kernel's flush-to-zero guards
/// (subnormal inputs, an underflowing `w * a`, a permanent below 2^-96 are all "uncertain").
/// `Some(sign)` is certified; `None` (the kernel's `UNCERTAIN`) leaves it to the host.
#[must_use]
pub fn filter_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Option<i8> {
    if filter::any_subnormal(a, b, l, o) || !filter::w_is_exact_f32(l[3]) {
        return None;
    }
    let t = TermsF32::new(a, b, l, o);
    if l[3] != 0.0 && (0..3).any(|i| a[i] != 0.0 && t.wa[i].abs() < F32_PRODUCT_MIN) {
        return None;
    }
    if !t.diffs_in_range(a, b, l, o) {
        return None;
    }
    let (det, perm) = t.det_perm();
    if !perm.is_finite() || (perm != 0.0 && perm < F32_PERM_MIN) {
        return None;
    }
    filter::certify_f32(det, perm, F32_FILTER_EPS)
}

/// `sv_filter_f64`: robust-math's `orient_filter_f64` (same expression and bound); subnormal
/// `f32` inputs are "uncertain". `Some(sign)` is certified; `None` leaves it to the host.
#[must_use]
pub fn filter_f64(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Option<i8> {
    if filter::any_subnormal(a, b, l, o) {
        return None;
    }
    orient_filter_f64(a, b, l, o)
}

/// The kernel's exact-mode filters, [`filter_f32`] and [`filter_f64`]; [`DeviceFilters::get`]
/// picks the one a build for an [`ExactFilter`] runs.
pub const FILTERS: DeviceFilters = DeviceFilters {
    f32: filter_f32,
    f64: filter_f64,
};

pub use shadowvol_silhouette::gpu::twin::EdgeResult;

/// Runs the kernel's logic over the whole (edge, light) grid of `x`, like one launch
/// ([`TwinInputs::each_edge_and_light`]; the kernel reads the same object-major lights flattened
/// to `f32`). The outputs are appended as the kernel's atomics append them (here in work-item
/// order, lights outer, edges inner).
#[must_use]
pub fn run_kernel(x: &TwinInputs, mode: Accuracy, filter: ExactFilter) -> KernelOutput {
    let mut out = KernelOutput {
        counts: vec![0; 2],
        silhouettes: Vec::new(),
        uncertain: Vec::new(),
    };
    let edges = x.layout.edge_count();
    x.each_edge_and_light(mode, FILTERS.get(filter), |l, e, r| {
        for k in r.uncertain {
            out.counts[0] += 1;
            out.uncertain.push(UncertainRecord {
                edge: e as u32,
                ov_slot: k,
                light: l as u32,
            });
        }
        if r.m != 0 {
            out.counts[1] += 1;
            out.silhouettes.push(((l * edges + e) as u32, r.m));
        }
    });
    out
}

/// Extracts like the `opencl` backend does, on the CPU: [`run_kernel`] over all lights, then the
/// backend's host finishing ([`finish`]: the compact list scattered, the uncertain records
/// decided with `orient_exact`). Fills `out` and returns the number of uncertain records.
///
/// # Errors
/// [`BackendError::InvalidInput`] for no lights, [`BackendError::Limit`] for oversized scenes,
/// [`BackendError::Device`] if the kernel's output were malformed.
pub fn extract(
    scene: &TopologyScene,
    lights: &[Light],
    mode: Accuracy,
    filter: ExactFilter,
    out: &mut Multiplicities,
) -> Result<u64, BackendError> {
    let x = TwinInputs::new(scene, lights, NAME)?;
    let output = run_kernel(&x, mode, filter);
    let uncertain = u64::from(output.counts[0]);
    finish(&x.layout, &x.object_lights, lights.len(), output, out, NAME)?;
    Ok(uncertain)
}
