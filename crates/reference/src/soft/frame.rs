//! The frame: disk coordinates, the pyramid, the projection and the clipping.

use super::integrate::{push_polygon, Edge};
use super::{EDGE_ON, SQUARE, U};
use glam::DVec3;
use shadowvol_scenes::LightDisk;

/// A projected point's homogeneous coordinates `(A, B, W)`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Hv {
    h: [f64; 3],
    /// For a caster's vertex, a bound on each coordinate's error (0 for clip points).
    e: f64,
    /// The clip planes the point was made on (bit `k`: the `k`-th of [`Frame::project`]).
    on: u8,
    /// The line of the polygon's edge that leaves this point: `k < 3` the triangle's edge
    /// from vertex `k`, [`CLIP_LINE`]` + j` the `j`-th clip plane.
    line: u8,
}

impl Hv {
    fn key(&self) -> [u64; 3] {
        self.h.map(f64::to_bits)
    }
}

/// A line `l · (a, b, 1) = 0` in disk coordinates with a bound on each coefficient's error.
#[derive(Debug, Clone, Copy)]
pub(super) struct HLine {
    l: [f64; 3],
    err: f64,
}

impl HLine {
    /// The line through two projected points (their homogeneous cross product; exactly the
    /// negative for the points swapped, so both copies of a shared edge get the same bound).
    fn through(p: &Hv, q: &Hv) -> Self {
        let (a, b) = (p.h, q.h);
        let l = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let (ma, mb) = (
            a.iter().fold(0.0f64, |m, x| m.max(x.abs())),
            b.iter().fold(0.0f64, |m, x| m.max(x.abs())),
        );
        Self {
            l,
            err: 2.0 * (ma * q.e + mb * p.e + q.e * p.e) + 4.0 * U * ma * mb,
        }
    }

    /// A bound on the distance of `p` from the exact line (∞ when the line's direction is not
    /// known to within its error).
    pub(super) fn dist(&self, p: Pt) -> f64 {
        let [la, lb, lw] = self.l;
        let num = (la * p.x + lb * p.y + lw).abs();
        let err = self.err * (p.x.abs() + p.y.abs() + 1.0)
            + 4.0 * U * ((la * p.x).abs() + (lb * p.y).abs() + lw.abs());
        let den = (la * la + lb * lb).sqrt() * (1.0 - 4.0 * U) - 1.5 * self.err;
        if den > 0.0 {
            (num + err) / den
        } else {
            f64::INFINITY
        }
    }
}

/// A point in the disk's coordinates with a bound on its distance from the exact one.
#[derive(Debug, Clone, Copy)]
pub(super) struct Pt {
    pub(super) x: f64,
    pub(super) y: f64,
    d: f64,
}

impl Pt {
    pub(super) fn key(&self) -> [u64; 2] {
        [self.x.to_bits(), self.y.to_bits()]
    }
}

/// One clip half-plane `f ≥ 0` in homogeneous coordinates: `f = c₀ A + c₁ B + c₂ W + c₃`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Form([f64; 4]);

impl Form {
    fn eval(&self, p: &Hv) -> f64 {
        let c = self.0;
        c[0] * p.h[0] + c[1] * p.h[1] + c[2] * p.h[2] + c[3]
    }
}

#[derive(Debug, Clone)]
pub(super) struct Frame {
    p: DVec3,
    /// The disk's centre (a directional light's unit direction).
    centre: DVec3,
    u: DVec3,
    v: DVec3,
    /// From `P` towards the disk's plane (point light), or the unit direction (directional).
    t: DVec3,
    /// `h` (point light) or 1 (directional).
    alpha: f64,
    pu: f64,
    pv: f64,
    /// `h` for a point light, `∞` for a directional one.
    far: f64,
    pub(super) r: f64,
    rr: f64,
    /// `sgn det(u, v, t)`.
    handed: f64,
    /// Error of every projected point due to the frame's own rounding.
    frame_err: f64,
    /// The pyramid's side planes through `P` (inward normals) and, for a point light, its box.
    sides: [DVec3; 4],
    hull: Option<(DVec3, DVec3)>,
    edge_on: Option<EdgeOn>,
}

/// The in-plane model of an edge-on disk.
#[derive(Debug, Clone, Copy)]
pub(super) struct EdgeOn {
    /// The disk's centre and normal.
    c: DVec3,
    n: DVec3,
    /// `P`'s foot in disk coordinates.
    apex: [f64; 2],
    /// The distance from `P` to the plane.
    h: f64,
    /// Far distance for the wedges (beyond the square seen from the apex).
    reach: f64,
}

impl Frame {
    /// `None` for a disk that is not finite.
    pub(super) fn new(disk: &LightDisk, p: DVec3) -> Option<Self> {
        let (u, v) = (disk.u, disk.v);
        let r = disk.radius;
        if !(r > 0.0 && r.is_finite() && disk.centre.is_finite() && p.is_finite()) {
            return None;
        }
        let rr = r * SQUARE;
        let mut edge_on = None;
        let (t, alpha, pu, pv, far, frame_err) = if disk.directional {
            let t = disk.centre;
            (
                t,
                1.0,
                0.0,
                0.0,
                f64::INFINITY,
                16.0 * U * (1.0 + rr) * (1.0 + rr),
            )
        } else {
            let cp = disk.centre - p;
            let h = cp.dot(disk.normal);
            let t = if h >= 0.0 { disk.normal } else { -disk.normal };
            let (pu, pv) = (-cp.dot(u), -cp.dot(v));
            let dist = cp.length();
            if h.abs() <= EDGE_ON * dist {
                let apex = [pu, pv];
                let reach = 4.0 * (pu.abs() + pv.abs() + 2.0 * rr);
                edge_on = Some(EdgeOn {
                    c: disk.centre,
                    n: disk.normal,
                    apex,
                    h: h.abs() + 4.0 * U * dist,
                    reach,
                });
                (t, 0.0, pu, pv, 0.0, 16.0 * U * (dist + rr))
            } else {
                let h = h.abs();
                let m = pu.abs() + pv.abs() + rr;
                // The frame's rounding moves every projection by about u |C − P| (1 + m / h).
                (t, h, pu, pv, h, 16.0 * U * (dist + rr) * (1.0 + m / h))
            }
        };
        let handed = if u.cross(v).dot(t) >= 0.0 { 1.0 } else { -1.0 };
        let corner = |a: f64, b: f64| {
            if disk.directional {
                disk.centre + a * u + b * v
            } else {
                disk.centre + a * u + b * v - p
            }
        };
        let d = [
            corner(rr, rr),
            corner(-rr, rr),
            corner(-rr, -rr),
            corner(rr, -rr),
        ];
        let mut sides = [DVec3::ZERO; 4];
        for k in 0..4 {
            let mut n = d[k].cross(d[(k + 1) % 4]);
            if n.dot(d[(k + 2) % 4]) < 0.0 {
                n = -n;
            }
            sides[k] = n;
        }
        let hull = (!disk.directional).then(|| {
            let (mut lo, mut hi) = (p, p);
            for dk in d {
                lo = lo.min(p + dk);
                hi = hi.max(p + dk);
            }
            let pad = (hi - lo).max_element() * 1e-9 + lo.abs().max(hi.abs()).max_element() * 1e-12;
            (lo - DVec3::splat(pad), hi + DVec3::splat(pad))
        });
        Some(Self {
            p,
            centre: disk.centre,
            u,
            v,
            t,
            alpha,
            pu,
            pv,
            far,
            r,
            rr,
            handed,
            frame_err,
            sides,
            hull,
            edge_on,
        })
    }

    /// Whether the box `[lo, hi]` may meet the pyramid (conservative).
    pub(super) fn box_may_meet(&self, lo: DVec3, hi: DVec3) -> bool {
        if let Some((hlo, hhi)) = self.hull {
            if lo.cmpgt(hhi).any() || hi.cmplt(hlo).any() {
                return false;
            }
        }
        let (a, b) = (lo - self.p, hi - self.p);
        let scale = a.abs().max(b.abs()).max_element();
        if self.edge_on.is_some() {
            // A flat pyramid: the hull's box already says it.
            return true;
        }
        let max_along = |n: DVec3| (0..3).map(|k| (n[k] * a[k]).max(n[k] * b[k])).sum::<f64>();
        for n in self.sides {
            let margin = 1e-12 * n.abs().element_sum() * scale + f64::MIN_POSITIVE;
            if max_along(n) < -margin {
                return false;
            }
        }
        let margin = 1e-12 * scale + f64::MIN_POSITIVE;
        if max_along(self.t) < -margin {
            return false;
        }
        if self.far.is_finite() && -max_along(-self.t) > self.far + margin {
            return false;
        }
        true
    }

    fn homog(&self, x: DVec3) -> Hv {
        let r = x - self.p;
        let (ru, rv, rt) = (r.dot(self.u), r.dot(self.v), r.dot(self.t));
        let a = self.alpha * ru + self.pu * rt;
        let b = self.alpha * rv + self.pv * rt;
        let s = r.abs().element_sum();
        let e = 8.0 * U * (self.alpha + self.pu.abs().max(self.pv.abs()) + 1.0) * s;
        Hv {
            h: [a, b, rt],
            e,
            on: 0,
            line: 0,
        }
    }

    /// Projects caster `tri`, clipped to the pyramid, and appends its counter-clockwise edges.
    /// False when a projected point's error could not be bounded (the result's bound is then
    /// set to 1).
    pub(super) fn project(&self, tri: [DVec3; 3], contact: f64, out: &mut Vec<Edge>) -> bool {
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        let sp = n.dot(self.p - tri[0]);
        if sp.abs() <= contact * n.length() {
            // Touching (or degenerate): a segment that starts on a plane cannot cross it.
            return true;
        }
        if let Some(eo) = self.edge_on {
            return self.project_edge_on(&eo, tri, n, out);
        }
        // sgn det(V0 − P, V1 − P, V2 − P) = −sgn sP; with the frame's handedness, the sign of
        // the projected triangle's orientation.
        let o = robust::orient3d(coord(tri[0]), coord(tri[1]), coord(tri[2]), coord(self.p));
        if o == 0.0 {
            return true;
        }
        let ccw = (o > 0.0) == (self.handed > 0.0);
        let n_t = n;
        let rr = self.rr;
        // The pyramid's planes (f ≥ 0 inside): a ≤ R′, a ≥ −R′, b ≤ R′, b ≥ −R′, and for a
        // point light W ≤ h (not beyond the light's plane).
        let forms = [
            Form([-1.0, 0.0, rr, 0.0]),
            Form([1.0, 0.0, rr, 0.0]),
            Form([0.0, -1.0, rr, 0.0]),
            Form([0.0, 1.0, rr, 0.0]),
            Form([0.0, 0.0, -1.0, self.far]),
        ];
        let planes = if self.far.is_finite() { 5 } else { 4 };
        let verts = tri.map(|x| self.homog(x));
        let mut all_inside = true;
        for f in &forms[..planes] {
            let vals = verts.map(|v| f.eval(&v));
            if vals.iter().all(|&x| x < 0.0) {
                return true;
            }
            all_inside &= vals.iter().all(|&x| x >= 0.0);
        }
        let mut poly = Poly::new(&verts);
        if !all_inside {
            for (k, f) in forms[..planes].iter().enumerate() {
                poly.clip(f, k as u8);
                if poly.n < 3 {
                    return true;
                }
            }
        }
        let n = poly.n;
        let mut pts = [Pt {
            x: 0.0,
            y: 0.0,
            d: 0.0,
        }; MAX_POLY];
        for (k, q) in poly.v[..n].iter().enumerate() {
            let [a, b, w] = q.h;
            if !(w > 0.0 && w.is_finite()) {
                return false;
            }
            pts[k] = Pt {
                x: a / w + 0.0,
                y: b / w + 0.0,
                d: 0.0,
            };
        }
        // Each edge's line, to measure its ends' distance from the exact line a posteriori
        // (for the edges left after cancellation).
        let side = |l: [f64; 3]| HLine { l, err: 0.0 };
        let edge_lines = [0, 1, 2].map(|k| HLine::through(&verts[k], &verts[(k + 1) % 3]));
        let mut lines = [None; MAX_POLY];
        for (line, v) in lines.iter_mut().zip(&poly.v[..n]) {
            *line = Some(if v.line < 3 {
                edge_lines[v.line as usize]
            } else {
                match v.line - CLIP_LINE {
                    0 => side([1.0, 0.0, -rr]),
                    1 => side([1.0, 0.0, rr]),
                    2 => side([0.0, 1.0, -rr]),
                    3 => side([0.0, 1.0, rr]),
                    _ => self.trace(&tri, n_t),
                }
            });
        }
        // Edges along the square's right, left and top sides lie outside the disk, and counting
        // w from below never meets them: left out. The bottom side's are counted.
        let keep: [bool; MAX_POLY] = std::array::from_fn(|i| {
            i < n && poly.v[i].on & poly.v[(i + 1) % n].on & SIDES_NOT_COUNTED == 0
        });
        push_polygon(
            &pts[..n],
            &keep[..n],
            &lines[..n],
            &[self.frame_err; MAX_POLY][..n],
            ccw,
            out,
        );
        true
    }

    /// The line where the caster's plane meets the disk's plane, in disk coordinates.
    fn trace(&self, tri: &[DVec3; 3], n: DVec3) -> HLine {
        // Disk points are `centre + a u + b v`.
        let off = self.centre - tri[0];
        let l = [n.dot(self.u), n.dot(self.v), n.dot(off)];
        let mag = n.abs().element_sum() * (1.0 + off.abs().element_sum());
        HLine {
            l,
            err: 16.0 * U * mag,
        }
    }

    /// The edge-on model: the caster's section by the disk's plane, seen from `P`'s foot.
    fn project_edge_on(&self, eo: &EdgeOn, tri: [DVec3; 3], n: DVec3, out: &mut Vec<Edge>) -> bool {
        let dist = tri.map(|x| (x - eo.c).dot(eo.n));
        if dist.iter().all(|&d| d > 0.0) || dist.iter().all(|&d| d < 0.0) {
            return true;
        }
        if dist.iter().all(|&d| d == 0.0) {
            // In the plane: as a light in a caster's plane, it never blocks.
            return true;
        }
        // The section's ends: vertices on the plane and crossings of edges whose ends lie
        // strictly on opposite sides, each a function of its vertex or edge alone.
        let mut ends: Vec<(Pt, f64)> = Vec::with_capacity(3);
        // 1 / sin of an edge's angle with the plane.
        let inv_sin = |x: DVec3, y: DVec3| {
            let d = y - x;
            d.length() / d.dot(eo.n).abs().max(f64::MIN_POSITIVE)
        };
        for k in 0..3 {
            let (i, j) = (k, (k + 1) % 3);
            if dist[i] == 0.0 {
                let x = tri[i];
                // A vertex on the plane: its steeper edge bounds the wedge's error.
                let s = inv_sin(x, tri[j]).min(inv_sin(x, tri[(k + 2) % 3]));
                ends.push((self.plane_point(eo, x, 4.0 * U * (x - eo.c).length()), s));
            }
            if (dist[i] > 0.0 && dist[j] < 0.0) || (dist[i] < 0.0 && dist[j] > 0.0) {
                let (x, y, dx, dy) = if key3(tri[i]) <= key3(tri[j]) {
                    (tri[i], tri[j], dist[i], dist[j])
                } else {
                    (tri[j], tri[i], dist[j], dist[i])
                };
                let tt = dx / (dx - dy);
                let q = x + tt * (y - x);
                let e = 8.0 * U * ((x - eo.c).length() + (y - x).length());
                ends.push((self.plane_point(eo, q, e), inv_sin(x, y)));
            }
        }
        if ends.len() < 2 {
            return true;
        }
        let (e1, s1) = ends[0];
        let (e2, s2) = ends[1];
        let [ax, ay] = eo.apex;
        let (d1, d2) = ([e1.x - ax, e1.y - ay], [e2.x - ax, e2.y - ay]);
        let cross = d1[0] * d2[1] - d1[1] * d2[0];
        if cross == 0.0 || (e1.x == e2.x && e1.y == e2.y) {
            return true;
        }
        // 1 / sin of the face's angle with the plane: how far its section moves per height.
        let face = n.length() / n.cross(eo.n).length().max(f64::MIN_POSITIVE);
        let far = |e: Pt, s: f64| {
            let (dx, dy) = (e.x - ax, e.y - ay);
            let len = dx.hypot(dy);
            // The wedge's side from the apex through e, moved by h / sin at e, turns by that
            // over len, which moves it by at most reach · that inside the square.
            let turn = eo.h * s.max(face) / len;
            let d = e.d + turn * eo.reach + 4.0 * U * eo.reach;
            // Beyond the square, and beyond e: a function of e alone, as a shared end needs.
            let reach = eo.reach.max(2.0 * len);
            let f = Pt {
                x: ax + reach * dx / len,
                y: ay + reach * dy / len,
                d,
            };
            (Pt { d, ..e }, f)
        };
        let (e1, f1) = far(e1, s1);
        let (e2, f2) = far(e2, s2);
        let mid = {
            let (l1, l2) = ((f1.x - ax).hypot(f1.y - ay), (f2.x - ax).hypot(f2.y - ay));
            let (mx, my) = (
                (f1.x - ax) / l1 + (f2.x - ax) / l2,
                (f1.y - ay) / l1 + (f2.y - ay) / l2,
            );
            let lm = mx.hypot(my);
            if lm == 0.0 {
                return true;
            }
            Pt {
                x: ax + l1.max(l2) * 2.0 * mx / lm,
                y: ay + l1.max(l2) * 2.0 * my / lm,
                d: f1.d.max(f2.d),
            }
        };
        let near = e1.d.max(e2.d) + eo.h * face;
        let (e1, e2) = (
            Pt {
                d: near.max(e1.d),
                ..e1
            },
            Pt {
                d: near.max(e2.d),
                ..e2
            },
        );
        // Counter-clockwise: e1, f1, mid, f2, e2 when the apex sees e1 before e2.
        let ring = if cross > 0.0 {
            [e1, f1, mid, f2, e2]
        } else {
            [e2, f2, mid, f1, e1]
        };
        let clipped = clip_square(&ring, self.rr);
        let n = clipped.len();
        if n >= 3 {
            let devs: Vec<f64> = (0..n)
                .map(|i| clipped[i].d.max(clipped[(i + 1) % n].d))
                .collect();
            push_polygon(&clipped, &vec![true; n], &vec![None; n], &devs, true, out);
        }
        true
    }

    /// A point of the disk's plane in the disk's coordinates.
    fn plane_point(&self, eo: &EdgeOn, x: DVec3, e: f64) -> Pt {
        let q = x - eo.c;
        Pt {
            x: q.dot(self.u) + 0.0,
            y: q.dot(self.v) + 0.0,
            d: e + 4.0 * U * q.length() + self.frame_err,
        }
    }
}

pub(super) fn coord(p: DVec3) -> robust::Coord3D<f64> {
    robust::Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

pub(super) fn key3(p: DVec3) -> [u64; 3] {
    p.to_array().map(f64::to_bits)
}

pub(super) const MAX_POLY: usize = 10;

/// The clip planes `a ≤ R′`, `a ≥ −R′` and `b ≤ R′` (bits of [`Hv::on`]).
pub(super) const SIDES_NOT_COUNTED: u8 = 0b0111;

/// [`Hv::line`] of the first clip plane.
pub(super) const CLIP_LINE: u8 = 8;

/// A convex polygon of at most [`MAX_POLY`] homogeneous points.
#[derive(Debug, Clone, Copy)]
pub(super) struct Poly {
    v: [Hv; MAX_POLY],
    n: usize,
}

impl Poly {
    fn new(tri: &[Hv; 3]) -> Self {
        let mut v = [tri[0]; MAX_POLY];
        v[..3].copy_from_slice(tri);
        for (k, p) in v[..3].iter_mut().enumerate() {
            p.line = k as u8;
        }
        Self { v, n: 3 }
    }

    /// Sutherland–Hodgman against `f ≥ 0` (clip plane number `plane`). A crossing point is
    /// computed from the two ends in the order of their bits, so the two triangles sharing an
    /// edge get the same bits.
    fn clip(&mut self, f: &Form, plane: u8) {
        let bit = 1 << plane;
        let src = self.v;
        let n = self.n;
        let mut vals = [0.0; MAX_POLY];
        for (val, p) in vals.iter_mut().zip(&src[..n]) {
            *val = f.eval(p);
        }
        self.n = 0;
        for i in 0..n {
            let j = (i + 1) % n;
            let (p, q, fp, fq) = (&src[i], &src[j], vals[i], vals[j]);
            if fp >= 0.0 && self.n < MAX_POLY {
                self.v[self.n] = *p;
                if fp == 0.0 {
                    self.v[self.n].on |= bit;
                    if fq < 0.0 {
                        // Leaving through a point on the plane: on along the clip line.
                        self.v[self.n].line = CLIP_LINE + plane;
                    }
                }
                self.n += 1;
            }
            if ((fp > 0.0 && fq < 0.0) || (fp < 0.0 && fq > 0.0)) && self.n < MAX_POLY {
                let mut c = cut(p, fp, q, fq);
                c.on = (p.on & q.on) | bit;
                // Leaving the half-plane the edge goes on along the clip line; entering, along
                // the cut edge's.
                c.line = if fp >= 0.0 { CLIP_LINE + plane } else { p.line };
                self.v[self.n] = c;
                self.n += 1;
            }
        }
    }
}

/// Where the segment `p q` crosses `f = 0` (`fp`, `fq` of strictly opposite signs), from the
/// ends in the order of their bits. Its error is not tracked: the edges through it are measured
/// on their lines afterwards.
pub(super) fn cut(p: &Hv, fp: f64, q: &Hv, fq: f64) -> Hv {
    let (x, fx, y, fy) = if p.key() <= q.key() {
        (p, fp, q, fq)
    } else {
        (q, fq, p, fp)
    };
    let tt = fx / (fx - fy);
    Hv {
        h: [0, 1, 2].map(|k| x.h[k] + tt * (y.h[k] - x.h[k])),
        e: 0.0,
        on: 0,
        line: 0,
    }
}

/// Clips a convex ring of disk points to the square `[−s, s]²` (crossings from the ends in the
/// order of their bits).
pub(super) fn clip_square(ring: &[Pt], s: f64) -> Vec<Pt> {
    let mut poly: Vec<Pt> = ring.to_vec();
    for (axis, sign) in [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0)] {
        if poly.len() < 3 {
            break;
        }
        let f = |p: &Pt| s - sign * if axis == 0 { p.x } else { p.y };
        let mut out = Vec::with_capacity(poly.len() + 1);
        for i in 0..poly.len() {
            let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
            let (fp, fq) = (f(&p), f(&q));
            if fp >= 0.0 {
                out.push(p);
            }
            if (fp > 0.0 && fq < 0.0) || (fp < 0.0 && fq > 0.0) {
                let (x, fx, y, fy) = if p.key() <= q.key() {
                    (p, fp, q, fq)
                } else {
                    (q, fq, p, fp)
                };
                let tt = fx / (fx - fy);
                let span = (y.x - x.x).abs().max((y.y - x.y).abs());
                out.push(Pt {
                    x: x.x + tt * (y.x - x.x) + 0.0,
                    y: x.y + tt * (y.y - x.y) + 0.0,
                    d: x.d.max(y.d) + 8.0 * U * (span + x.x.abs() + x.y.abs()),
                });
            }
        }
        poly = out;
    }
    poly
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every edge of a clipped polygon lies on the line it is labelled with (the triangle's
    /// edge, or the clip plane), also when a vertex lies exactly on a clip plane: the labels
    /// choose the line each edge's error is measured against.
    #[test]
    fn clipped_edges_lie_on_their_labelled_lines() {
        let rr = 1.0;
        let forms = [
            Form([-1.0, 0.0, rr, 0.0]),
            Form([1.0, 0.0, rr, 0.0]),
            Form([0.0, -1.0, rr, 0.0]),
            Form([0.0, 1.0, rr, 0.0]),
            Form([0.0, 0.0, -1.0, 3.0]),
        ];
        let hv = |a: f64, b: f64, w: f64| Hv {
            h: [a, b, w],
            e: 0.0,
            on: 0,
            line: 0,
        };
        // Small integers: many vertices exactly on a plane (A = ±W, B = ±W, W = 0 or 3).
        let mut rng = shadowvol_scenes::shapes::Rng::new(3);
        let mut int = || f64::from(rng.below(9) as u32) - 4.0;
        let mut on_plane = 0;
        for _ in 0..20_000 {
            let tri = [0, 1, 2].map(|_| hv(int(), int(), int().abs()));
            on_plane += usize::from(tri.iter().any(|v| forms.iter().any(|f| f.eval(v) == 0.0)));
            let mut poly = Poly::new(&tri);
            for (k, f) in forms.iter().enumerate() {
                poly.clip(f, k as u8);
                if poly.n < 3 {
                    break;
                }
            }
            if poly.n < 3 {
                continue;
            }
            for i in 0..poly.n {
                let (p, q) = (poly.v[i], poly.v[(i + 1) % poly.n]);
                let line = p.line;
                let off = |x: &Hv| {
                    if line < 3 {
                        let (a, b) = (tri[line as usize].h, tri[(line as usize + 1) % 3].h);
                        let n = [
                            a[1] * b[2] - a[2] * b[1],
                            a[2] * b[0] - a[0] * b[2],
                            a[0] * b[1] - a[1] * b[0],
                        ];
                        (n[0] * x.h[0] + n[1] * x.h[1] + n[2] * x.h[2]).abs()
                    } else {
                        forms[(line - CLIP_LINE) as usize].eval(x).abs()
                    }
                };
                assert!(
                    off(&p) < 1e-9 && off(&q) < 1e-9,
                    "{tri:?}: edge {i} of {:?} is not on line {line}",
                    &poly.v[..poly.n]
                );
            }
        }
        assert!(
            on_plane > 1000,
            "{on_plane} triangles touch a plane exactly"
        );
    }
}
