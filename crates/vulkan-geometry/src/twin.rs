//! The CPU twin of the geometry shader (`shaders/silhouette_gs.geom`), for tests: nothing in the
//! backend calls it.
//!
//! The same buffers (a [`SceneLayout`](shadowvol_silhouette::gpu::SceneLayout) and object-major lights), the same per-edge loop, the same
//! filters, in Rust. When the device disagrees with the `cpu` backend, running the twin on the
//! same input tells whether the shader logic or the device arithmetic is at fault.
//!
//! The twins of the three GPU backends have the same shape: [`filter_f32`] and [`filter_f64`]
//! (the device filters of exact mode, here as [`FILTERS`]), the per-invocation function
//! ([`edge_multiplicity`](shadowvol_silhouette::gpu::twin::edge_multiplicity), the loop this twin shares with the other per-edge kernel's),
//! [`run_kernel`] (one pass: the device's raw output) and [`extract`] (the whole extraction on the CPU, with the backend's own host side).
//!
//! ```
//! use shadowvol_silhouette::gpu::ExactFilter;
//! use shadowvol_silhouette::{Accuracy, Multiplicities};
//! use shadowvol_test_support::corpus;
//! use shadowvol_vulkan_geometry::twin;
//!
//! let case = &corpus::cases()[0];
//! let scene = case.scene().unwrap();
//! let mut m = Multiplicities::default();
//! let _uncertain = twin::extract(&scene, &case.lights, Accuracy::Exact, ExactFilter::F32, &mut m).unwrap();
//! assert_eq!(m.edge_count(), scene.total_edges());
//! ```

use crate::resolve::finish_batch;
use crate::NAME;
use shadowvol_robust_math::filter::{self, TermsF32};
use shadowvol_robust_math::{orient_filter_f64, Accuracy, Light, F32_FILTER_EPS};
use shadowvol_silhouette::gpu::twin::{DeviceFilters, TwinInputs};
use shadowvol_silhouette::gpu::{ExactFilter, UncertainRecord};
use shadowvol_silhouette::{BackendError, Multiplicities, TopologyScene};

/// Twin of the shader's `f32` filter (`orient_filter` with `SHADOWVOL_NO_F64`): robust-math's
/// [`orient_filter_f32`](shadowvol_robust_math::orient_filter_f32) plus guards that keep it
/// certified on devices that flush `f32` denormals to zero (subnormal inputs, non-zero
/// differences flushed to zero, `L.w * A` leaving the normal range are all "uncertain").
///
/// Returns `Some(sign)` only when the sign equals the exact sign; `None` leaves it to the host.
#[must_use]
pub fn filter_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Option<i8> {
    if filter::any_subnormal(a, b, l, o) || !filter::w_is_exact_f32(l[3]) {
        return None;
    }
    let t = TermsF32::new(a, b, l, o);
    if !t.diffs_in_range(a, b, l, o) {
        return None;
    }
    // `L.w * A` must stay normal: an underflowed (or flushed) product has an absolute error.
    if (0..3).any(|i| {
        (l[3] != 0.0 && a[i] != 0.0 && t.wa[i].abs() < f32::MIN_POSITIVE) || t.wa[i].is_infinite()
    }) {
        return None;
    }
    let (det, perm) = t.det_perm();
    if !perm.is_finite() || det.is_nan() {
        return None;
    }
    filter::certify_f32(det, perm, F32_FILTER_EPS)
}

/// Twin of the shader's `f64` filter (`orient_filter` without `SHADOWVOL_NO_F64`): robust-math's
/// [`orient_filter_f64`], whose exact `f32` to `f64` conversion the shader does on the bits.
#[must_use]
pub fn filter_f64(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Option<i8> {
    orient_filter_f64(a, b, l, o)
}

/// The shader's exact-mode filters, [`filter_f32`] and [`filter_f64`]; [`DeviceFilters::get`]
/// picks the one a build for an [`ExactFilter`] runs.
pub const FILTERS: DeviceFilters = DeviceFilters {
    f32: filter_f32,
    f64: filter_f64,
};

pub use shadowvol_silhouette::gpu::twin::EdgeResult;

/// What one pass over the (edge, light) grid leaves on the device.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct KernelOutput {
    /// `mult[light * edge_count + edge]`, uncertain pairs counted as 0.
    pub mult: Vec<i32>,
    /// The `(edge, OV slot, light)` triples the filter could not certify (here in invocation
    /// order; on the device in atomic-append order).
    pub uncertain: Vec<UncertainRecord>,
}

/// Runs the shader's logic for every (edge, light) of one pass over `x`
/// ([`TwinInputs::each_edge_and_light`]).
#[must_use]
pub fn run_kernel(x: &TwinInputs, mode: Accuracy, filter: ExactFilter) -> KernelOutput {
    let edges = x.layout.edge_count();
    let mut out = KernelOutput {
        mult: vec![0; edges * x.light_count],
        uncertain: Vec::new(),
    };
    x.each_edge_and_light(mode, FILTERS.get(filter), |li, e, r| {
        out.mult[li * edges + e] = r.m;
        out.uncertain
            .extend(r.uncertain.into_iter().map(|k| UncertainRecord {
                edge: e as u32,
                ov_slot: k,
                light: li as u32,
            }));
    });
    out
}

/// Extracts like the `vulkan` backend does, on the CPU: [`run_kernel`] over all lights, then the
/// backend's host side (the uncertain pairs decided with `orient_exact`, the compact lists
/// built). Fills `out` and returns the number of uncertain pairs.
///
/// # Errors
/// [`BackendError::InvalidInput`] for no lights, [`BackendError::Limit`] for oversized scenes.
pub fn extract(
    scene: &TopologyScene,
    lights: &[Light],
    mode: Accuracy,
    filter: ExactFilter,
    out: &mut Multiplicities,
) -> Result<u64, BackendError> {
    let x = TwinInputs::new(scene, lights, NAME)?;
    let k = run_kernel(&x, mode, filter);
    out.reset(x.layout.edge_count(), lights.len());
    out.all_values_mut().copy_from_slice(&k.mult);
    finish_batch(
        &x.layout,
        &x.object_lights,
        0..lights.len(),
        &k.uncertain,
        out,
    )?;
    out.rebuild_silhouettes();
    Ok(k.uncertain.len() as u64)
}
