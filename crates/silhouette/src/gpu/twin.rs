//! What the CPU twins of the per-edge kernels share: the `opencl` kernel and the `vulkan`
//! geometry shader run the same loop over an edge's opposite vertices, differing only in their
//! exact-mode filter, so one CPU version of that loop serves both twins. Used by tests only
//! (through the backends' `twin` modules).

use super::{ExactFilter, SceneLayout};
use crate::{check_lights, object_lights, BackendError, Light, TopologyScene};
use shadowvol_robust_math::{canonical, sign_f32, triangle_sign, Accuracy};

/// A device filter of exact mode for `(A, B, L, O)`: `Some(sign)` only when the sign equals the
/// exact sign of `orient_exact`; `None` leaves the triple to the host.
pub type FilterFn = fn([f32; 3], [f32; 3], [f32; 4], [f32; 3]) -> Option<i8>;

/// A kernel's two exact-mode filters, the one its build picks per [`ExactFilter`].
#[derive(Debug, Clone, Copy)]
pub struct DeviceFilters {
    /// The `f32` filter (devices without `f64`).
    pub f32: FilterFn,
    /// The `f64` filter.
    pub f64: FilterFn,
}

impl DeviceFilters {
    /// The filter a kernel built for `filter` runs.
    #[must_use]
    pub fn get(self, filter: ExactFilter) -> FilterFn {
        match filter {
            ExactFilter::F32 => self.f32,
            ExactFilter::F64 => self.f64,
        }
    }
}

/// What one kernel invocation computes for one (edge, light).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct EdgeResult {
    /// The multiplicity: in exact mode, the sum of the certified signs only.
    pub m: i32,
    /// Global OV slots (into [`SceneLayout::ovs`]) whose sign the filter could not certify.
    pub uncertain: Vec<u32>,
}

/// The kernels' loop over the opposite vertices of global edge `e` for object-space light `l`:
/// `original` the naive `f32` sign per (edge, OV); `robust` and `ordered` the sign of the
/// canonical triangle times the parity; `exact` the device's certified `filter` (one of a
/// kernel's [`DeviceFilters`]), whose `None` leaves the slot to the host.
///
/// # Panics
/// If `e` is out of range.
#[must_use]
pub fn edge_multiplicity(
    layout: &SceneLayout,
    e: usize,
    l: [f32; 4],
    mode: Accuracy,
    filter: FilterFn,
) -> EdgeResult {
    let p = |v: u32| layout.position(v);
    let (a, b, _) = layout.edge(e);
    let mut out = EdgeResult::default();
    for k in layout.ov_slots(e) {
        let o = layout.ovs[k];
        let s = match mode {
            Accuracy::Original => sign_f32(p(a), p(b), l, p(o)),
            Accuracy::Exact => filter(p(a), p(b), l, p(o)).unwrap_or_else(|| {
                out.uncertain.push(k as u32);
                0
            }),
            Accuracy::Robust | Accuracy::Ordered => {
                let ([i0, i1, i2], parity) = canonical(a, b, o);
                let v = |i: u32| glam::Vec3::from_array(p(i));
                triangle_sign(mode, v(i0), v(i1), v(i2), l) * parity
            }
        };
        out.m += i32::from(s);
    }
    out
}

/// What a twin's `extract` starts from, as its backend's `extract` does: the scene laid out
/// (`backend` names it in errors), the object-space lights per object, and the same lights
/// object-major (`[object * light_count + light]`) as the kernels read them.
#[derive(Debug, Clone)]
pub struct TwinInputs {
    /// The flattened scene.
    pub layout: SceneLayout,
    /// `[object][light]`: each light in each object's space ([`object_lights`]).
    pub object_lights: Vec<Vec<[f32; 4]>>,
    /// The same lights, object-major.
    pub packed: Vec<[f32; 4]>,
    /// How many lights.
    pub light_count: usize,
}

impl TwinInputs {
    /// Checks `lights`, lays out `scene` and brings the lights into each object's space.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for no or non-finite lights, [`BackendError::Limit`] for
    /// scenes beyond `u32` indexing.
    pub fn new(
        scene: &TopologyScene,
        lights: &[Light],
        backend: &'static str,
    ) -> Result<Self, BackendError> {
        check_lights(lights)?;
        let layout = SceneLayout::build(scene, backend)?;
        let object_lights = object_lights(scene.transforms(), lights);
        let packed = object_lights.iter().flatten().copied().collect();
        Ok(Self {
            layout,
            object_lights,
            packed,
            light_count: lights.len(),
        })
    }

    /// One launch of a per-edge kernel on the CPU: [`edge_multiplicity`] for every (light,
    /// edge), light by light and edge by edge, each edge with its object's light and the
    /// kernel's exact-mode `filter`; `each(light, edge, result)` takes each result.
    pub fn each_edge_and_light(
        &self,
        mode: Accuracy,
        filter: FilterFn,
        mut each: impl FnMut(usize, usize, EdgeResult),
    ) {
        let n = self.light_count;
        for l in 0..n {
            for e in 0..self.layout.edge_count() {
                let object = self.layout.edge(e).2 as usize;
                let light = self.packed[object * n + l];
                each(
                    l,
                    e,
                    edge_multiplicity(&self.layout, e, light, mode, filter),
                );
            }
        }
    }
}
