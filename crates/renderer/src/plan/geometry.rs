//! The geometry the plan decides with: frustum and near-clip volume planes, box and point
//! tests, and the exact per-triangle near-plane test.

use glam::{DVec3, DVec4, Vec3};
use shadowvol_robust_math::orient_exact;

/// Which side of triangle `t`'s plane the light `l` is on, as `sgn H(a, b, c, L)` with
/// `H(a, b, c, X) = −(n · (X − a))` for a point `X` and `n = (b − a) × (c − a)`; 0 when the light
/// lies in the plane (the triangle casts no shadow of it). Exact for any finite `f32` input.
#[must_use]
pub(super) fn light_side(t: [Vec3; 3], l: [f32; 4]) -> i8 {
    // orient_exact(a, b, l, c) is sgn det(a 1; b 1; L; c 1): H's rows with the last two swapped.
    -orient_exact(t[0].to_array(), t[1].to_array(), l, t[2].to_array())
}

/// A plane `n · x + d >= 0` is inside, as `(n, d)`.
pub type Plane = DVec4;

pub(super) fn plane_through(p: DVec3, normal: DVec3, inside: DVec3) -> Option<Plane> {
    let len = normal.length();
    if len.is_nan() || len <= 0.0 || !len.is_finite() {
        return None;
    }
    let n = normal / len;
    let mut pl = n.extend(-n.dot(p));
    if eval(pl, inside) < 0.0 {
        pl = -pl;
    }
    // The reference point must be strictly inside, or the plane is degenerate for it.
    (eval(pl, inside) > 0.0).then_some(pl)
}

#[inline]
pub(super) fn eval(pl: Plane, p: DVec3) -> f64 {
    pl.truncate().dot(p) + pl.w
}

/// The five inward planes of the view frustum (left, right, bottom, top, near).
#[must_use]
pub fn frustum_planes(eye: DVec3, near: [DVec3; 4]) -> Vec<Plane> {
    let centre = (near[0] + near[1] + near[2] + near[3]) / 4.0;
    let forward = centre - eye;
    let inside = eye + forward * 2.0;
    let mut v = Vec::with_capacity(5);
    for i in 0..4 {
        let (a, b) = (near[i], near[(i + 1) % 4]);
        if let Some(p) = plane_through(eye, (a - eye).cross(b - eye), inside) {
            v.push(p);
        }
    }
    if let Some(p) = plane_through(centre, forward, inside) {
        v.push(p);
    }
    v
}

/// The 8 corners of a box.
#[must_use]
pub fn box_corners(lo: DVec3, hi: DVec3) -> [DVec3; 8] {
    let mut c = [DVec3::ZERO; 8];
    for (i, v) in c.iter_mut().enumerate() {
        *v = DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
    }
    c
}

/// True when the shadow volume of the box `(lo, hi)` under `light` provably lies outside the
/// frustum given by its inward `planes` (then the object's shadow cannot be seen).
#[must_use]
pub fn shadow_outside_frustum(lo: DVec3, hi: DVec3, light: [f32; 4], planes: &[Plane]) -> bool {
    let l = DVec4::new(
        f64::from(light[0]),
        f64::from(light[1]),
        f64::from(light[2]),
        f64::from(light[3]),
    );
    let corners = box_corners(lo, hi);
    let margin = relative_margin(lo, hi);
    planes.iter().any(|&pl| {
        corners.iter().all(|&c| {
            let dir = c * l.w - l.truncate();
            eval(pl, c) < -margin && pl.truncate().dot(dir) <= 0.0
        })
    })
}

/// The planes of the near-clip volume (convex hull of the light and the near rectangle; for a
/// directional light the rectangle swept towards the light), inward. `None` when the volume is
/// degenerate (light in the near plane, direction parallel to it): then z-pass is never proven
/// safe.
#[must_use]
pub fn near_clip_volume(near: [DVec3; 4], light: [f32; 4]) -> Option<Vec<Plane>> {
    let l = DVec3::new(
        f64::from(light[0]),
        f64::from(light[1]),
        f64::from(light[2]),
    );
    let w = f64::from(light[3]);
    let centre = (near[0] + near[1] + near[2] + near[3]) / 4.0;
    let rect_n = (near[1] - near[0]).cross(near[3] - near[0]);
    let mut planes = Vec::with_capacity(5);
    if w == 0.0 {
        let d = l;
        let inside = centre + d.normalize() * (near[1] - near[0]).length();
        planes.push(plane_through(centre, rect_n, inside)?);
        for i in 0..4 {
            let (a, b) = (near[i], near[(i + 1) % 4]);
            planes.push(plane_through(a, (b - a).cross(d), inside)?);
        }
    } else {
        let lp = l / w;
        if !lp.is_finite() {
            return None;
        }
        let inside = (centre * 4.0 + lp) / 5.0;
        planes.push(plane_through(centre, rect_n, inside)?);
        for i in 0..4 {
            let (a, b) = (near[i], near[(i + 1) % 4]);
            planes.push(plane_through(a, (b - a).cross(lp - a), inside)?);
        }
    }
    Some(planes)
}

/// Objects with more triangles than this keep z-fail when their box meets the near-clip volume:
/// [`near_rect_clear_of_shadows`] costs one exact side test per triangle per light, on the host,
/// every frame.
pub const ZPASS_TRIANGLE_TEST_MAX: usize = 1 << 18;

/// True when no point of the near-plane rectangle `near` (world space, `f64`) lies in the
/// shadow of any triangle `triangles` (ids into `world`, the `f32` world positions the volumes
/// are drawn from) under `light` (world space, homogeneous `f32`): then z-pass counts are
/// correct for this object whatever its silhouette.
///
/// A triangle's shadow lies on the far side of its plane from the light, so the rectangle is
/// clear of it when each of its corners is strictly on the light's side (which side the light is
/// on: `orient_exact`'s exact sign), or, for a light in the plane (a shadow of no volume), strictly off the plane; or when the
/// triangle lies strictly outside one of the near-clip volume's inward `planes` (see
/// [`near_clip_volume`]; then no ray from the light to the rectangle passes through it). The
/// corners' sides are evaluated in `f64` with a relative margin of `10⁻⁹`, so the test is
/// conservative: a corner near a triangle's plane makes it false.
///
/// # Panics
/// Panics if a triangle's id is out of range of `world`.
#[must_use]
pub fn near_rect_clear_of_shadows(
    world: &[Vec3],
    triangles: &[[u32; 3]],
    light: [f32; 4],
    near: [DVec3; 4],
    planes: &[Plane],
) -> bool {
    let hull = NearClipHull::new(light, near);
    triangles.iter().all(|t| {
        let v = [
            world[t[0] as usize],
            world[t[1] as usize],
            world[t[2] as usize],
        ];
        let a = v[0].as_dvec3();
        let n = (v[1].as_dvec3() - a).cross(v[2].as_dvec3() - a);
        let nlen = n.length();
        if !nlen.is_finite() {
            return false;
        }
        // sgn H(a, b, c, X) = −sgn(n · (X − a)) for a point X: light_side's convention.
        let side = light_side(v, light);
        let corners_clear = nlen > 0.0
            && near.iter().all(|&x| {
                let h = -n.dot(x - a);
                let margin = 1e-9 * nlen * (x - a).length();
                if side == 0 {
                    h.abs() > margin
                } else {
                    h * f64::from(side) > margin
                }
            });
        corners_clear || {
            let t = [a, v[1].as_dvec3(), v[2].as_dvec3()];
            points_outside(&t, planes)
                || hull
                    .as_ref()
                    .is_some_and(|h| triangle_misses_near_clip(t, h))
        }
    })
}

/// The near-clip volume of one light as the separating-axis test needs it: its apex (a point,
/// or for a directional light the direction the rectangle is swept along), its edges and face
/// normals, and the largest coordinate. Built once per light and object, not per triangle.
pub(super) struct NearClipHull {
    apex: DVec3,
    directional: bool,
    near: [DVec3; 4],
    edges: Vec<DVec3>,
    face_axes: Vec<DVec3>,
    scale: f64,
}

impl NearClipHull {
    /// `None` when the light's point is not finite (then nothing is proven separate).
    pub(super) fn new(light: [f32; 4], near: [DVec3; 4]) -> Option<Self> {
        let w = f64::from(light[3]);
        let lxyz = DVec3::new(light[0].into(), light[1].into(), light[2].into());
        let (apex, directional) = if w == 0.0 {
            (lxyz, true)
        } else {
            (lxyz / w, false)
        };
        if !apex.is_finite() {
            return None;
        }
        let scale = near
            .iter()
            .fold(0.0f64, |m, p| m.max(p.abs().max_element()))
            .max(if directional {
                0.0
            } else {
                apex.abs().max_element()
            });
        let mut edges = Vec::with_capacity(8);
        let mut face_axes = Vec::with_capacity(5);
        for i in 0..4 {
            let (x, y) = (near[i], near[(i + 1) % 4]);
            let to_apex = if directional { apex } else { apex - x };
            edges.push(y - x);
            if !directional {
                edges.push(to_apex);
            }
            face_axes.push((y - x).cross(to_apex));
        }
        if directional {
            edges.push(apex);
        }
        face_axes.push((near[1] - near[0]).cross(near[3] - near[0]));
        Some(Self {
            apex,
            directional,
            near,
            edges,
            face_axes,
            scale,
        })
    }
}

/// Separating-axis test between the triangle `t` and the near-clip volume `hull` (the pyramid
/// from the light over the near rectangle, or for a directional light the rectangle swept
/// towards it): true when some axis among the volume's face normals, the triangle's normal and
/// the cross products of their edges has the two strictly apart, with a margin of `10⁻⁹`
/// relative to the coordinates. Complete for convex polyhedra, so it also separates a triangle
/// that passes a hair beside the light, which no single face plane does.
pub(super) fn triangle_misses_near_clip(t: [DVec3; 3], hull: &NearClipHull) -> bool {
    let scale = t
        .iter()
        .fold(hull.scale, |m, p| m.max(p.abs().max_element()))
        .max(1e-30);
    let tri_edges = [t[1] - t[0], t[2] - t[1], t[0] - t[2]];
    let separates = |u: DVec3| {
        let ulen = u.length();
        if !(ulen > 0.0 && ulen.is_finite()) {
            return false;
        }
        let margin = 1e-9 * ulen * scale;
        let (tlo, thi) = t
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                let d = u.dot(*p);
                (lo.min(d), hi.max(d))
            });
        let (mut vlo, mut vhi) =
            hull.near
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    let d = u.dot(*p);
                    (lo.min(d), hi.max(d))
                });
        let d = u.dot(hull.apex);
        if hull.directional {
            if d > 0.0 {
                vhi = f64::INFINITY;
            } else if d < 0.0 {
                vlo = f64::NEG_INFINITY;
            }
        } else {
            vlo = vlo.min(d);
            vhi = vhi.max(d);
        }
        thi < vlo - margin || vhi < tlo - margin
    };
    hull.face_axes.iter().any(|&u| separates(u))
        || separates(tri_edges[0].cross(tri_edges[1]))
        || tri_edges
            .iter()
            .any(|&e| hull.edges.iter().any(|&f| separates(e.cross(f))))
}

/// The margin a point must clear a plane by to count as outside: `10⁻⁶` of the larger of the
/// box `lo..hi`'s diagonal and its coordinates' magnitude (at least `10⁻³⁶`), so it scales with
/// both the extent and the rounding error of coordinates far from the origin.
pub(super) fn relative_margin(lo: DVec3, hi: DVec3) -> f64 {
    (hi - lo)
        .length()
        .max(lo.abs().max_element())
        .max(hi.abs().max_element())
        .max(1e-30)
        * 1e-6
}

/// True when some inward plane has every point strictly outside it, with a margin of `10⁻⁶`
/// relative to the points' extent and magnitude.
pub(super) fn points_outside(points: &[DVec3], planes: &[Plane]) -> bool {
    let (lo, hi) = points
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let margin = relative_margin(lo, hi);
    planes
        .iter()
        .any(|&pl| points.iter().all(|&c| eval(pl, c) < -margin))
}

/// True when the box `(lo, hi)` provably does not meet the convex volume given by its inward
/// `planes` (some plane has all 8 corners strictly outside, with a relative margin).
#[must_use]
pub fn box_outside(lo: DVec3, hi: DVec3, planes: &[Plane]) -> bool {
    points_outside(&box_corners(lo, hi), planes)
}

#[cfg(test)]
mod light_side_tests {
    use super::light_side;
    use glam::Vec3;

    #[test]
    fn the_side_follows_the_normal_and_is_zero_in_the_plane() {
        // n = (b − a) × (c − a) = +z: H is negative above the plane, positive below.
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        assert_eq!(light_side(t, [0.2, 0.3, 5.0, 1.0]), -1);
        assert_eq!(light_side(t, [0.2, 0.3, -5.0, 1.0]), 1);
        assert_eq!(light_side(t, [7.0, -3.0, 0.0, 1.0]), 0);
        // A directional light towards +z, and one along the plane.
        assert_eq!(light_side(t, [0.0, 0.0, 1.0, 0.0]), -1);
        assert_eq!(light_side(t, [1.0, 1.0, 0.0, 0.0]), 0);
        // An odd permutation of the vertices flips the side; a hair above the plane still counts.
        assert_eq!(light_side([t[1], t[0], t[2]], [0.2, 0.3, 5.0, 1.0]), 1);
        assert_eq!(light_side(t, [0.2, 0.3, f32::MIN_POSITIVE, 1.0]), -1);
    }
}
