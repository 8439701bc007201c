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
//! use shadowvol_wgpu_compute::cpu_twin::{self, ExactFilter};
//!
//! let case = &corpus::cases()[0];
//! let scene = case.scene().unwrap();
//! let mut m = Multiplicities::default();
//! let uncertain = cpu_twin::extract(&scene, &case.lights, Accuracy::Exact, ExactFilter::F32, &mut m).unwrap();
//! assert_eq!(m.light_count(), case.lights.len());
//! assert!(uncertain <= (scene.total_ovs() * case.lights.len()) as u64);
//! ```

use crate::layout::SceneLayout;
use crate::resolve::{finish_chunk, ChunkOutput};
use shadowvol_robust_math::{
    sign_f32, Accuracy, Light, F32_FILTER_EPS, F32_FILTER_MAX, F32_FILTER_MIN, F64_FILTER_EPS,
};
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

#[inline]
fn sgn(x: f32) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

#[inline]
fn is_subnormal(x: f32) -> bool {
    x != 0.0 && x.abs() < f32::MIN_POSITIVE
}

#[inline]
fn out_of_range(x: f32) -> bool {
    let m = x.abs();
    m != 0.0 && !(F32_FILTER_MIN..=F32_FILTER_MAX).contains(&m)
}

/// Twin of WGSL `filter_f32`: robust-math's `orient_filter_f32` (same formula, same
/// [`F32_FILTER_EPS`], range checks, and only `w` in {0, 1} certified) plus the two device guards [`GPU_F32_INPUT_MAX`] and
/// [`GPU_F32_PERM_MIN`]. `Some(sign)` is certified, `None` is uncertain.
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
    {
        return None;
    }
    let (ex, ey, ez) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    if l[3] != 0.0 && l[3] != 1.0 {
        return None;
    }
    let (vx, vy, vz) = (l[0] - l[3] * a[0], l[1] - l[3] * a[1], l[2] - l[3] * a[2]);
    let (dx, dy, dz) = (o[0] - a[0], o[1] - a[1], o[2] - a[2]);
    if [ex, ey, ez, vx, vy, vz, dx, dy, dz]
        .into_iter()
        .any(out_of_range)
    {
        return None;
    }
    let (p1, q1) = (ey * vz, ez * vy);
    let (p2, q2) = (ez * vx, ex * vz);
    let (p3, q3) = (ex * vy, ey * vx);
    let det = ((p1 - q1) * dx + (p2 - q2) * dy) + (p3 - q3) * dz;
    let perm = ((p1.abs() + q1.abs()) * dx.abs() + (p2.abs() + q2.abs()) * dy.abs())
        + (p3.abs() + q3.abs()) * dz.abs();
    if perm == 0.0 {
        return Some(0);
    }
    if perm < GPU_F32_PERM_MIN {
        return None;
    }
    if det.abs() > F32_FILTER_EPS * perm {
        return Some(sgn(det));
    }
    None
}

/// Twin of WGSL `filter_f64` (shaders/exact_f64.wgsl): robust-math's `orient_filter_f64` with
/// the bound [`GPU_F64_FILTER_EPS`].
#[must_use]
pub fn filter_f64(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Option<i8> {
    let (ax, ay, az) = (f64::from(a[0]), f64::from(a[1]), f64::from(a[2]));
    let lw = f64::from(l[3]);
    let ex = ax - f64::from(b[0]);
    let ey = ay - f64::from(b[1]);
    let ez = az - f64::from(b[2]);
    let vx = f64::from(l[0]) - lw * ax;
    let vy = f64::from(l[1]) - lw * ay;
    let vz = f64::from(l[2]) - lw * az;
    let dx = f64::from(o[0]) - ax;
    let dy = f64::from(o[1]) - ay;
    let dz = f64::from(o[2]) - az;
    let (p1, q1) = (ey * vz, ez * vy);
    let (p2, q2) = (ez * vx, ex * vz);
    let (p3, q3) = (ex * vy, ey * vx);
    let det = ((p1 - q1) * dx + (p2 - q2) * dy) + (p3 - q3) * dz;
    let perm = ((p1.abs() + q1.abs()) * dx.abs() + (p2.abs() + q2.abs()) * dy.abs())
        + (p3.abs() + q3.abs()) * dz.abs();
    if det.abs() > GPU_F64_FILTER_EPS * perm {
        return Some(if det > 0.0 { 1 } else { -1 });
    }
    if perm == 0.0 {
        return Some(0);
    }
    None
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
    if a.iter()
        .chain(&b)
        .chain(&o)
        .chain(&l)
        .any(|&x| is_subnormal(x))
    {
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

/// One uncertain `(edge, OV, light)` triple, as the kernel appends it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct UncertainRecord {
    /// Global edge index.
    pub edge: u32,
    /// Global OV slot (index into [`SceneLayout::ovs`]).
    pub ov_slot: u32,
    /// Light index within the dispatch.
    pub light: u32,
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
    let layout = SceneLayout::build(scene)?;
    let packed = pack_lights(&object_lights(scene, lights), 0, lights.len());
    let k = run_kernel(&layout, &packed, lights.len(), mode, filter);
    out.reset(layout.edge_count(), lights.len());
    let uncertain = k.uncertain.len() as u64;
    let _patch = finish_chunk(
        &layout,
        &packed,
        lights.len(),
        0,
        ChunkOutput {
            mult: Some(k.mult),
            lists: k.silhouettes,
            uncertain: k.uncertain,
        },
        out,
    );
    Ok(uncertain)
}
