//! The CPU twin of `kernels/silhouette.cl`: the same functions, the same loop over (edge, light)
//! work items and OVs, the same atomic-append outputs, in Rust.
//!
//! When the device and the `cpu` backend disagree, run the twin: if it agrees with `cpu`, the
//! fault is in the kernel build or the driver; if not, in the logic shared by both.
//! [`TwinBackend`] runs it behind the [`SilhouetteBackend`] trait, through the same layout
//! ([`SceneLayout`]) and host finishing ([`finish`]) as the device path.

use crate::layout::flat_lights;
use crate::resolve::{finish, KernelOutput};
use shadowvol_robust_math::filter::{self, TermsF32};
use shadowvol_robust_math::{orient_filter_f64, Accuracy, Light, F32_FILTER_EPS};
use shadowvol_silhouette::gpu::{
    mode_code, SceneLayout, UncertainRecord, MODE_EXACT, MODE_ORIGINAL, MODE_ROBUST,
};
use shadowvol_silhouette::{
    check_lights, object_lights, BackendError, BackendInfo, ExtractStats, Multiplicities,
    PreparedId, PreparedScenes, SilhouetteBackend, TopologyScene,
};
use std::time::Instant;

/// The registry-style name of [`TwinBackend`] (not in the CLI registry).
pub const TWIN_NAME: &str = "opencl-twin";

/// The kernel's "not certified" filter result.
pub const UNCERTAIN: i32 = 2;

const F32_PRODUCT_MIN: f32 = f32::from_bits(27 << 23); // 2^-100
const F32_PERM_MIN: f32 = f32::from_bits(31 << 23); // 2^-96

fn decision(s: Option<i8>) -> i32 {
    s.map_or(UNCERTAIN, i32::from)
}

/// `sv_is_subnormal`: a subnormal `f32`, tested on the bits (robust-math's
/// [`is_subnormal`](shadowvol_robust_math::filter::is_subnormal)).
#[must_use]
pub fn is_subnormal(x: f32) -> bool {
    filter::is_subnormal(x)
}

/// `sv_sign_f32`: `((A − B) × V)·(O − A)` in f32, robust-math's [`sign_f32`] op order.
#[must_use]
pub fn sign_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i32 {
    i32::from(shadowvol_robust_math::sign_f32(a, b, l, o))
}

/// `sv_filter_f32`: robust-math's `orient_filter_f32` plus the kernel's flush-to-zero guards
/// (subnormal inputs, an underflowing `w * a`, a permanent below 2^-96 are all "uncertain").
/// Returns -1, 0, 1 or [`UNCERTAIN`].
#[must_use]
pub fn filter_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i32 {
    if filter::any_subnormal(a, b, l, o) || !filter::w_is_exact_f32(l[3]) {
        return UNCERTAIN;
    }
    let t = TermsF32::new(a, b, l, o);
    if l[3] != 0.0 && (0..3).any(|i| a[i] != 0.0 && t.wa[i].abs() < F32_PRODUCT_MIN) {
        return UNCERTAIN;
    }
    if !t.diffs_in_range(a, b, l, o) {
        return UNCERTAIN;
    }
    let (det, perm) = t.det_perm();
    if !perm.is_finite() || (perm != 0.0 && perm < F32_PERM_MIN) {
        return UNCERTAIN;
    }
    decision(filter::certify_f32(det, perm, F32_FILTER_EPS))
}

/// `sv_filter_f64`: robust-math's `orient_filter_f64` (same expression and bound); subnormal
/// `f32` inputs are "uncertain". Returns -1, 0, 1 or [`UNCERTAIN`].
#[must_use]
pub fn filter_f64(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i32 {
    if filter::any_subnormal(a, b, l, o) {
        return UNCERTAIN;
    }
    decision(orient_filter_f64(a, b, l, o))
}

/// What every work item of one enqueue shares: the kernel's arguments.
struct Launch<'a> {
    layout: &'a SceneLayout,
    /// The flattened per-(object, light) buffer ([`flat_lights`]).
    lights: &'a [f32],
    num_lights: usize,
    /// The kernel's mode code.
    mode: u32,
    use_f64: bool,
    unc_capacity: usize,
}

/// One work item of the kernel: edge `e`, light `l`. Appends to `out` exactly like the kernel's
/// atomics (here in work-item order).
fn work_item(launch: &Launch<'_>, e: usize, l: usize, out: &mut KernelOutput) {
    let Launch {
        layout,
        lights,
        num_lights,
        mode,
        use_f64,
        unc_capacity,
    } = *launch;
    let (ia, ib, object) = layout.edge(e);
    let li = (object as usize * num_lights + l) * 4;
    let light = [lights[li], lights[li + 1], lights[li + 2], lights[li + 3]];
    let pa = layout.position(ia);
    let pb = layout.position(ib);
    let mut m = 0i32;
    for k in layout.ov_slots(e) {
        let io = layout.ovs[k];
        let po = layout.position(io);
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
                    out.uncertain.push(UncertainRecord {
                        edge: e as u32,
                        ov_slot: k as u32,
                        light: l as u32,
                    });
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
            .push(((l * layout.edge_count() + e) as u32, m));
    }
}

/// Runs the kernel's logic over the whole (edge, light) grid, like one enqueue.
///
/// `lights` is the flattened per-(object, light) buffer ([`flat_lights`]); `mode` the kernel's
/// mode code; `use_f64` picks the exact filter.
#[must_use]
pub fn run_kernel(
    layout: &SceneLayout,
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
    let launch = Launch {
        layout,
        lights,
        num_lights,
        mode: mode_code(mode),
        use_f64,
        unc_capacity: usize::MAX,
    };
    for l in 0..num_lights {
        for e in 0..layout.edge_count() {
            work_item(&launch, e, l, &mut out);
        }
    }
    out
}

/// The twin behind the [`SilhouetteBackend`] trait (name `opencl-twin`; not in the CLI
/// registry). Uses the same layout and host finishing as the device backend.
#[derive(Debug)]
pub struct TwinBackend {
    scenes: PreparedScenes<(TopologyScene, SceneLayout)>,
    use_f64: bool,
}

impl TwinBackend {
    /// A twin whose exact mode uses the `f64` filter (`use_f64`) or the `f32` filter.
    #[must_use]
    pub fn new(use_f64: bool) -> Self {
        Self {
            scenes: PreparedScenes::new(TWIN_NAME),
            use_f64,
        }
    }
}

impl SilhouetteBackend for TwinBackend {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            name: TWIN_NAME,
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
        let layout = SceneLayout::build(scene, TWIN_NAME)?;
        Ok(self.scenes.insert((scene.clone(), layout)))
    }

    fn extract(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        let (scene, layout) = self.scenes.get(id)?;
        check_lights(lights)?;
        let start = Instant::now();
        let obj_lights = object_lights(scene.transforms(), lights);
        let flat_l = flat_lights(&obj_lights);
        let output = run_kernel(layout, &flat_l, lights.len(), mode, self.use_f64);
        let uncertain = u64::from(output.counts[0]);
        let compute = start.elapsed();
        let start = Instant::now();
        finish(layout, &obj_lights, lights.len(), output, out, TWIN_NAME)?;
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
