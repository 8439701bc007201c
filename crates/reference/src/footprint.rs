//! The footprint rule: whether a shadow boundary of a light crosses a pixel's footprint.
//!
//! A pixel's *footprint* is its square (`[x, x + 1] × [y, y + 1]` in pixels) seen through the
//! camera on the plane of the triangle under its centre: the plane `P` of that triangle cut by
//! the four planes through the eye and the pixel's edges, a convex quadrilateral. A shadow
//! boundary of a light *crosses* the footprint when the footprint holds both a region of
//! positive area that some caster shadows and a region of positive area that no caster shadows.
//!
//! Caster `T = (a, b, c)` shadows the point `x` when `x` and the light lie strictly on opposite
//! sides of `T`'s plane and the line through them meets the closed triangle (what
//! [`crate::occlusion`] decides per surface point). On `P` that set is the footprint cut by four
//! half-spaces: the three planes through the light and an edge of `T` (the bounding planes of
//! `T`'s shadow wedge) and `T`'s own plane. So every question here is the sign of a linear form
//! at a vertex of a polygon whose edges are such planes on `P`, that is the sign of a 4×4
//! determinant of plane coefficients (over a 3×3 one), decided exactly in big integers:
//! * the camera's planes from the `f64` view-projection matrix the surface points come from
//!   (its entries taken as exact), the pixel's edges at `2X / W − 1` (scaled by `W`);
//! * `P`, `T`'s plane and the wedge planes from the `f32` vertices and the `f32` homogeneous
//!   light, as the 3×3 cofactors of their rows; which side of `T`'s plane the light is on is
//!   [`crate::occlusion::light_side`] (`shadowvol-robust-math`'s exact predicate).
//!
//! The shadowed region is found caster by caster; the unshadowed region is the footprint minus
//! each shadow in turn, kept as convex pieces. A caster is a candidate when its BVH box meets the
//! convex hull of the light and the footprint (the footprint enlarged by 1/16 for the rounding
//! of its `f64` corners); an `f64` filter with a margin of `2⁻³⁰` of its terms sets aside the
//! candidates whose shadow clearly misses the footprint, and answers at once (no boundary) when
//! one clearly covers it; for a caster wholly between the light and the plane, the same filter
//! runs on the plane, against the triangle of its vertices' projections. Only where more than
//! 24 casters stay near one footprint, or the pieces would pass 64, does the rule give up and
//! answer "no boundary": it may leave a pixel an artifact, it never moves one without an exact
//! proof that shadow and light both lie inside its footprint.

use crate::occlusion::scaled_ints;
use crate::states::{Casters, SurfacePoint};
use crate::Shot;
use glam::{DMat4, DVec3, DVec4, Vec3};
use num_bigint::{BigInt, Sign};

/// Integer plane coefficients `π`: the point `x` is on the positive side when `π · (x, 1) > 0`.
/// Any positive multiple is the same plane.
type Plane = [BigInt; 4];

/// Relative margin of the `f64` filter (`2⁻³⁰`), far above the rounding of its terms.
const MARGIN: f64 = 1.0 / 1_073_741_824.0;
/// How much the footprint is enlarged (about its centroid) to gather candidate casters.
const EXPAND: f64 = 1.0 / 16.0;
/// The most convex pieces the unshadowed region may be kept in; beyond, the rule gives up.
const MAX_PIECES: usize = 64;
/// The most casters the exact test takes on one footprint; beyond, the rule gives up.
const MAX_NEAR: usize = 24;

/// What the rule reads of a shot, built once per comparison.
pub(crate) struct Footprints<'s, 'a> {
    shot: &'s Shot<'a>,
    casters: &'s Casters,
    w: usize,
    h: usize,
    inv: DMat4,
    eye: DVec3,
    /// Rows 0 (clip x), 1 (clip y) and 3 (clip w) of the view-projection matrix, as integers
    /// (the whole matrix scaled by one power of two).
    clip: [[BigInt; 4]; 3],
}

/// How a caster's shadow lies on a footprint, by the `f64` filter.
enum Filtered {
    Misses,
    Covers,
    Near,
}

impl<'s, 'a> Footprints<'s, 'a> {
    pub(crate) fn new(shot: &'s Shot<'a>, casters: &'s Casters) -> Self {
        let aspect = f64::from(shot.width) / f64::from(shot.height);
        let m = shot.camera.view_proj_f64(aspect);
        let rows = [m.row(0), m.row(1), m.row(3)].map(|r| r.to_array());
        let flat: Vec<f64> = rows.iter().flatten().copied().collect();
        let ints = scaled_ints(&flat);
        let row = |r: usize| -> [BigInt; 4] { std::array::from_fn(|c| ints[4 * r + c].clone()) };
        Self {
            shot,
            casters,
            w: shot.width as usize,
            h: shot.height as usize,
            inv: m.inverse(),
            eye: shot.camera.eye.as_dvec3(),
            clip: [row(0), row(1), row(2)],
        }
    }

    /// True when a shadow boundary of light `li` crosses pixel `i`'s footprint (see the module
    /// documentation); `sp` is the pixel's surface point.
    pub(crate) fn crosses(&self, i: usize, sp: &SurfacePoint, li: usize) -> bool {
        let [obj, tri] = self.shot.ids[i];
        if obj == 0 {
            return false;
        }
        let Some(own) = self.shot.triangle(obj as usize - 1, tri as usize) else {
            return false;
        };
        let (x, y) = (i % self.w, i / self.w);
        let Some(corners) = self.corners(own, x, y) else {
            return false;
        };
        let l = self.shot.light(li);
        let sides = &self.casters.sides[li];
        let hull = Hull::new(corners, l, own);
        let mut near = Vec::new();
        let mut covered = false;
        self.casters.bvh.visit_boxes(
            |lo, hi| hull.may_meet(lo, hi),
            |k| {
                if self.casters.ids[k] == sp.triangle || sides[k] == 0 {
                    return false;
                }
                let t = self.casters.raw[k];
                let f = match filter(t, l, sides[k], &corners, self.eye) {
                    Filtered::Near => projected(t, l, &corners, own, self.eye),
                    f => f,
                };
                match f {
                    Filtered::Misses => false,
                    Filtered::Covers => {
                        covered = true;
                        true
                    }
                    Filtered::Near => {
                        near.push(k);
                        false
                    }
                }
            },
        );
        if covered || near.is_empty() || near.len() > MAX_NEAR {
            // One caster shadows the whole footprint, none comes near it, or too many do for
            // the exact test's cost (the pixel stays an artifact).
            return false;
        }
        self.exact(own, x, y, l, &near, sides)
    }

    /// The footprint's corners in `f64` (left-bottom, right-bottom, right-top, left-top), `None`
    /// when a corner ray does not meet the plane in front of the eye.
    fn corners(&self, own: [Vec3; 3], x: usize, y: usize) -> Option<[DVec3; 4]> {
        let t = own.map(Vec3::as_dvec3);
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        let mut out = [DVec3::ZERO; 4];
        for (k, (cx, cy)) in [(x, y + 1), (x + 1, y + 1), (x + 1, y), (x, y)]
            .into_iter()
            .enumerate()
        {
            let ndc = DVec4::new(
                cx as f64 / self.w as f64 * 2.0 - 1.0,
                1.0 - cy as f64 / self.h as f64 * 2.0,
                0.5,
                1.0,
            );
            let p = self.inv * ndc;
            let dir = p.truncate() / p.w - self.eye;
            let denom = n.dot(dir);
            let s = n.dot(t[0] - self.eye) / denom;
            if !(s.is_finite() && s > 0.0) {
                return None;
            }
            out[k] = self.eye + dir * s;
        }
        Some(out)
    }

    /// The exact decision over the casters the filter left near the footprint.
    fn exact(
        &self,
        own: [Vec3; 3],
        x: usize,
        y: usize,
        l: [f32; 4],
        near: &[usize],
        sides: &[i8],
    ) -> bool {
        let mut arena = Arena {
            planes: vec![point_plane(own)],
        };
        let Some(q) = self.footprint(&mut arena, x, y) else {
            return false;
        };
        let lh = l.map(f64::from);
        let shadows: Vec<[usize; 4]> = near
            .iter()
            .map(|&k| {
                let [a, b, c] = self.casters.raw[k].map(homogeneous);
                let s = sides[k];
                let mut oriented = |p: Plane| {
                    let p = if s > 0 { p.map(|v| -v) } else { p };
                    arena.push(p)
                };
                [
                    oriented(plane_through([lh, a, b])),
                    oriented(plane_through([lh, b, c])),
                    oriented(plane_through([lh, c, a])),
                    oriented(plane_through([a, b, c])),
                ]
            })
            .collect();
        let inside = |arena: &Arena, piece: &[usize], s: &[usize; 4]| {
            s.iter()
                .try_fold(piece.to_vec(), |p, &h| arena.clip(&p, h))
                .is_some()
        };
        if !shadows.iter().any(|s| inside(&arena, &q, s)) {
            return false;
        }
        // The unshadowed region: the footprint minus each shadow, in convex pieces.
        let mut pieces = vec![q];
        for s in &shadows {
            let mut next = Vec::new();
            for piece in pieces {
                if !inside(&arena, &piece, s) {
                    next.push(piece);
                    continue;
                }
                // piece \ S = ∪_k piece ∩ {h_0 ≥ 0, …, h_(k−1) ≥ 0, h_k < 0}.
                let mut rest = Some(piece);
                for &h in s {
                    let Some(cur) = rest else { break };
                    let neg = arena.negated(h);
                    if let Some(out) = arena.clip(&cur, neg) {
                        next.push(out);
                    }
                    rest = arena.clip(&cur, h);
                }
            }
            if next.is_empty() {
                return false;
            }
            if next.len() > MAX_PIECES {
                return false;
            }
            pieces = next;
        }
        true
    }

    /// The footprint as a polygon of camera planes on `P` (arena index 0): left, bottom, right,
    /// top; `None` unless all four corners lie strictly inside the other two planes (the
    /// footprint is a bounded quadrilateral in front of the eye).
    fn footprint(&self, arena: &mut Arena, x: usize, y: usize) -> Option<Vec<usize>> {
        let [r0, r1, r3] = &self.clip;
        let (w, h) = (BigInt::from(self.w), BigInt::from(self.h));
        let lin = |a: &BigInt, ra: &[BigInt; 4], b: &BigInt, rb: &[BigInt; 4]| -> Plane {
            std::array::from_fn(|c| a * &ra[c] + b * &rb[c])
        };
        let (x0, x1) = (BigInt::from(2 * x) - &w, BigInt::from(2 * x + 2) - &w);
        let (y0, y1) = (&h - BigInt::from(2 * y), &h - BigInt::from(2 * y + 2));
        let neg = |v: &BigInt| -v;
        let q = vec![
            // x_ndc ≥ (2x − W) / W: W·c.x − (2x − W)·c.w ≥ 0.
            arena.push(lin(&w, r0, &neg(&x0), r3)),
            // y_ndc ≥ (H − 2(y + 1)) / H.
            arena.push(lin(&h, r1, &neg(&y1), r3)),
            // x_ndc ≤ (2x + 2 − W) / W.
            arena.push(lin(&neg(&w), r0, &x1, r3)),
            // y_ndc ≤ (H − 2y) / H.
            arena.push(lin(&neg(&h), r1, &y0, r3)),
        ];
        for k in 0..4 {
            let (i, j) = (q[k], q[(k + 1) % 4]);
            for &other in &[q[(k + 2) % 4], q[(k + 3) % 4]] {
                if arena.vertex_sign(i, j, other) <= 0 {
                    return None;
                }
            }
        }
        Some(q)
    }
}

/// Planes of one pixel: `P` at index 0, then the footprint's and the casters' planes.
struct Arena {
    planes: Vec<Plane>,
}

impl Arena {
    fn push(&mut self, p: Plane) -> usize {
        self.planes.push(p);
        self.planes.len() - 1
    }

    fn negated(&mut self, h: usize) -> usize {
        let p = self.planes[h].clone().map(|v| -v);
        self.push(p)
    }

    /// The sign of plane `k` at the point where `P`, plane `i` and plane `j` meet: sgn det₄(P,
    /// i, j, k) · sgn det₃ of their normals (0 also when they do not meet in one point).
    fn vertex_sign(&self, i: usize, j: usize, k: usize) -> i8 {
        let p = &self.planes;
        let d3 = det3_sign(&p[0], &p[i], &p[j]);
        d3 * det4_sign(&p[0], &p[i], &p[j], &p[k])
    }

    /// The convex polygon `poly` (planes in cyclic order; vertex `m` is where planes `m` and
    /// `m + 1` meet on `P`) cut to the side where plane `k` is positive; `None` when that leaves
    /// no area.
    fn clip(&self, poly: &[usize], k: usize) -> Option<Vec<usize>> {
        let n = poly.len();
        let s: Vec<i8> = (0..n)
            .map(|m| self.vertex_sign(poly[m], poly[(m + 1) % n], k))
            .collect();
        if s.iter().all(|&v| v > 0) {
            return Some(poly.to_vec());
        }
        // The positive vertices are one run a..=b (convexity).
        let a = (0..n).find(|&m| s[m] > 0 && s[(m + n - 1) % n] <= 0)?;
        let mut b = a;
        while s[(b + 1) % n] > 0 {
            b = (b + 1) % n;
        }
        let mut out = Vec::with_capacity(n + 1);
        let mut m = a;
        loop {
            out.push(poly[m]);
            if m == (b + 1) % n {
                break;
            }
            m = (m + 1) % n;
        }
        out.push(k);
        Some(out)
    }
}

/// The convex hull of the light and the footprint (enlarged), as `f64` half-spaces
/// `n · (x − p) ≥ 0`, for the BVH's boxes.
struct Hull {
    planes: Vec<(DVec3, DVec3)>,
}

impl Hull {
    fn new(corners: [DVec3; 4], l: [f32; 4], own: [Vec3; 3]) -> Self {
        let g = corners.iter().copied().sum::<DVec3>() / 4.0;
        let c = corners.map(|c| g + (c - g) * (1.0 + EXPAND));
        let t = own.map(Vec3::as_dvec3);
        let mut np = (t[1] - t[0]).cross(t[2] - t[0]);
        let xyz = DVec3::new(f64::from(l[0]), f64::from(l[1]), f64::from(l[2]));
        let w = f64::from(l[3]);
        let mut planes = Vec::with_capacity(6);
        let mut orient = |n: DVec3, p: DVec3, inside: DVec3| {
            let n = if n.dot(inside - p) < 0.0 { -n } else { n };
            planes.push((n, p));
        };
        if w == 0.0 {
            if np.dot(xyz) < 0.0 {
                np = -np;
            }
            for k in 0..4 {
                orient((c[(k + 1) % 4] - c[k]).cross(xyz), c[k], g);
            }
            planes.push((np, g));
        } else {
            let lp = xyz / w;
            if np.dot(lp - g) < 0.0 {
                np = -np;
            }
            for k in 0..4 {
                orient((c[k] - lp).cross(c[(k + 1) % 4] - lp), lp, g);
            }
            planes.push((np, g));
            planes.push((-np, lp));
        }
        Self { planes }
    }

    /// False only when the box lies outside one of the planes by more than the margin.
    fn may_meet(&self, lo: DVec3, hi: DVec3) -> bool {
        let centre = (lo + hi) * 0.5;
        let half = (hi - lo) * 0.5;
        self.planes.iter().all(|&(n, p)| {
            let top = n.dot(centre - p) + n.abs().dot(half);
            let scale = n.abs().dot(centre.abs() + half + p.abs());
            top >= -MARGIN * scale
        })
    }
}

/// The `f64` filter: caster `t`'s shadow (`side` = [`crate::occlusion::light_side`]) against
/// the footprint's corners, each of its four half-spaces `N · (x − base) ≥ 0` evaluated with a
/// margin of [`MARGIN`] times the magnitude of its terms.
fn filter(t: [Vec3; 3], l: [f32; 4], side: i8, corners: &[DVec3; 4], eye: DVec3) -> Filtered {
    let [a, b, c] = t.map(Vec3::as_dvec3);
    let xyz = DVec3::new(f64::from(l[0]), f64::from(l[1]), f64::from(l[2]));
    let w = f64::from(l[3]);
    let s = f64::from(side);
    let edge = |p: DVec3, q: DVec3| -> (DVec3, DVec3, DVec3) {
        if w == 0.0 {
            let (u, v) = (xyz, q - p);
            (-s * u.cross(v), perm(u, v), p)
        } else {
            let lp = xyz / w;
            let (u, v) = (p - lp, q - lp);
            (s * u.cross(v), perm(u, v), lp)
        }
    };
    let far = {
        let (u, v) = (b - a, c - a);
        (s * u.cross(v), perm(u, v), a)
    };
    let eye = eye.abs();
    let mut all_inside = true;
    for (n, np, base) in [edge(a, b), edge(b, c), edge(c, a), far] {
        let mut all_out = true;
        for &x in corners {
            let v = n.dot(x - base);
            let margin = MARGIN * np.dot((x - base).abs() + x.abs() + eye);
            all_out &= v < -margin;
            all_inside &= v > margin;
        }
        if all_out {
            return Filtered::Misses;
        }
    }
    if all_inside {
        Filtered::Covers
    } else {
        Filtered::Near
    }
}

/// The `f64` filter on the footprint's plane, for a caster the half-spaces leave near it: when
/// all three vertices lie strictly between the light and the plane (of the pixel's triangle
/// `own`), the shadow there is the triangle of their projections from the light. An edge normal
/// of either polygon that separates them by the margin says it misses; every corner inside it
/// by the margin, that it covers the footprint. Otherwise (or when unsure) [`Filtered::Near`].
fn projected(
    t: [Vec3; 3],
    l: [f32; 4],
    corners: &[DVec3; 4],
    own: [Vec3; 3],
    eye: DVec3,
) -> Filtered {
    let o = own.map(Vec3::as_dvec3);
    let n = (o[1] - o[0]).cross(o[2] - o[0]);
    let g = corners.iter().copied().sum::<DVec3>() / 4.0;
    let xyz = DVec3::new(f64::from(l[0]), f64::from(l[1]), f64::from(l[2]));
    let w = f64::from(l[3]);
    let mut p = [DVec3::ZERO; 3];
    let mut stretch: f64 = 1.0;
    for (k, v) in t.iter().enumerate() {
        let v = v.as_dvec3();
        if w == 0.0 {
            // Along the direction away from the light, onto the plane.
            let u = n.dot(v - g) / n.dot(xyz);
            if !(u.is_finite() && u > 0.0) {
                return Filtered::Near;
            }
            p[k] = v - xyz * u;
        } else {
            let lp = xyz / w;
            let s = n.dot(g - lp) / n.dot(v - lp);
            if !(s.is_finite() && s > 1.0 + 1e-9) {
                return Filtered::Near;
            }
            stretch = stretch.max(s);
            p[k] = lp + (v - lp) * s;
        }
    }
    let scale = p
        .iter()
        .chain(corners)
        .map(|x| x.abs().max_element())
        .fold(eye.abs().max_element() + xyz.abs().max_element(), f64::max)
        * stretch;
    let margin = |axis: DVec3| MARGIN * axis.abs().element_sum() * scale;
    let axes = (0..3)
        .map(|k| n.cross(p[(k + 1) % 3] - p[k]))
        .chain((0..4).map(|k| n.cross(corners[(k + 1) % 4] - corners[k])));
    for axis in axes {
        let range = |pts: &mut dyn Iterator<Item = DVec3>| {
            pts.map(|x| axis.dot(x))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(v), hi.max(v))
                })
        };
        let (tlo, thi) = range(&mut p.iter().copied());
        let (qlo, qhi) = range(&mut corners.iter().copied());
        let m = margin(axis);
        if thi < qlo - m || qhi < tlo - m {
            return Filtered::Misses;
        }
    }
    // Each corner strictly inside every edge of the projected triangle (oriented inwards).
    let inward = (p[1] - p[0]).cross(p[2] - p[0]).dot(n).signum();
    let covers = (0..3).all(|k| {
        let axis = n.cross(p[(k + 1) % 3] - p[k]) * inward;
        let m = margin(axis);
        corners.iter().all(|&c| axis.dot(c - p[k]) > m)
    });
    if covers {
        Filtered::Covers
    } else {
        Filtered::Near
    }
}

/// Per component of `u × v`, the sum of the absolute values of its two products.
fn perm(u: DVec3, v: DVec3) -> DVec3 {
    DVec3::new(
        (u.y * v.z).abs() + (u.z * v.y).abs(),
        (u.z * v.x).abs() + (u.x * v.z).abs(),
        (u.x * v.y).abs() + (u.y * v.x).abs(),
    )
}

fn homogeneous(v: Vec3) -> [f64; 4] {
    [f64::from(v.x), f64::from(v.y), f64::from(v.z), 1.0]
}

/// The plane through the triangle's three points.
fn point_plane(t: [Vec3; 3]) -> Plane {
    plane_through(t.map(homogeneous))
}

/// The plane through three homogeneous points (finite `f64` rows), with `π · X = det₄(X₁; X₂;
/// X₃; X)`: each row is scaled to integers on its own (a positive factor), then `π` is the
/// cofactors of the last row.
fn plane_through(rows: [[f64; 4]; 3]) -> Plane {
    let r: Vec<Vec<BigInt>> = rows.iter().map(|row| scaled_ints(row)).collect();
    std::array::from_fn(|c| {
        let cols: Vec<usize> = (0..4).filter(|&k| k != c).collect();
        let m = |i: usize, j: usize| &r[i][cols[j]];
        let d = m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1))
            - m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0))
            + m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0));
        // Cofactor sign of (row 3, column c).
        if (3 + c) % 2 == 0 {
            d
        } else {
            -d
        }
    })
}

fn sign(x: &BigInt) -> i8 {
    match x.sign() {
        Sign::Plus => 1,
        Sign::Minus => -1,
        Sign::NoSign => 0,
    }
}

/// Sign of the 3×3 determinant of the planes' normals (their first three coefficients).
fn det3_sign(a: &Plane, b: &Plane, c: &Plane) -> i8 {
    let d = &a[0] * (&b[1] * &c[2] - &b[2] * &c[1]) - &a[1] * (&b[0] * &c[2] - &b[2] * &c[0])
        + &a[2] * (&b[0] * &c[1] - &b[1] * &c[0]);
    sign(&d)
}

/// Sign of the 4×4 determinant of the rows, by the 2×2 minors of rows {0, 1} and {2, 3}.
fn det4_sign(r0: &Plane, r1: &Plane, r2: &Plane, r3: &Plane) -> i8 {
    let lo = |i: usize, j: usize| &r0[i] * &r1[j] - &r0[j] * &r1[i];
    let hi = |i: usize, j: usize| &r2[i] * &r3[j] - &r2[j] * &r3[i];
    let d = lo(0, 1) * hi(2, 3) - lo(0, 2) * hi(1, 3) + lo(0, 3) * hi(1, 2) + lo(1, 2) * hi(0, 3)
        - lo(1, 3) * hi(0, 2)
        + lo(2, 3) * hi(0, 1);
    sign(&d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::occlusion::light_side;

    fn dot(p: &Plane, x: [f64; 4]) -> i8 {
        let xs = scaled_ints(&x);
        sign(&(0..4).map(|c| &p[c] * &xs[c]).sum::<BigInt>())
    }

    /// `plane_through` passes through its three points, and its sign at a fourth is det₄ of the
    /// rows; with the light, the caster's plane's sign at the light is `light_side`.
    #[test]
    fn planes_are_the_cofactors() {
        let t = [
            Vec3::new(0.5, 0.0, 1.0),
            Vec3::new(2.0, 0.25, 1.5),
            Vec3::new(0.0, 3.0, 0.75),
        ];
        for l in [
            [1.0f32, 2.0, 5.0, 1.0],
            [0.3, -1.0, 2.0, 0.0],
            [4.0, 2.0, 6.0, 2.0],
        ] {
            let p = point_plane(t);
            for v in t {
                assert_eq!(dot(&p, homogeneous(v)), 0);
            }
            assert_eq!(dot(&p, l.map(f64::from)), light_side(t, l), "{l:?}");
            let lh = l.map(f64::from);
            let [a, b, c] = t.map(homogeneous);
            let e = plane_through([lh, a, b]);
            assert_eq!(dot(&e, lh), 0);
            assert_eq!(dot(&e, a), 0);
            assert_eq!(dot(&e, b), 0);
            // The shadow wedge is on c's side of each of its planes after orienting by -side.
            assert_eq!(dot(&e, c), -light_side(t, l));
        }
    }

    /// `det4_sign` agrees with `f64` away from 0 and changes sign under a row swap.
    #[test]
    fn det4_matches_f64() {
        let rows = [
            [1.0, 2.0, 3.0, 1.0],
            [-2.0, 0.5, 4.0, 1.0],
            [0.25, -3.0, 1.0, 1.0],
            [5.0, 1.0, -1.0, 1.0],
        ];
        let f = DMat4::from_cols_array_2d(&rows).determinant();
        let p: Vec<Plane> = rows
            .iter()
            .map(|r| {
                let v = scaled_ints(r);
                std::array::from_fn(|c| v[c].clone())
            })
            .collect();
        let s = if f > 0.0 { 1 } else { -1 };
        assert_eq!(det4_sign(&p[0], &p[1], &p[2], &p[3]), s);
        assert_eq!(det4_sign(&p[1], &p[0], &p[2], &p[3]), -s);
    }
}
