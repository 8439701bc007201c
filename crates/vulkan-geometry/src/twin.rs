//! The CPU twin of the geometry shader (`shaders/silhouette_gs.geom`).
//!
//! Same buffers ([`DeviceScene`]), same per-edge loop, same filters and the same emitted side
//! quads, in Rust. When the device disagrees with the `cpu` backend, running the twin on the same
//! input tells whether the shader logic or the device arithmetic is at fault.
//!
//! ```
//! use shadowvol_vulkan_geometry::twin::{extract_twin, DeviceFilter};
//! use shadowvol_silhouette::{corpus, Accuracy};
//!
//! let case = &corpus::cases()[0];
//! let scene = case.scene().unwrap();
//! let (m, _uncertain) = extract_twin(&scene, &case.lights, Accuracy::Exact, DeviceFilter::F32).unwrap();
//! assert_eq!(m.edge_count(), scene.total_edges());
//! ```

use glam::{Mat4, Vec3, Vec4};
use shadowvol_robust_math::{
    orient_exact, orient_filter_f64, sign_f32, Accuracy, Light, F32_FILTER_EPS, F32_FILTER_MAX,
    F32_FILTER_MIN,
};
use shadowvol_silhouette::{
    check_lights, object_lights, BackendError, Multiplicities, TopologyScene,
};

/// Shader mode codes (push constant `mode`).
pub mod mode_code {
    /// [`shadowvol_robust_math::Accuracy::Original`].
    pub const ORIGINAL: u32 = 0;
    /// [`shadowvol_robust_math::Accuracy::Robust`].
    pub const ROBUST: u32 = 1;
    /// [`shadowvol_robust_math::Accuracy::Ordered`].
    pub const ORDERED: u32 = 2;
    /// [`shadowvol_robust_math::Accuracy::Exact`] (device filter + host resolution).
    pub const EXACT: u32 = 3;
    /// Emit quads from multiplicities already in the result buffer (the render path's exact mode).
    pub const PRECOMPUTED: u32 = 4;
}

/// The shader code of an accuracy mode.
#[must_use]
pub fn mode_code_of(mode: Accuracy) -> u32 {
    match mode {
        Accuracy::Original => mode_code::ORIGINAL,
        Accuracy::Robust => mode_code::ROBUST,
        Accuracy::Ordered => mode_code::ORDERED,
        Accuracy::Exact => mode_code::EXACT,
    }
}

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

/// The global arrays the shaders read, built from a [`TopologyScene`].
///
/// Vertex ids are global: object `i`'s welded vertex `v` is `vertex_base[i] + v`. Adding the same
/// base to all ids of an object keeps their order, so canonical orders and parities are those of
/// the object-local ids the `cpu` backend uses.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DeviceScene {
    /// Welded positions of all objects (object space), `xyz` per vertex.
    pub positions: Vec<[f32; 3]>,
    /// Per global edge: `(a, b, first OV, one past the last OV)`, global ids and OV indices.
    pub edges: Vec<[u32; 4]>,
    /// Opposite vertices (global ids).
    pub ovs: Vec<u32>,
    /// Object index of every global edge.
    pub edge_object: Vec<u32>,
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
    /// First global vertex id of each object.
    pub vertex_base: Vec<u32>,
}

fn too_large(what: &str, count: usize) -> BackendError {
    BackendError::Limit {
        backend: "vulkan",
        message: format!("{what} is {count}, more than u32 indices can address"),
    }
}

impl DeviceScene {
    /// Lays out `scene` for the device.
    ///
    /// # Errors
    /// [`BackendError::Limit`] when a count exceeds `u32` indexing.
    pub fn build(scene: &TopologyScene) -> Result<Self, BackendError> {
        let (vertices, edges, ovs) = (
            scene.total_vertices(),
            scene.total_edges(),
            scene.total_ovs(),
        );
        for (what, n) in [
            ("the number of vertices", vertices),
            ("the number of edges", edges),
            ("the number of opposite vertices", ovs),
            (
                "the number of triangle corners",
                3 * scene.total_triangles(),
            ),
        ] {
            if u32::try_from(n).is_err() {
                return Err(too_large(what, n));
            }
        }
        let mut ds = DeviceScene::default();
        for (i, o) in scene.objects.iter().enumerate() {
            let t = &o.table;
            let base = ds.positions.len() as u32;
            let ov_base = ds.ovs.len() as u32;
            ds.vertex_base.push(base);
            ds.positions
                .extend(t.positions.iter().map(|p| p.to_array()));
            ds.vertex_object
                .extend(std::iter::repeat_n(i as u32, t.positions.len()));
            ds.ovs.extend(t.ovs.iter().map(|&v| v + base));
            for (e, &[a, b]) in t.edges.iter().enumerate() {
                ds.edges.push([
                    a + base,
                    b + base,
                    t.ov_offsets[e] + ov_base,
                    t.ov_offsets[e + 1] + ov_base,
                ]);
                ds.edge_object.push(i as u32);
            }
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
        self.positions[v as usize]
    }
}

#[inline]
fn subnormal(x: f32) -> bool {
    x != 0.0 && !x.is_normal() && x.is_finite()
}

#[inline]
fn diff_ok(x: f32, y: f32, d: f32) -> bool {
    let m = d.abs();
    if m == 0.0 {
        return x == y;
    }
    (F32_FILTER_MIN..=F32_FILTER_MAX).contains(&m)
}

/// The shader's `f32` filter: [`shadowvol_robust_math::orient_filter_f32`] plus guards that keep
/// it certified on devices that flush `f32` denormals to zero (subnormal inputs, non-zero
/// differences flushed to zero, `L.w * A` leaving the normal range are all "uncertain").
///
/// Returns `Some(sign)` only when the sign equals the exact sign.
#[must_use]
pub fn device_filter_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Option<i8> {
    if a.iter()
        .chain(&b)
        .chain(&o)
        .chain(&l)
        .any(|&x| subnormal(x))
    {
        return None;
    }
    // For w other than 0 or 1, w*A is rounded, and when it cancels against L.xyz the error of V
    // is relative to |w*A|, not to |V|: the bound would not hold (robust-math's rule).
    if l[3] != 0.0 && l[3] != 1.0 {
        return None;
    }
    let e = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let la = [l[3] * a[0], l[3] * a[1], l[3] * a[2]];
    let v = [l[0] - la[0], l[1] - la[1], l[2] - la[2]];
    let d = [o[0] - a[0], o[1] - a[1], o[2] - a[2]];
    for i in 0..3 {
        if !diff_ok(a[i], b[i], e[i]) || !diff_ok(l[i], la[i], v[i]) || !diff_ok(o[i], a[i], d[i]) {
            return None;
        }
        // `L.w * A` must stay normal: an underflowed (or flushed) product has an absolute error.
        if (l[3] != 0.0 && a[i] != 0.0 && la[i].abs() < f32::MIN_POSITIVE) || la[i].is_infinite() {
            return None;
        }
    }
    let (p1, q1) = (e[1] * v[2], e[2] * v[1]);
    let (p2, q2) = (e[2] * v[0], e[0] * v[2]);
    let (p3, q3) = (e[0] * v[1], e[1] * v[0]);
    let det = (p1 - q1) * d[0] + (p2 - q2) * d[1] + (p3 - q3) * d[2];
    let perm = (p1.abs() + q1.abs()) * d[0].abs()
        + (p2.abs() + q2.abs()) * d[1].abs()
        + (p3.abs() + q3.abs()) * d[2].abs();
    if !perm.is_finite() || det.is_nan() {
        return None;
    }
    if det.abs() > F32_FILTER_EPS * perm {
        Some(if det > 0.0 { 1 } else { -1 })
    } else if perm == 0.0 {
        Some(0)
    } else {
        None
    }
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
    /// Global OV indices (into [`DeviceScene::ovs`]) whose sign the device could not certify.
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
    let [a, b, begin, end] = ds.edges[e];
    let mut out = GsEdge::default();
    for k in begin..end {
        let o = ds.ovs[k as usize];
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

/// The exact sign of an uncertain (edge, OV) pair, as the host decides it.
///
/// # Panics
/// If `e` or `k` is out of range.
#[must_use]
pub fn resolve_uncertain(ds: &DeviceScene, e: usize, k: u32, l: [f32; 4]) -> i8 {
    let [a, b, _, _] = ds.edges[e];
    let o = ds.ovs[k as usize];
    orient_exact(ds.p(a), ds.p(b), l, ds.p(o))
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
    let obj_lights = object_lights(scene, lights);
    let mut out = Multiplicities::zeroed(ds.edges.len(), lights.len());
    let mut uncertain = 0u64;
    for li in 0..lights.len() {
        let values = out.values_mut(li);
        for (e, v) in values.iter_mut().enumerate() {
            let l = obj_lights
                .get(ds.edge_object[e] as usize)
                .and_then(|per_light| per_light.get(li))
                .copied()
                .unwrap_or([0.0; 4]);
            let r = gs_edge(&ds, e, l, mode, filter);
            *v = r.m;
            for k in r.uncertain {
                uncertain += 1;
                *v += i32::from(resolve_uncertain(&ds, e, k, l));
            }
        }
    }
    out.rebuild_silhouettes();
    Ok((out, uncertain))
}
