//! The CPU twin of `kernels/silhouette.cl`: the same functions, the same loop over (edge, light)
//! work items and OVs, the same atomic-append outputs, in Rust.
//!
//! When the device and the `cpu` backend disagree, run the twin: if it agrees with `cpu`, the
//! fault is in the kernel build or the driver; if not, in the logic shared by both.
//! [`TwinBackend`] runs it behind the [`SilhouetteBackend`] trait, through the same layout
//! ([`FlatScene`]) and host finishing ([`finish`]) as the device path.

use crate::layout::{
    finish, flat_lights, mode_code, FlatScene, KernelOutput, MODE_EXACT, MODE_ORIGINAL, MODE_ROBUST,
};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::{
    check_lights, object_lights, BackendError, BackendInfo, ExtractStats, Multiplicities,
    PreparedId, PreparedScenes, SilhouetteBackend, TopologyScene,
};
use std::time::Instant;

/// The kernel's "not certified" filter result.
pub const UNCERTAIN: i32 = 2;

const F32_FILTER_EPS: f32 = 1.0 / 524_288.0; // 2^-19
const F32_FILTER_MIN: f32 = 1.0 / 1_099_511_627_776.0; // 2^-40
const F32_FILTER_MAX: f32 = 1_099_511_627_776.0; // 2^40
const F32_PRODUCT_MIN: f32 = f32::from_bits(27 << 23); // 2^-100
const F32_PERM_MIN: f32 = f32::from_bits(31 << 23); // 2^-96
const F64_FILTER_EPS: f64 = 1.0e-15;

fn sgn32(x: f32) -> i32 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// `sv_is_subnormal`: a subnormal `f32`, tested on the bits.
#[must_use]
pub fn is_subnormal(x: f32) -> bool {
    let u = x.to_bits();
    (u & 0x7f80_0000) == 0 && (u & 0x007f_ffff) != 0
}

/// `sv_sign_f32`: `((A − B) × V)·(O − A)` in f32, robust-math's `sign_f32` op order.
#[must_use]
pub fn sign_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i32 {
    let vx = l[0] - l[3] * a[0];
    let vy = l[1] - l[3] * a[1];
    let vz = l[2] - l[3] * a[2];
    let ex = a[0] - b[0];
    let ey = a[1] - b[1];
    let ez = a[2] - b[2];
    let nx = ey * vz - ez * vy;
    let ny = ez * vx - ex * vz;
    let nz = ex * vy - ey * vx;
    let dx = o[0] - a[0];
    let dy = o[1] - a[1];
    let dz = o[2] - a[2];
    sgn32((nx * dx + ny * dy) + nz * dz)
}

fn diff_ok(x: f32, y: f32, d: f32) -> bool {
    if x == y {
        return true;
    }
    let m = d.abs();
    (F32_FILTER_MIN..=F32_FILTER_MAX).contains(&m)
}

fn any_subnormal(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> bool {
    a.iter()
        .chain(&b)
        .chain(&o)
        .chain(&l)
        .any(|&x| is_subnormal(x))
}

/// `sv_filter_f32`: robust-math's `orient_filter_f32` plus the kernel's flush-to-zero guards
/// (subnormal inputs, an underflowing `w * a`, a permanent below 2^-96 are all "uncertain").
/// Returns -1, 0, 1 or [`UNCERTAIN`].
#[must_use]
pub fn filter_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i32 {
    if any_subnormal(a, b, l, o) {
        return UNCERTAIN;
    }
    // For w other than 0 or 1, w*A is rounded, and when it cancels against L.xyz the error of V
    // is relative to |w*A|, not to |V|: the bound would not hold (robust-math's rule).
    if l[3] != 0.0 && l[3] != 1.0 {
        return UNCERTAIN;
    }
    let ex = a[0] - b[0];
    let ey = a[1] - b[1];
    let ez = a[2] - b[2];
    let wx = l[3] * a[0];
    let wy = l[3] * a[1];
    let wz = l[3] * a[2];
    if l[3] != 0.0
        && ((a[0] != 0.0 && wx.abs() < F32_PRODUCT_MIN)
            || (a[1] != 0.0 && wy.abs() < F32_PRODUCT_MIN)
            || (a[2] != 0.0 && wz.abs() < F32_PRODUCT_MIN))
    {
        return UNCERTAIN;
    }
    let vx = l[0] - wx;
    let vy = l[1] - wy;
    let vz = l[2] - wz;
    let dx = o[0] - a[0];
    let dy = o[1] - a[1];
    let dz = o[2] - a[2];
    if !(diff_ok(a[0], b[0], ex)
        && diff_ok(a[1], b[1], ey)
        && diff_ok(a[2], b[2], ez)
        && diff_ok(l[0], wx, vx)
        && diff_ok(l[1], wy, vy)
        && diff_ok(l[2], wz, vz)
        && diff_ok(o[0], a[0], dx)
        && diff_ok(o[1], a[1], dy)
        && diff_ok(o[2], a[2], dz))
    {
        return UNCERTAIN;
    }
    let (p1, q1) = (ey * vz, ez * vy);
    let (p2, q2) = (ez * vx, ex * vz);
    let (p3, q3) = (ex * vy, ey * vx);
    let det = ((p1 - q1) * dx + (p2 - q2) * dy) + (p3 - q3) * dz;
    let perm = ((p1.abs() + q1.abs()) * dx.abs() + (p2.abs() + q2.abs()) * dy.abs())
        + (p3.abs() + q3.abs()) * dz.abs();
    if !perm.is_finite() {
        return UNCERTAIN;
    }
    if perm == 0.0 {
        return 0;
    }
    if perm < F32_PERM_MIN {
        return UNCERTAIN;
    }
    if det.abs() > F32_FILTER_EPS * perm {
        return if det > 0.0 { 1 } else { -1 };
    }
    UNCERTAIN
}

/// `sv_filter_f64`: robust-math's `orient_filter_f64` (same expression and bound); subnormal
/// `f32` inputs are "uncertain". Returns -1, 0, 1 or [`UNCERTAIN`].
#[must_use]
pub fn filter_f64(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i32 {
    if any_subnormal(a, b, l, o) {
        return UNCERTAIN;
    }
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
    let bound = F64_FILTER_EPS * perm;
    if det.abs() > bound {
        if det > 0.0 {
            1
        } else {
            -1
        }
    } else if perm == 0.0 {
        0
    } else {
        UNCERTAIN
    }
}

/// One work item of the kernel: edge `e`, light `l`. Appends to `out` exactly like the kernel's
/// atomics (here in work-item order).
#[allow(clippy::too_many_arguments)]
fn work_item(
    flat: &FlatScene,
    lights: &[f32],
    num_lights: usize,
    mode: u32,
    use_f64: bool,
    e: usize,
    l: usize,
    unc_capacity: usize,
    out: &mut KernelOutput,
) {
    let li = (flat.edge_obj[e] as usize * num_lights + l) * 4;
    let light = [lights[li], lights[li + 1], lights[li + 2], lights[li + 3]];
    let ia = flat.edges[2 * e];
    let ib = flat.edges[2 * e + 1];
    let pa = flat.position(ia);
    let pb = flat.position(ib);
    let begin = flat.ov_offsets[e] as usize;
    let end = flat.ov_offsets[e + 1] as usize;
    let mut m = 0i32;
    for k in begin..end {
        let io = flat.ovs[k];
        let po = flat.position(io);
        let s = if mode == MODE_ORIGINAL {
            sign_f32(pa, pb, light, po)
        } else if mode == MODE_EXACT {
            let s = if use_f64 {
                filter_f64(pa, pb, light, po)
            } else {
                filter_f32(pa, pb, light, po)
            };
            if s == UNCERTAIN {
                let slot = out.counts[0] as usize;
                out.counts[0] += 1;
                if slot < unc_capacity {
                    out.uncertain.push([e as u32, k as u32, l as u32]);
                }
                0
            } else {
                s
            }
        } else {
            let (p0, p1, p2, parity) = if io > ib {
                (pa, pb, po, 1)
            } else if io < ia {
                (po, pa, pb, 1)
            } else {
                (pa, po, pb, -1)
            };
            let s0 = sign_f32(p0, p1, light, p2);
            let s = if mode == MODE_ROBUST {
                let s1 = sign_f32(p1, p2, light, p0);
                let s2 = sign_f32(p2, p0, light, p1);
                if s0 == s1 && s1 == s2 {
                    s0
                } else {
                    0
                }
            } else {
                s0
            };
            s * parity
        };
        m += s;
    }
    if m != 0 {
        out.counts[1] += 1;
        out.silhouettes
            .push(((l * flat.edge_count() + e) as u32, m));
    }
}

/// Runs the kernel's logic over the whole (edge, light) grid, like one enqueue.
///
/// `lights` is the flattened per-(object, light) buffer ([`flat_lights`]); `mode` the kernel's
/// mode code; `use_f64` picks the exact filter.
#[must_use]
pub fn run_kernel(
    flat: &FlatScene,
    lights: &[f32],
    num_lights: usize,
    mode: Accuracy,
    use_f64: bool,
) -> KernelOutput {
    let mut out = KernelOutput {
        counts: vec![0; 2],
        silhouettes: Vec::new(),
        uncertain: Vec::new(),
    };
    let code = mode_code(mode);
    for l in 0..num_lights {
        for e in 0..flat.edge_count() {
            work_item(
                flat,
                lights,
                num_lights,
                code,
                use_f64,
                e,
                l,
                usize::MAX,
                &mut out,
            );
        }
    }
    out
}

/// The twin behind the [`SilhouetteBackend`] trait (name `opencl-twin`; not in the CLI
/// registry). Uses the same layout and host finishing as the device backend.
#[derive(Debug, Default)]
pub struct TwinBackend {
    scenes: PreparedScenes<(TopologyScene, FlatScene)>,
    use_f64: bool,
}

impl TwinBackend {
    /// A twin whose exact mode uses the `f64` filter (`use_f64`) or the `f32` filter.
    #[must_use]
    pub fn new(use_f64: bool) -> Self {
        Self {
            use_f64,
            ..Self::default()
        }
    }
}

impl SilhouetteBackend for TwinBackend {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            name: "opencl-twin",
            device: "host CPU, Rust twin of kernels/silhouette.cl".to_owned(),
            modes: Accuracy::ALL.to_vec(),
            max_lights: None,
            details: vec![(
                "exact_filter".to_owned(),
                if self.use_f64 { "f64" } else { "f32" }.to_owned(),
            )],
        }
    }

    fn prepare(&mut self, scene: &TopologyScene) -> Result<PreparedId, BackendError> {
        let flat = FlatScene::build(scene, "opencl-twin")?;
        Ok(self.scenes.insert((scene.clone(), flat)))
    }

    fn extract(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        let (scene, flat) = self.scenes.get("opencl-twin", id)?;
        check_lights(lights)?;
        let start = Instant::now();
        let obj_lights = object_lights(scene, lights);
        let flat_l = flat_lights(&obj_lights);
        let output = run_kernel(flat, &flat_l, lights.len(), mode, self.use_f64);
        let uncertain = u64::from(output.counts[0]);
        let compute = start.elapsed();
        let start = Instant::now();
        finish(flat, &obj_lights, lights.len(), output, out, "opencl-twin")?;
        Ok(ExtractStats {
            compute,
            host_resolve: start.elapsed(),
            uncertain,
            ..ExtractStats::default()
        })
    }

    fn release(&mut self, id: PreparedId) {
        self.scenes.remove(id);
    }
}
