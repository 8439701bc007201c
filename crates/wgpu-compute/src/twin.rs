//! The CPU twin of `shaders/silhouette.wgsl` (and `shaders/exact_f64.wgsl`).
//!
//! Each function here mirrors one WGSL function, statement for statement, and [`run_kernel`]
//! mirrors the two steps: one "invocation" per global triangle of a [`TriangleLayout`] (a sign
//! per light, undecided pairs appended in exact mode), then one per global edge of a
//! [`SceneLayout`] (lights in the outer loop, opposite vertices in the inner one, the compact
//! list appended when `m != 0`). When the GPU disagrees with the `cpu` backend, run the
//! twin on the same input: if the twin is right, the fault is in the device or the WGSL
//! translation; if it is wrong too, it is in the algorithm (vello keeps CPU shaders for the same
//! reason).
//!
//! The only intended difference from the device is floating-point contraction: Rust never fuses
//! `a * b + c`, a GPU compiler may. That can change the last bits of the `f32` modes, never the
//! exact mode, whose filters certify only signs that hold with contraction too.
//!
//! ```
//! use shadowvol_silhouette::{Accuracy, Multiplicities};
//! use shadowvol_test_support::corpus;
//! use shadowvol_wgpu_compute::twin::{self, ExactFilter};
//!
//! let case = &corpus::cases()[0];
//! let scene = case.scene().unwrap();
//! let mut m = Multiplicities::default();
//! let uncertain = twin::extract(&scene, &case.lights, Accuracy::Exact, ExactFilter::F32, &mut m).unwrap();
//! assert_eq!(m.light_count(), case.lights.len());
//! assert!(uncertain <= (scene.total_ovs() * case.lights.len()) as u64);
//! ```

use crate::resolve::{expand_uncertain, finish_batch, BatchOutput, UncertainTriangle};
use shadowvol_robust_math::filter::{self, TermsF32};
use shadowvol_robust_math::{sign_f32, Accuracy, Light, F32_FILTER_EPS, F64_FILTER_EPS};
use shadowvol_silhouette::gpu::{SceneLayout, TriangleLayout, NEGATIVE};
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

/// Twin of WGSL `triangle_sign_traced`: the sign of the canonical triangle `(p0, p1, p2)` (ids
/// ascending) in `mode`, and whether exact mode needed the fallback (the filter could not
/// certify it). The sign is `None` when exact mode leaves it to the host (`device_exact`
/// false); with `device_exact`, [`orient_int`](crate::exact_int::orient_int) decides it.
/// `original` evaluates the one order, as `ordered` does (the kernel's edge step does not use it
/// in that mode; the renderer's caps do).
#[must_use]
pub fn triangle_sign(
    mode: Accuracy,
    filter: ExactFilter,
    device_exact: bool,
    [p0, p1, p2]: [[f32; 3]; 3],
    l: [f32; 4],
) -> (Option<i8>, bool) {
    match mode {
        Accuracy::Exact => match exact_filter(filter, p0, p1, l, p2) {
            Some(s) => (Some(s), false),
            None if device_exact => (Some(crate::exact_int::orient_int(p0, p1, l, p2)), true),
            None => (None, true),
        },
        Accuracy::Robust => {
            let s0 = sign_f32(p0, p1, l, p2);
            let s1 = sign_f32(p1, p2, l, p0);
            let s2 = sign_f32(p2, p0, l, p1);
            (Some(if s0 == s1 && s1 == s2 { s0 } else { 0 }), false)
        }
        Accuracy::Ordered | Accuracy::Original => (Some(sign_f32(p0, p1, l, p2)), false),
    }
}

/// The sign value of a triangle the renderer's resident pass marks as touching the light (a
/// vertex exactly at the point light): it has no volume. WGSL `TOUCH`.
pub const TOUCH: i32 = 2;

/// The inputs of one edge step: the scene, its triangles, the triangle step's signs
/// (`[light * tri_count + triangle]`) and the object-major lights.
#[derive(Debug, Clone, Copy)]
pub struct EdgeInputs<'a> {
    /// Positions, edges and opposite vertices.
    pub layout: &'a SceneLayout,
    /// Triangles and the triangle of each opposite-vertex slot.
    pub triangles: &'a TriangleLayout,
    /// The triangle step's signs (unused by `original` unless `touch_signs`).
    pub signs: &'a [i32],
    /// `lights[object * light_count + light]`, object space.
    pub lights: &'a [[f32; 4]],
    /// Lights of the dispatch.
    pub light_count: usize,
    /// WGSL `TOUCH_SIGNS`: skip opposite vertices whose triangle's sign is [`TOUCH`].
    pub touch_signs: bool,
}

/// Twin of WGSL `edge_multiplicity`: `m` of global edge `e` for light `li`. `original` sums the
/// naive per-(edge, OV) signs; the other modes sum the parity times the signs of the OVs'
/// triangles. [`TOUCH`] triangles contribute nothing.
///
/// # Panics
/// Panics if `e`, `li` or the inputs are out of range.
#[must_use]
pub fn edge_multiplicity(x: &EdgeInputs<'_>, e: usize, li: usize, mode: Accuracy) -> i32 {
    let [ia, ib, _, object] = x.layout.edges[e];
    let row = li * x.triangles.tri_count();
    let triangle = |k: usize| row + (x.triangles.ov_tris[k] & !NEGATIVE) as usize;
    let mut m = 0i32;
    if mode == Accuracy::Original {
        let l = x.lights[object as usize * x.light_count + li];
        let (a, b) = (x.layout.position(ia), x.layout.position(ib));
        for k in x.layout.ov_slots(e) {
            if x.touch_signs && x.signs[triangle(k)] == TOUCH {
                continue;
            }
            m += i32::from(sign_f32(a, b, l, x.layout.position(x.layout.ovs[k])));
        }
    } else {
        for k in x.layout.ov_slots(e) {
            let s = x.signs[triangle(k)];
            if s != TOUCH {
                m += if x.triangles.ov_tris[k] & NEGATIVE != 0 {
                    -s
                } else {
                    s
                };
            }
        }
    }
    m
}

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
/// object-major (`lights[object * light_count + light]`, object-space, from [`object_lights`]).
/// What the exact filter cannot certify is left to the host (see [`run_kernel_with`]).
///
/// # Panics
/// Panics if `lights.len() != layout.object_count() * light_count`, or `triangles` was not built
/// against `layout`.
#[must_use]
pub fn run_kernel(
    layout: &SceneLayout,
    triangles: &TriangleLayout,
    lights: &[[f32; 4]],
    light_count: usize,
    mode: Accuracy,
    filter: ExactFilter,
) -> KernelOutput {
    run_kernel_with(layout, triangles, lights, light_count, mode, filter, false)
}

/// [`run_kernel`] for the module of
/// [`module_source_with`](crate::shaders::module_source_with): with `device_exact`, the backend's
/// exact pipelines. The triangle step (built with `DEFER_INT`) appends what the filter cannot
/// certify, with sign 0; `resolve_uncertain` then decides each appended pair with
/// [`orient_int`](crate::exact_int::orient_int) ([`KernelOutput::resolved`]), and nothing is left
/// in [`KernelOutput::uncertain`]. The inline fallback pipeline gives the same signs with no
/// list.
///
/// # Panics
/// As [`run_kernel`].
#[must_use]
pub fn run_kernel_with(
    layout: &SceneLayout,
    triangles: &TriangleLayout,
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
    let tri_count = triangles.tri_count();
    let mut out = KernelOutput {
        signs: vec![0; tri_count * light_count],
        mult: vec![0; edge_count * light_count],
        silhouettes: vec![Vec::new(); light_count],
        uncertain: Vec::new(),
        resolved: Vec::new(),
    };
    if mode != Accuracy::Original {
        // The triangle step: one invocation per triangle.
        for (t, tr) in triangles.tris.iter().enumerate() {
            let p = [tr[0], tr[1], tr[2]].map(|v| layout.position(v));
            for li in 0..light_count {
                let l = lights[tr[3] as usize * light_count + li];
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
            let tr = triangles.tris[r.triangle as usize];
            let p = [tr[0], tr[1], tr[2]].map(|v| layout.position(v));
            let l = lights[tr[3] as usize * light_count + r.light as usize];
            let s = triangle_sign(mode, filter, true, p, l).0;
            out.signs[r.light as usize * tri_count + r.triangle as usize] =
                i32::from(s.expect("the integer path decides every pair"));
        }
        out.resolved = std::mem::take(&mut out.uncertain);
    }
    // The edge step: one invocation per edge.
    let x = EdgeInputs {
        layout,
        triangles,
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
    check_lights(lights)?;
    let layout = SceneLayout::build(scene, crate::NAME)?;
    let triangles = TriangleLayout::build(scene, &layout, crate::NAME)?;
    let obj_lights = object_lights(scene.transforms(), lights);
    let packed = pack_lights(&obj_lights, 0, lights.len());
    let k = run_kernel(&layout, &triangles, &packed, lights.len(), mode, filter);
    out.reset(layout.edge_count(), lights.len());
    let records = if k.uncertain.is_empty() {
        Vec::new()
    } else {
        expand_uncertain(&k.uncertain, &triangles.edge_slots(&layout), lights.len())?
    };
    let uncertain = records.len() as u64;
    let _patch = finish_batch(
        &layout,
        &obj_lights,
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
