//! The CPU twin of `shaders/silhouette.wgsl` (and `shaders/exact_f64.wgsl`).
//!
//! Each function here mirrors one WGSL function, statement for statement, and [`run_kernel`]
//! mirrors the kernel's per-edge loop: one "invocation" per global edge of a [`SceneLayout`], lights
//! in the outer loop, opposite vertices in the inner one, the compact list appended when `m != 0`,
//! uncertain triples appended in exact mode. When the GPU disagrees with the `cpu` backend, run the
//! twin on the same input: if the twin is right, the fault is in the device or the WGSL
//! translation; if it is wrong too, it is in the algorithm (vello keeps CPU shaders for the same
//! reason).
//!
//! The only intended difference from the device is floating-point contraction: Rust never fuses
//! `a * b + c`, a GPU compiler may. That can change the last bits of the `f32` modes, never the
//! exact mode, whose filters certify only signs that hold with contraction too.
//!
//! ```
//! use shadowvol_silhouette::{corpus, Accuracy, Multiplicities};
//! use shadowvol_wgpu_compute::twin::{self, ExactFilter};
//!
//! let case = &corpus::cases()[0];
//! let scene = case.scene().unwrap();
//! let mut m = Multiplicities::default();
//! let uncertain = twin::extract(&scene, &case.lights, Accuracy::Exact, ExactFilter::F32, &mut m).unwrap();
//! assert_eq!(m.light_count(), case.lights.len());
//! assert!(uncertain <= (scene.total_ovs() * case.lights.len()) as u64);
//! ```

use crate::resolve::{finish_batch, BatchOutput};
use shadowvol_robust_math::filter::{self, TermsF32};
use shadowvol_robust_math::{sign_f32, Accuracy, Light, F32_FILTER_EPS, F64_FILTER_EPS};
use shadowvol_silhouette::gpu::{SceneLayout, UncertainRecord};
use shadowvol_silhouette::{
    check_lights, object_lights, BackendError, Multiplicities, TopologyScene,
};

/// Which certified filter exact mode runs on the device.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ExactFilter {
    /// `f64` arithmetic (needs `wgpu::Features::SHADER_F64`): [`filter_f64`].
    F64,
    /// `f32` arithmetic with range checks: [`filter_f32`].
    F32,
}

impl ExactFilter {
    /// `"f64"` or `"f32"`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            ExactFilter::F64 => "f64",
            ExactFilter::F32 => "f32",
        }
    }
}

/// Relative bound of the device's `f64` filter: 8 × robust-math's [`F64_FILTER_EPS`].
///
/// `F64_FILTER_EPS` (1e-15) covers the `9u` of the straight evaluation. WGSL cannot forbid FMA
/// contraction or reassociation; both remove roundings without adding any, so the straight
/// bound still holds, and the factor 8 is margin for them (and for drivers). A larger bound only
/// sends more near-degenerate triples to the host. Must equal `GPU_F64_FILTER_EPS` in
/// `shaders/exact_f64.wgsl` (a test checks it).
pub const GPU_F64_FILTER_EPS: f64 = 8.0 * F64_FILTER_EPS;

/// Largest input magnitude (positions and light components) the device's `f32` filter accepts:
/// 2^39, so that no difference or product overflows before the range checks (WGSL leaves the
/// result of an overflowing operation indeterminate).
pub const GPU_F32_INPUT_MAX: f32 = 549_755_813_888.0; // 2^39

/// Smallest non-zero permanent the device's `f32` filter certifies: 2^-60. A device may flush
/// subnormal intermediates to zero (only the terms `(p - q) * d` can become subnormal under the
/// range checks); each flush moves `det` by less than 2^-126, far below `F32_FILTER_EPS × 2^-60`.
pub const GPU_F32_PERM_MIN: f32 = 1.0 / 1_152_921_504_606_846_976.0; // 2^-60

/// Twin of WGSL `filter_f32`: robust-math's `orient_filter_f32` (the same
/// [`TermsF32`] arithmetic, [`F32_FILTER_EPS`], range checks, and only `w` in {0, 1} certified)
/// plus the two device guards [`GPU_F32_INPUT_MAX`] and [`GPU_F32_PERM_MIN`]. `Some(sign)` is
/// certified, `None` is uncertain.
///
/// Whenever it certifies, `orient_filter_f32` certifies the same sign (the guards only add
/// `None`s); a test checks this.
#[must_use]
pub fn filter_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Option<i8> {
    if a.iter()
        .chain(&b)
        .chain(&o)
        .chain(&l)
        .any(|x| x.abs() > GPU_F32_INPUT_MAX)
        || !filter::w_is_exact_f32(l[3])
    {
        return None;
    }
    let t = TermsF32::new(a, b, l, o);
    if !t.diffs_in_range(a, b, l, o) {
        return None;
    }
    let (det, perm) = t.det_perm();
    if perm != 0.0 && perm < GPU_F32_PERM_MIN {
        return None;
    }
    filter::certify_f32(det, perm, F32_FILTER_EPS)
}

/// Twin of WGSL `filter_f64` (shaders/exact_f64.wgsl): robust-math's [`filter::det_perm_f64`]
/// with the bound [`GPU_F64_FILTER_EPS`].
#[must_use]
pub fn filter_f64(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Option<i8> {
    let (det, perm) = filter::det_perm_f64(a, b, l, o);
    filter::certify_f64(det, perm, GPU_F64_FILTER_EPS)
}

/// Twin of WGSL `exact_filter`: inputs with a subnormal component are never certified (a device
/// may flush them), otherwise the chosen filter decides.
#[must_use]
pub fn exact_filter(
    filter: ExactFilter,
    a: [f32; 3],
    b: [f32; 3],
    l: [f32; 4],
    o: [f32; 3],
) -> Option<i8> {
    if filter::any_subnormal(a, b, l, o) {
        return None;
    }
    match filter {
        ExactFilter::F32 => filter_f32(a, b, l, o),
        ExactFilter::F64 => filter_f64(a, b, l, o),
    }
}

/// Twin of WGSL `canonical_sign` (robust and ordered): sorts the triangle by id, evaluates in that
/// order, multiplies by the parity. `robust` selects the three-evaluation rule.
#[must_use]
#[allow(clippy::too_many_arguments)]
pub fn canonical_sign(
    robust: bool,
    ia: u32,
    ib: u32,
    io: u32,
    a: [f32; 3],
    b: [f32; 3],
    o: [f32; 3],
    l: [f32; 4],
) -> i8 {
    let (p0, p1, p2, parity) = if io < ia {
        (o, a, b, 1)
    } else if io < ib {
        (a, o, b, -1)
    } else {
        (a, b, o, 1)
    };
    let s0 = sign_f32(p0, p1, l, p2);
    if robust {
        let s1 = sign_f32(p1, p2, l, p0);
        let s2 = sign_f32(p2, p0, l, p1);
        if s0 != s1 || s1 != s2 {
            return 0;
        }
    }
    s0 * parity
}

/// What one kernel dispatch produces.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct KernelOutput {
    /// `mult[light * edge_count + edge]`, uncertain triples counted as 0.
    pub mult: Vec<i32>,
    /// Per light, the compact list `(edge, m)` of edges with `m != 0` (here in edge order; on the
    /// device in atomic-append order).
    pub silhouettes: Vec<Vec<(u32, i32)>>,
    /// Uncertain triples (exact mode only).
    pub uncertain: Vec<UncertainRecord>,
}

/// Runs the kernel's logic for every edge of `layout`: `lights` is object-major
/// (`lights[object * light_count + light]`, object-space, from [`object_lights`]).
///
/// # Panics
/// Panics if `lights.len() != layout.object_count() * light_count`.
#[must_use]
pub fn run_kernel(
    layout: &SceneLayout,
    lights: &[[f32; 4]],
    light_count: usize,
    mode: Accuracy,
    filter: ExactFilter,
) -> KernelOutput {
    run_kernel_with(layout, lights, light_count, mode, filter, false)
}

/// [`run_kernel`] for the module of
/// [`module_source_with`](crate::shaders::module_source_with): with `device_exact`, what the
/// filter cannot certify is decided by [`orient_int`](crate::exact_int::orient_int) and nothing
/// is appended to [`KernelOutput::uncertain`].
///
/// # Panics
/// As [`run_kernel`].
#[must_use]
pub fn run_kernel_with(
    layout: &SceneLayout,
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
    let mut out = KernelOutput {
        mult: vec![0; edge_count * light_count],
        silhouettes: vec![Vec::new(); light_count],
        uncertain: Vec::new(),
    };
    for e in 0..edge_count {
        // One invocation.
        let [ia, ib, _, object] = layout.edges[e];
        let a = layout.position(ia);
        let b = layout.position(ib);
        for li in 0..light_count {
            let l = lights[object as usize * light_count + li];
            let mut m = 0i32;
            for k in layout.ov_slots(e) {
                let io = layout.ovs[k];
                let o = layout.position(io);
                let s = match mode {
                    Accuracy::Original => sign_f32(a, b, l, o),
                    Accuracy::Exact if device_exact => exact_filter(filter, a, b, l, o)
                        .unwrap_or_else(|| crate::exact_int::orient_int(a, b, l, o)),
                    Accuracy::Exact => exact_filter(filter, a, b, l, o).unwrap_or_else(|| {
                        out.uncertain.push(UncertainRecord {
                            edge: e as u32,
                            ov_slot: k as u32,
                            light: li as u32,
                        });
                        0
                    }),
                    Accuracy::Robust | Accuracy::Ordered => {
                        canonical_sign(mode == Accuracy::Robust, ia, ib, io, a, b, o, l)
                    }
                };
                m += i32::from(s);
            }
            out.mult[li * edge_count + e] = m;
            if m != 0 {
                out.silhouettes[li].push((e as u32, m));
            }
        }
    }
    out
}

/// Object-space lights packed object-major for lights `first..first + count`, as uploaded.
pub(crate) fn pack_lights(
    obj_lights: &[Vec<[f32; 4]>],
    first: usize,
    count: usize,
) -> Vec<[f32; 4]> {
    obj_lights
        .iter()
        .flat_map(|per_object| per_object[first..first + count].iter().copied())
        .collect()
}

/// Extracts like the wgpu backend does, on the CPU: the twin kernel over all lights at once,
/// then the same host resolution of uncertain triples (with `orient_exact`). Fills `out` and
/// returns the number of uncertain triples.
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
    check_lights(lights)?;
    let layout = SceneLayout::build(scene, crate::NAME)?;
    let obj_lights = object_lights(scene, lights);
    let packed = pack_lights(&obj_lights, 0, lights.len());
    let k = run_kernel(&layout, &packed, lights.len(), mode, filter);
    out.reset(layout.edge_count(), lights.len());
    let uncertain = k.uncertain.len() as u64;
    let _patch = finish_batch(
        &layout,
        &obj_lights,
        0..lights.len(),
        BatchOutput {
            mult: Some(k.mult),
            lists: k.silhouettes,
            uncertain: k.uncertain,
        },
        out,
    )?;
    Ok(uncertain)
}
