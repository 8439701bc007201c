//! The CPU twin of the geometry shader (`shaders/silhouette_gs.geom`).
//!
//! Same buffers ([`DeviceScene`]), same per-edge loop, same filters and the same emitted side
//! quads, in Rust. When the device disagrees with the `cpu` backend, running the twin on the same
//! input tells whether the shader logic or the device arithmetic is at fault.
//!
//! ```
//! use shadowvol_vulkan_geometry::twin::{extract_twin, DeviceFilter};
//! use shadowvol_silhouette::Accuracy;
//! use shadowvol_test_support::corpus;
//!
//! let case = &corpus::cases()[0];
//! let scene = case.scene().unwrap();
//! let (m, _uncertain) = extract_twin(&scene, &case.lights, Accuracy::Exact, DeviceFilter::F32).unwrap();
//! assert_eq!(m.edge_count(), scene.total_edges());
//! ```

use crate::NAME;
use glam::{Mat4, Vec3, Vec4};
use shadowvol_robust_math::filter::{self, TermsF32};
use shadowvol_robust_math::{orient_filter_f64, sign_f32, Accuracy, Light, F32_FILTER_EPS};
use shadowvol_silhouette::gpu::{self, SceneLayout, UncertainRecord};
use shadowvol_silhouette::{
    check_lights, object_lights, BackendError, Multiplicities, TopologyScene,
};

/// The shader's mode code that emits quads from multiplicities already in the result buffer
/// (the render path's exact mode). The other codes are [`shadowvol_silhouette::gpu::mode_code`]'s.
pub const MODE_PRECOMPUTED: u32 = 4;

/// Which certified filter exact mode runs on the device.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DeviceFilter {
    /// `orient_filter_f64` (devices with `shaderFloat64`).
    F64,
    /// The `f32` filter with the shader's denormal guards ([`device_filter_f32`]).
    F32,
}

impl DeviceFilter {
    /// `"f64"` or `"f32"`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            DeviceFilter::F64 => "f64",
            DeviceFilter::F32 => "f32",
        }
    }
}

/// The global arrays the shaders read, built from a [`TopologyScene`]: the shared
/// [`SceneLayout`] (positions, edge records, opposite vertices) and what the render path adds.
///
/// Vertex ids are global: object `i`'s welded vertex `v` is `layout.vertex_offsets[i] + v`.
/// Adding the same base to all ids of an object keeps their order, so canonical orders and
/// parities are those of the object-local ids the `cpu` backend uses.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DeviceScene {
    /// Positions, edge records `(a, b, first OV slot, object)` plus the sentinel, and opposite
    /// vertices.
    pub layout: SceneLayout,
    /// Object index of every global vertex.
    pub vertex_object: Vec<u32>,
    /// Triangle corners (global ids), three per kept triangle.
    pub corners: Vec<u32>,
    /// World-from-object matrices, column-major.
    pub models: Vec<[f32; 16]>,
    /// Per object, a point near its vertices (the centre of their bounding box, rounded to
    /// `f32`): the render path transforms `position - anchor`, which keeps precision for objects
    /// far from the origin.
    pub anchors: Vec<[f32; 3]>,
}

impl DeviceScene {
    /// Lays out `scene` for the device.
    ///
    /// # Errors
    /// [`BackendError::Limit`] when a count exceeds `u32` indexing.
    pub fn build(scene: &TopologyScene) -> Result<Self, BackendError> {
        let layout = SceneLayout::build(scene, NAME)?;
        let corners = 3 * scene.total_triangles();
        if u32::try_from(corners).is_err() {
            return Err(BackendError::Limit {
                backend: NAME,
                message: format!(
                    "the number of triangle corners is {corners}, more than u32 indices can address"
                ),
            });
        }
        let mut ds = DeviceScene {
            layout,
            ..DeviceScene::default()
        };
        for (i, o) in scene.objects.iter().enumerate() {
            let t = &o.table;
            let base = ds.layout.vertex_offsets[i];
            ds.vertex_object
                .extend(std::iter::repeat_n(i as u32, t.positions.len()));
            ds.corners
                .extend(t.triangles.iter().flat_map(|tri| tri.map(|v| v + base)));
            ds.models
                .push(Mat4::from(o.world_from_object).to_cols_array());
            let (lo, hi) = t.positions.iter().fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), &p| (lo.min(p), hi.max(p)),
            );
            let anchor = if t.positions.is_empty() {
                Vec3::ZERO
            } else {
                (lo.as_dvec3() * 0.5 + hi.as_dvec3() * 0.5).as_vec3()
            };
            ds.anchors.push(anchor.to_array());
        }
        Ok(ds)
    }

    fn p(&self, v: u32) -> [f32; 3] {
        self.layout.position(v)
    }
}

/// The shader's `f32` filter: [`shadowvol_robust_math::orient_filter_f32`] plus guards that keep
/// it certified on devices that flush `f32` denormals to zero (subnormal inputs, non-zero
/// differences flushed to zero, `L.w * A` leaving the normal range are all "uncertain").
///
/// Returns `Some(sign)` only when the sign equals the exact sign.
#[must_use]
pub fn device_filter_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Option<i8> {
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

/// The device filter of exact mode: `Some(sign)` when certified, `None` when the host must decide.
#[must_use]
pub fn device_filter(
    filter: DeviceFilter,
    a: [f32; 3],
    b: [f32; 3],
    l: [f32; 4],
    o: [f32; 3],
) -> Option<i8> {
    match filter {
        DeviceFilter::F64 => orient_filter_f64(a, b, l, o),
        DeviceFilter::F32 => device_filter_f32(a, b, l, o),
    }
}

/// What one geometry-shader invocation computes for one (edge, light).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct GsEdge {
    /// The multiplicity the shader writes: in exact mode, the sum of the certified signs only.
    pub m: i32,
    /// Global OV slots (into [`SceneLayout::ovs`]) whose sign the device could not certify.
    pub uncertain: Vec<u32>,
}

/// The shader's per-edge loop for global edge `e` and object-space light `l`.
///
/// # Panics
/// If `e` is out of range.
#[must_use]
pub fn gs_edge(
    ds: &DeviceScene,
    e: usize,
    l: [f32; 4],
    mode: Accuracy,
    filter: DeviceFilter,
) -> GsEdge {
    let (a, b, _) = ds.layout.edge(e);
    let mut out = GsEdge::default();
    for k in ds.layout.ov_slots(e) {
        let k = k as u32;
        let o = ds.layout.ovs[k as usize];
        let s = match mode {
            Accuracy::Original => sign_f32(ds.p(a), ds.p(b), l, ds.p(o)),
            Accuracy::Exact => match device_filter(filter, ds.p(a), ds.p(b), l, ds.p(o)) {
                Some(s) => s,
                None => {
                    out.uncertain.push(k);
                    0
                }
            },
            Accuracy::Robust | Accuracy::Ordered => {
                let (i0, i1, i2, parity) = if o > b {
                    (a, b, o, 1)
                } else if o < a {
                    (o, a, b, 1)
                } else {
                    (a, o, b, -1)
                };
                let (p0, p1, p2) = (ds.p(i0), ds.p(i1), ds.p(i2));
                let mut t = sign_f32(p0, p1, l, p2);
                if mode == Accuracy::Robust {
                    let t1 = sign_f32(p1, p2, l, p0);
                    let t2 = sign_f32(p2, p0, l, p1);
                    if t != t1 || t1 != t2 {
                        t = 0;
                    }
                }
                t * parity
            }
        };
        out.m += i32::from(s);
    }
    out
}

/// True when `p` is the point light `l` in `f32` arithmetic: `l.w != 0` and `p * l.w == l.xyz`
/// componentwise. The render path follows the renderer crate's convention that triangles with
/// such a vertex cast no shadow volume (with the light at a vertex the shadow has no volume);
/// extraction results are not affected.
#[must_use]
pub fn touches_light(p: [f32; 3], l: [f32; 4]) -> bool {
    l[3] != 0.0 && (0..3).all(|k| p[k] * l[3] == l[k])
}

/// The side quad the shader emits (|m| times) for edge `(A, B)` with multiplicity sign
/// `m.signum()`, as homogeneous object-space points in triangle-strip order: `A, B, A∞, B∞` for
/// `m > 0`, `B, A, B∞, A∞` for `m < 0`, where `X∞ = (X * L.w - L.xyz, 0)` is the point at infinity
/// away from the light.
#[must_use]
pub fn side_quad(a: Vec3, b: Vec3, l: [f32; 4], m: i32) -> [Vec4; 4] {
    let lxyz = Vec3::new(l[0], l[1], l[2]);
    let ca = a.extend(1.0);
    let cb = b.extend(1.0);
    let ia = (a * l[3] - lxyz).extend(0.0);
    let ib = (b * l[3] - lxyz).extend(0.0);
    if m > 0 {
        [ca, cb, ia, ib]
    } else {
        [cb, ca, ib, ia]
    }
}

/// Runs the twin over a whole scene: the shader loop for every (edge, light), then the host
/// resolution of uncertain pairs, exactly as [`crate::VulkanBackend`] does. Returns the
/// multiplicities (with compact lists) and the number of uncertain pairs.
///
/// # Errors
/// [`BackendError::InvalidInput`] for no lights, [`BackendError::Limit`] for oversized scenes.
pub fn extract_twin(
    scene: &TopologyScene,
    lights: &[Light],
    mode: Accuracy,
    filter: DeviceFilter,
) -> Result<(Multiplicities, u64), BackendError> {
    check_lights(lights)?;
    let ds = DeviceScene::build(scene)?;
    let obj_lights = object_lights(scene.transforms(), lights);
    let mut out = Multiplicities::zeroed(ds.layout.edge_count(), lights.len());
    let mut records = Vec::new();
    let edges = ds.layout.edge_count().max(1);
    for (li, values) in out.all_values_mut().chunks_mut(edges).enumerate() {
        for (e, v) in values.iter_mut().enumerate() {
            let l = obj_lights[ds.layout.edge(e).2 as usize][li];
            let r = gs_edge(&ds, e, l, mode, filter);
            *v = r.m;
            records.extend(r.uncertain.into_iter().map(|k| UncertainRecord {
                edge: e as u32,
                ov_slot: k,
                light: li as u32,
            }));
        }
    }
    gpu::resolve_uncertain(
        &ds.layout,
        &obj_lights,
        0..lights.len(),
        &records,
        &mut out,
        NAME,
    )?;
    out.rebuild_silhouettes();
    Ok((out, records.len() as u64))
}
