//! The CPU twin of the WGSL kernels (`shaders/silhouette.wgsl`, `shaders/exact_f64.wgsl` and
//! `shaders/exact_int.wgsl`), for tests: nothing in the backend calls it.
//!
//! The per-function twins ([`shadowvol_gpu::twin`]: the filters, `triangle_sign`,
//! `edge_multiplicity`, `orient_int`) are shared with the renderer's resident pass; [`run_kernel`]
//! mirrors the kernel's two steps over a [`TableLayout`]: one "invocation" per global triangle (a sign
//! per light, undecided pairs appended in exact mode), then one per global edge (lights in the
//! outer loop, opposite vertices in the inner one, the compact list appended when `m != 0`). [`extract`] runs the kernel and the backend's own host side on
//! a whole scene. When the GPU disagrees with the `cpu` backend, run the twin on the same input:
//! if the twin is right, the fault is in the device or the WGSL translation; if it is wrong too,
//! it is in the algorithm (vello keeps CPU shaders for the same reason).
//!
//! The twins of the three GPU backends have the same shape: `filter_f32`, `filter_f64` and
//! `exact_filter` (the device filters of exact mode), the per-invocation functions, `run_kernel`
//! (one dispatch: the device's raw output) and `extract` (the whole extraction on the CPU).
//!
//! The only intended difference from the device is floating-point contraction: Rust never fuses
//! `a * b + c`, a GPU compiler may. That can change the last bits of the `f32` modes, never the
//! exact mode, whose filters certify only signs that hold with contraction too.
//!
//! ```
//! use shadowvol_silhouette::gpu::ExactFilter;
//! use shadowvol_silhouette::{Accuracy, Multiplicities};
//! use shadowvol_test_support::corpus;
//! use shadowvol_wgpu_compute::twin;
//!
//! let case = &corpus::cases()[0];
//! let scene = case.scene().unwrap();
//! let mut m = Multiplicities::default();
//! let uncertain = twin::extract(&scene, &case.lights, Accuracy::Exact, ExactFilter::F32, &mut m).unwrap();
//! assert_eq!(m.light_count(), case.lights.len());
//! assert!(uncertain <= (scene.total_ovs() * case.lights.len()) as u64);
//! ```

use crate::resolve::{expand_uncertain, finish_batch, BatchOutput, UncertainTriangle};
pub use shadowvol_gpu::twin::{
    edge_multiplicity, exact_filter, filter_f32, filter_f64, mul32, orient_int, triangle_sign,
    EdgeInputs,
};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::gpu::twin::TwinInputs;
use shadowvol_silhouette::gpu::{ExactFilter, SceneIndex, TableLayout};
use shadowvol_silhouette::{BackendError, Multiplicities, TopologyScene};

/// What the kernels' two steps produce for one dispatch.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct KernelOutput {
    /// The triangle step's `signs[light * tri_count + triangle]` (all 0 in `original`, which has
    /// no triangle step); undecided triangles are 0.
    pub signs: Vec<i32>,
    /// `mult[light * edge_count + edge]`, undecided triangles counted as 0.
    pub mult: Vec<i32>,
    /// Per light, the compact list `(edge, m)` of edges with `m != 0` (here in edge order; on the
    /// device in atomic-append order).
    pub silhouettes: Vec<Vec<(u32, i32)>>,
    /// `(triangle, light)` pairs left to the host (exact mode without `device_exact` only).
    pub uncertain: Vec<UncertainTriangle>,
    /// `(triangle, light)` pairs the filter left that `resolve_uncertain` decided on the device
    /// (exact mode with `device_exact`), in append order here.
    pub resolved: Vec<UncertainTriangle>,
}

/// Runs the kernels' logic for every triangle, then every edge, of `layout`: `lights` is
/// object-major (`lights[object * light_count + light]`, object-space, from [`object_lights`](shadowvol_silhouette::object_lights)).
/// What the exact filter cannot certify is left to the host (see [`run_kernel_with`]).
///
/// # Panics
/// Panics if `lights.len() != layout.object_count() * light_count`.
#[must_use]
pub fn run_kernel(
    layout: &TableLayout,
    lights: &[[f32; 4]],
    light_count: usize,
    mode: Accuracy,
    filter: ExactFilter,
) -> KernelOutput {
    run_kernel_with(layout, lights, light_count, mode, filter, false)
}

/// [`run_kernel`] for the module of
/// [`module_source_with`](shadowvol_gpu::shaders::module_source_with): with `device_exact`, the backend's
/// exact pipelines. The triangle step (built with `DEFER_INT`) appends what the filter cannot
/// certify, with sign 0; `resolve_uncertain` then decides each appended pair with
/// [`orient_int`] ([`KernelOutput::resolved`]), and nothing is left
/// in [`KernelOutput::uncertain`]. The inline fallback pipeline gives the same signs with no
/// list.
///
/// # Panics
/// As [`run_kernel`].
#[must_use]
pub fn run_kernel_with(
    layout: &TableLayout,
    lights: &[[f32; 4]],
    light_count: usize,
    mode: Accuracy,
    filter: ExactFilter,
    device_exact: bool,
) -> KernelOutput {
    assert_eq!(
        lights.len(),
        layout.object_count() * light_count,
        "one light per (object, light)"
    );
    let edge_count = layout.edge_count();
    let tri_count = layout.tri_count();
    let mut out = KernelOutput {
        signs: vec![0; tri_count * light_count],
        mult: vec![0; edge_count * light_count],
        silhouettes: vec![Vec::new(); light_count],
        uncertain: Vec::new(),
        resolved: Vec::new(),
    };
    if mode != Accuracy::Original {
        // The triangle step: one invocation per triangle.
        for (t, tr) in layout.tris.iter().enumerate() {
            let p = tr.map(|v| layout.position(v));
            let object = layout.tri_object(t);
            for li in 0..light_count {
                let l = lights[object * light_count + li];
                let s = match triangle_sign(mode, filter, false, p, l).0 {
                    Some(s) => s,
                    None => {
                        out.uncertain.push(UncertainTriangle {
                            triangle: t as u32,
                            light: li as u32,
                        });
                        0
                    }
                };
                out.signs[li * tri_count + t] = i32::from(s);
            }
        }
    }
    if device_exact {
        // `resolve_uncertain`: one invocation per appended pair.
        for r in &out.uncertain {
            let t = r.triangle as usize;
            let p = layout.tris[t].map(|v| layout.position(v));
            let l = lights[layout.tri_object(t) * light_count + r.light as usize];
            let s = triangle_sign(mode, filter, true, p, l).0;
            out.signs[r.light as usize * tri_count + r.triangle as usize] =
                i32::from(s.expect("the integer path decides every pair"));
        }
        out.resolved = std::mem::take(&mut out.uncertain);
    }
    // The edge step: one invocation per edge.
    let x = EdgeInputs {
        layout,
        signs: &out.signs,
        lights,
        light_count,
        touch_signs: false,
    };
    for e in 0..edge_count {
        for li in 0..light_count {
            let m = edge_multiplicity(&x, e, li, mode);
            out.mult[li * edge_count + e] = m;
            if m != 0 {
                out.silhouettes[li].push((e as u32, m));
            }
        }
    }
    out
}

/// Extracts like the wgpu backend does, on the CPU: the twin kernel over all lights at once,
/// then the same host resolution of what exact mode left undecided (with `orient_exact`). Fills
/// `out` and returns the number of uncertain (edge, OV, light) triples: three per undecided
/// (triangle, light) pair.
///
/// # Errors
/// [`BackendError::InvalidInput`] for an empty light list, [`BackendError::Limit`] for scenes
/// beyond `u32` indexing.
pub fn extract(
    scene: &TopologyScene,
    lights: &[Light],
    mode: Accuracy,
    filter: ExactFilter,
    out: &mut Multiplicities,
) -> Result<u64, BackendError> {
    let x = TwinInputs::new(scene, lights, crate::NAME)?;
    let layout = TableLayout::build(scene, crate::NAME)?;
    let k = run_kernel(&layout, &x.packed, lights.len(), mode, filter);
    out.reset(layout.edge_count(), lights.len());
    let index = SceneIndex::new(scene);
    let records = if k.uncertain.is_empty() {
        Vec::new()
    } else {
        let of = |t: usize| index.edge_slots(t);
        expand_uncertain(&k.uncertain, of, index.tri_count(), lights.len())?
    };
    let uncertain = records.len() as u64;
    let _patch = finish_batch(
        &index,
        &x.object_lights,
        0..lights.len(),
        BatchOutput {
            mult: Some(k.mult),
            lists: k.silhouettes,
            uncertain: records,
        },
        out,
    )?;
    Ok(uncertain)
}
