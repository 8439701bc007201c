//! The judge of soft shadows: the true share of a light's disk that a surface point sees.
//!
//! A light with a size ([`LightDisk`]) is a disk: for a point or spot light a disk in world
//! units, for a directional light its cone of directions, represented by the tangent-plane disk
//! of radius `tan θ` at unit distance along the direction (a direction is a point of that disk).
//! The **visibility** of a surface point `P` is the share of the disk's area (area measure in
//! the disk's plane) whose points `Y` it sees: the open segment from `P` to `Y` (for a
//! directional light, the open ray from `P` along `Y`) crosses no caster triangle. The casters
//! are the same `f32` world triangles the hard reference casts against ([`Shot::triangles`] of
//! the surfaces that [`Shot::casts_shadows`]), with the same conventions: the pixel's own
//! triangle never occludes, and a caster whose plane passes within the contact distance of `P`
//! ([`crate::occlusion::CONTACT`]) touches it and does not occlude. Facing is not part of it: a
//! disk partly behind the surface's own plane is hidden there only by casters (for a closed
//! caster, by its far side), as the hard reference separates occlusion from `cos θ`.
//!
//! # Method
//!
//! 1. **Gather.** The BVH ([`crate::Bvh`]) lists the casters whose boxes may meet the pyramid
//!    with apex `P` over the square `[−R′, R′]²` around the disk (`R′ = R (1 + 2⁻²⁰)`; for a
//!    directional light an infinite pyramid of directions). None: the visibility is exactly 1.
//! 2. **Project.** Every disk point `Y` the caster hides is the central projection from `P`
//!    onto the disk's plane of a caster point between `P` and that plane. Each vertex `X` is
//!    mapped linearly to homogeneous coordinates `(A, B, W)` with `r = X − P`: for a point light
//!    `W = r·t` (`t` the unit normal from `P` towards the plane, at distance `h`),
//!    `A = h r·u + p_u W`, `B = h r·v + p_v W` (`p_u`, `p_v` the disk coordinates of `P`'s foot),
//!    so that `a = A / W`, `b = B / W` are the disk coordinates of the projection; for a
//!    directional light `(A, B, W) = (r·u, r·v, r·d)` with `d` the unit direction. The triangle
//!    is clipped in these coordinates to the pyramid, `|A| ≤ R′ W`, `|B| ≤ R′ W` (which keeps
//!    `W > 0`: nothing behind `P`), and for a point light to `W ≤ h` (points beyond the light's
//!    plane do not occlude); no near plane is needed, since the pyramid closes at `P` and every
//!    projected point stays in the square. Each clipped triangle is oriented counter-clockwise
//!    in the disk's coordinates from the exact sign of its plane at `P` (`robust::orient3d`).
//! 3. **Cancel.** The covered region is `{w > 0}`, where `w(x)` counts the projected triangles
//!    covering `x`; `w` is the sum of its polygons' signed edges, so an edge that two triangles
//!    traverse in opposite directions (a shared edge of a mesh that is not a silhouette from
//!    `P`) contributes nothing. Every projected point is a function of one vertex, or of one
//!    (clipped) edge and one clip plane, evaluated with the edge's ends in a fixed order, so the
//!    two copies of a shared edge are bit-identical and cancel exactly; silhouette edges (both
//!    neighbours on the same side) add to multiplicity 2. What remains is the silhouette from
//!    `P` of what the pyramid holds, plus the square's sides.
//! 4. **Integrate.** When no remaining edge that separates `w = 0` from `w > 0` comes within its
//!    error of the disk, the disk is all covered or all seen: the visibility is exactly 0 or 1.
//!    Otherwise, when the edges form one convex
//!    counter-clockwise cycle (one convex occluder, clipped or not), the area is the closed form
//!    [`polygon_disk_area`] (a convex polygon clipped by a disk). Otherwise the disk's `x` range
//!    is cut into slabs at every edge end, every crossing of two edges inside the disk and every
//!    crossing of an edge with the circle; within a slab no two edges cross inside the disk, so
//!    sorting the edges at the slab's middle and counting `w` from below gives the intervals
//!    where `w > 0`, each bounded above and below by an edge (a trapezoid) or by the circle (the
//!    arc's integral `∫√(R² − x²) dx`, in closed form). An order decided wrongly only between
//!    two edges closer than their rounding changes the area by at most their distance, so the
//!    integration is stable where a boundary walk that classifies pieces would not be.
//!
//! The disk's plane may pass through `P` (the disk seen edge-on, `h ≤ 2⁻²⁶ |C − P|`, [`EDGE_ON`]): the
//! projection then degenerates, and the method works in the plane instead: a caster crossing
//! it meets it in a segment, which hides the part of the disk behind it as seen from `P`'s foot
//! (a wedge beyond the segment, clipped to the square); the same cancellation and integration
//! follow. A caster lying in the plane never blocks (the hard reference's convention for a light
//! in a caster's plane); one within `h` of the plane on `P`'s side that does not cross it is not
//! seen by this model, and the bound does not cover it (it would have to be parallel to the
//! disk's plane to `2⁻²⁶`).
//!
//! # Error bound
//!
//! [`Visibility::bound`] bounds `|value − true visibility|`. It is a first-order forward error
//! bound (terms in `u²`, `u = 2⁻⁵³`, left out), made of:
//! * the projection: each edge left after cancellation lies on a known line: a caster edge's
//!   projection (the homogeneous cross product of its ends' `(A, B, W)`, whose error follows
//!   from each coordinate's: the rounding of `r = X − P` and of the dot products), a side of the
//!   square, or the caster's plane met with the light's. Both ends' distance from the exact
//!   line is bounded a posteriori (the computed point put into the line, with the line's and
//!   the evaluation's errors), plus the frame's own rounding (`u, v, t, h, p_u, p_v`). Sliding
//!   along its line (a clip point's ill-conditioned part) moves no edge; an edge moved by `δ`
//!   changes the covered area by at most `δ` times its length inside the disk enlarged by `δ`,
//!   summed over the edges left (cancelled copies move together and change nothing);
//! * the integration: `16 u` times the sum of the magnitudes of the terms summed
//!   (compensated summation), plus `4 u π R²` per evaluation of the arc integral;
//! * edge-on, the in-plane model's own error: `h` times `1 / sin` of the angle between the
//!   plane and the caster edge or face that makes each wedge boundary, times the boundary's
//!   length over its distance from `P` (first order in `h`).
//!
//! Measured (`tests/soft.rs`): against the closed form on plates the error is at most
//! `2·10⁻¹⁵`, the bound `3·10⁻¹⁵` to `10⁻¹³`; the bound grows like `u |C − P| / h` as `P` nears the
//! disk's plane (about `10⁻⁶` at [`EDGE_ON`] on the tests' scene); on a 256² bunny on a floor
//! the largest is `4·10⁻⁹`. Exactly 0 or 1 (bound 0) is reported only as step 4 says.
//! [`Visibility::is_penumbra`] is strictly between, beyond the bound.

use crate::bvh::Bvh;
use crate::occlusion::CONTACT;
use crate::states::PixelPoints;
use crate::Shot;
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use shadowvol_scenes::LightDisk;

/// `f64` unit roundoff `2⁻⁵³`.
const U: f64 = 1.0 / 9_007_199_254_740_992.0;

/// The square around the disk: `R′ = R · SQUARE` (`1 + 2⁻²⁰`).
const SQUARE: f64 = 1.0 + 1.0 / 1_048_576.0;

/// Relative distance of `P` from the disk's plane below which the disk is taken edge-on (`2⁻²⁶`
/// of `|C − P|`): the projection's bound grows like `u |C − P| / h`, the in-plane model's like
/// `h`; on the tests' scene they meet near `2⁻²⁶`, at about `10⁻⁶`.
pub const EDGE_ON: f64 = 1.0 / 67_108_864.0;

/// At most this many edges left after cancellation are tried as one convex cycle.
const FAST_PATH_EDGES: usize = 64;

/// How the covered area is integrated once the edges are known.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Integration {
    /// The closed form when the edges form one convex cycle, slabs otherwise (the default).
    #[default]
    Auto,
    /// Always the slabs (to test them against the closed form).
    Slabs,
}

/// The visibility of a light's disk from one surface point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Visibility {
    /// The share of the disk's area the point sees past the casters, in `[0, 1]`.
    pub value: f64,
    /// `|value − true visibility| ≤ bound` (see the module's error bound). 0 when the value is
    /// exactly 0 or 1 (no edge separating seen from hidden comes near the disk).
    pub bound: f64,
    /// Casters whose BVH boxes met the pyramid from the point to the disk's square.
    pub casters: u32,
    /// Projected edges left after cancellation (silhouettes and the square's sides), all of
    /// them, inside the disk or not.
    pub edges: u32,
}

impl Visibility {
    /// Exactly 1: the point sees the whole disk.
    #[must_use]
    pub fn is_lit(&self) -> bool {
        self.value == 1.0 && self.bound == 0.0
    }

    /// Exactly 0: the point sees none of the disk.
    #[must_use]
    pub fn is_umbra(&self) -> bool {
        self.value == 0.0 && self.bound == 0.0
    }

    /// Strictly between 0 and 1, beyond the bound.
    #[must_use]
    pub fn is_penumbra(&self) -> bool {
        self.value - self.bound > 0.0 && self.value + self.bound < 1.0
    }

    const LIT: Self = Self {
        value: 1.0,
        bound: 0.0,
        casters: 0,
        edges: 0,
    };
}

/// The casters of a scene as the soft reference reads them: a BVH over the `f32` world
/// triangles of the surfaces that cast shadows, each with its global triangle index (surfaces
/// concatenated, what [`crate::SurfacePoint::triangle`] names). Build once per shot, query per
/// point and light.
#[derive(Debug, Clone)]
pub struct SoftCasters {
    bvh: Bvh,
    ids: Vec<u32>,
    /// `|eye|∞`: with the point's own magnitude, it sets the contact distance.
    eye: f64,
}

impl SoftCasters {
    /// The casters of `shot` (the same triangles and bits as the hard reference's).
    #[must_use]
    pub fn new(shot: &Shot<'_>) -> Self {
        let casts: Vec<bool> = shot.scene.surfaces().map(|s| s.casts_shadows).collect();
        let mut tris = Vec::new();
        let mut ids = Vec::new();
        let mut next = 0u32;
        for (oi, obj) in shot.triangles().iter().enumerate() {
            for t in obj {
                if casts[oi] {
                    tris.push(t.map(Vec3::as_dvec3));
                    ids.push(next);
                }
                next += 1;
            }
        }
        Self::build(tris, ids, shot.camera.eye.as_dvec3())
    }

    /// Casters from bare triangles; triangle `i`'s id is `i`. `eye` plays the camera's part in
    /// the contact distance (`CONTACT × (|P|∞ + |eye|∞)`, as in the hard reference).
    #[must_use]
    pub fn from_triangles(tris: &[[Vec3; 3]], eye: DVec3) -> Self {
        let ids = (0..tris.len() as u32).collect();
        Self::build(
            tris.iter().map(|t| t.map(Vec3::as_dvec3)).collect(),
            ids,
            eye,
        )
    }

    fn build(tris: Vec<[DVec3; 3]>, ids: Vec<u32>, eye: DVec3) -> Self {
        Self {
            bvh: Bvh::build_with_ids(tris, ids.clone()),
            ids,
            eye: eye.abs().max_element(),
        }
    }

    /// Number of caster triangles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// True when there is no caster.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// The visibility of `disk` from `point`, ignoring the caster with id `skip` (the point's
    /// own triangle; `u32::MAX` for none). See the module documentation. A disk or point that is
    /// not finite gives value 0 with bound 1 (nothing known).
    #[must_use]
    pub fn visibility(
        &self,
        disk: &LightDisk,
        point: DVec3,
        skip: u32,
        integration: Integration,
    ) -> Visibility {
        let contact = CONTACT * (point.abs().max_element() + self.eye);
        let Some(frame) = Frame::new(disk, point) else {
            return Visibility {
                value: 0.0,
                bound: 1.0,
                casters: 0,
                edges: 0,
            };
        };
        let mut edges = Vec::new();
        let mut casters = 0u32;
        let mut bad = false;
        self.bvh.visit_boxes(
            |lo, hi| frame.box_may_meet(lo, hi),
            |i| {
                if self.ids[i] == skip {
                    return false;
                }
                casters += 1;
                let tri = self.bvh.triangle(i);
                bad |= !frame.project(tri, contact, &mut edges);
                false
            },
        );
        if casters == 0 {
            return Visibility::LIT;
        }
        let merged = cancel(edges);
        let mut v = integrate(&merged, frame.r, integration);
        v.casters = casters;
        if bad {
            v.bound = v.bound.max(1.0);
        }
        v
    }
}

/// The visibility of `disk` from `point` among bare casters: [`SoftCasters::visibility`] of
/// [`SoftCasters::from_triangles`] with nothing skipped and the default integration. Builds
/// the BVH on every call; for many points build [`SoftCasters`] once.
#[must_use]
pub fn disk_visibility(
    tris: &[[Vec3; 3]],
    disk: &LightDisk,
    point: DVec3,
    eye: DVec3,
) -> Visibility {
    SoftCasters::from_triangles(tris, eye).visibility(disk, point, u32::MAX, Integration::Auto)
}

// ---------------------------------------------------------------------------------------------
// The frame: disk coordinates, the pyramid, the projection.

/// A projected point's homogeneous coordinates `(A, B, W)`.
#[derive(Debug, Clone, Copy)]
struct Hv {
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
struct HLine {
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
    fn dist(&self, p: Pt) -> f64 {
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
struct Pt {
    x: f64,
    y: f64,
    d: f64,
}

impl Pt {
    fn key(&self) -> [u64; 2] {
        [self.x.to_bits(), self.y.to_bits()]
    }
}

/// One clip half-plane `f ≥ 0` in homogeneous coordinates: `f = c₀ A + c₁ B + c₂ W + c₃`.
#[derive(Debug, Clone, Copy)]
struct Form([f64; 4]);

impl Form {
    fn eval(&self, p: &Hv) -> f64 {
        let c = self.0;
        c[0] * p.h[0] + c[1] * p.h[1] + c[2] * p.h[2] + c[3]
    }
}

#[derive(Debug, Clone)]
struct Frame {
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
    r: f64,
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
struct EdgeOn {
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
    fn new(disk: &LightDisk, p: DVec3) -> Option<Self> {
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
    fn box_may_meet(&self, lo: DVec3, hi: DVec3) -> bool {
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
    fn project(&self, tri: [DVec3; 3], contact: f64, out: &mut Vec<Edge>) -> bool {
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

fn coord(p: DVec3) -> robust::Coord3D<f64> {
    robust::Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

fn key3(p: DVec3) -> [u64; 3] {
    p.to_array().map(f64::to_bits)
}

const MAX_POLY: usize = 10;

/// The clip planes `a ≤ R′`, `a ≥ −R′` and `b ≤ R′` (bits of [`Hv::on`]).
const SIDES_NOT_COUNTED: u8 = 0b0111;

/// [`Hv::line`] of the first clip plane.
const CLIP_LINE: u8 = 8;

/// A convex polygon of at most [`MAX_POLY`] homogeneous points.
#[derive(Debug, Clone, Copy)]
struct Poly {
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
fn cut(p: &Hv, fp: f64, q: &Hv, fq: f64) -> Hv {
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
fn clip_square(ring: &[Pt], s: f64) -> Vec<Pt> {
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

// ---------------------------------------------------------------------------------------------
// Edges and their cancellation.

/// A directed edge `p → q` of multiplicity `m` (negative: `q → p`), with `p`'s key below `q`'s.
#[derive(Debug, Clone, Copy)]
struct Edge {
    p: Pt,
    q: Pt,
    m: i32,
    /// The edge's line, to bound the ends' distance from the exact line (`None`: `extra` is
    /// that bound).
    line: Option<HLine>,
    /// Added to the distance: the frame's own error.
    extra: f64,
}

impl Edge {
    /// A bound on the distance of both ends from the exact edge's line.
    fn deviation(&self) -> f64 {
        self.line
            .map_or(0.0, |l| l.dist(self.p).max(l.dist(self.q)))
            + self.extra
    }
}

/// Appends the ring's edges `i → i + 1` that `keep` keeps, each on line `lines[i]` (or with
/// the deviation `extra[i]` alone), reversed unless `ccw`.
fn push_polygon(
    pts: &[Pt],
    keep: &[bool],
    lines: &[Option<HLine>],
    extra: &[f64],
    ccw: bool,
    out: &mut Vec<Edge>,
) {
    let n = pts.len();
    for i in 0..n {
        if !keep[i] {
            continue;
        }
        let (mut a, mut b) = (pts[i], pts[(i + 1) % n]);
        if !ccw {
            std::mem::swap(&mut a, &mut b);
        }
        if a.x == b.x && a.y == b.y {
            continue;
        }
        let (line, extra) = (lines[i], extra[i]);
        out.push(if a.key() < b.key() {
            Edge {
                p: a,
                q: b,
                m: 1,
                line,
                extra,
            }
        } else {
            Edge {
                p: b,
                q: a,
                m: -1,
                line,
                extra,
            }
        });
    }
}

/// Sums the multiplicities of identical edges (same bits at both ends) and drops those that
/// cancel. Sorted by a hash of the ends (16-byte records), then exactly within equal hashes.
fn cancel(edges: Vec<Edge>) -> Vec<Edge> {
    let full = |e: &Edge| (e.p.key(), e.q.key());
    let mut order: Vec<(u64, u32)> = edges
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let [a, b] = e.p.key();
            let [c, d] = e.q.key();
            let mut h = a.wrapping_mul(0x9E37_79B9_7F4A_7C15);
            for w in [b, c, d] {
                h = (h.rotate_left(23) ^ w).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            }
            (h, i as u32)
        })
        .collect();
    order.sort_unstable();
    let mut out: Vec<Edge> = Vec::with_capacity(edges.len() / 4 + 4);
    let mut i = 0;
    while i < order.len() {
        let mut j = i + 1;
        while j < order.len() && order[j].0 == order[i].0 {
            j += 1;
        }
        let group = &mut order[i..j];
        if group.len() > 1 {
            group.sort_unstable_by_key(|&(_, k)| full(&edges[k as usize]));
        }
        let mut k = 0;
        while k < group.len() {
            let mut e = edges[group[k].1 as usize];
            let mut l = k + 1;
            while l < group.len() && full(&edges[group[l].1 as usize]) == full(&e) {
                let f = &edges[group[l].1 as usize];
                e.m += f.m;
                e.extra = e.extra.max(f.extra);
                l += 1;
            }
            if e.m != 0 {
                out.push(e);
            }
            k = l;
        }
        i = j;
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Integration.

/// A non-vertical edge from left to right with its signed weight (`+m` when it runs towards
/// `+x`: counting from below, crossing it enters `m` polygons).
#[derive(Debug, Clone, Copy)]
struct Seg {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    s: i32,
    /// Within its error of the disk.
    inner: bool,
}

impl Seg {
    fn y_at(&self, x: f64) -> f64 {
        if x == self.x0 {
            self.y0
        } else if x == self.x1 {
            self.y1
        } else {
            self.y0 + (x - self.x0) * ((self.y1 - self.y0) / (self.x1 - self.x0))
        }
    }
}

/// The parameters `t ∈ [0, 1]` where the segment `p + t (q − p)` meets the circle of radius
/// `r` about the origin, ascending (none, one or two).
fn circle_params(p: [f64; 2], q: [f64; 2], r: f64) -> ([f64; 2], usize) {
    let d = [q[0] - p[0], q[1] - p[1]];
    let a = d[0] * d[0] + d[1] * d[1];
    let b = p[0] * d[0] + p[1] * d[1];
    let c = p[0] * p[0] + p[1] * p[1] - r * r;
    let disc = b * b - a * c;
    if a == 0.0 || disc < 0.0 {
        return ([0.0; 2], 0);
    }
    let s = disc.sqrt();
    let mut out = [0.0; 2];
    let mut n = 0;
    for t in [(-b - s) / a, (-b + s) / a] {
        if (0.0..=1.0).contains(&t) {
            out[n] = t;
            n += 1;
        }
    }
    (out, n)
}

/// The length of the segment's part within distance `r` of the origin.
fn length_within(p: [f64; 2], q: [f64; 2], r: f64) -> f64 {
    let d = [q[0] - p[0], q[1] - p[1]];
    let len = d[0].hypot(d[1]);
    let a = d[0] * d[0] + d[1] * d[1];
    if a == 0.0 {
        return 0.0;
    }
    let b = p[0] * d[0] + p[1] * d[1];
    let c = p[0] * p[0] + p[1] * p[1] - r * r;
    let disc = b * b - a * c;
    if disc <= 0.0 {
        return 0.0;
    }
    let s = disc.sqrt();
    let (t0, t1) = (((-b - s) / a).max(0.0), ((-b + s) / a).min(1.0));
    (t1 - t0).max(0.0) * len
}

/// Neumaier's compensated sum.
#[derive(Debug, Default, Clone, Copy)]
struct Sum {
    s: f64,
    c: f64,
}

impl Sum {
    fn add(&mut self, x: f64) {
        let t = self.s + x;
        if self.s.abs() >= x.abs() {
            self.c += (self.s - t) + x;
        } else {
            self.c += (x - t) + self.s;
        }
        self.s = t;
    }
    fn value(&self) -> f64 {
        self.s + self.c
    }
}

/// The visibility of the disk of radius `r` from the edges left after cancellation.
fn integrate(edges: &[Edge], r: f64, integration: Integration) -> Visibility {
    let disk_area = std::f64::consts::PI * r * r;
    let count = edges.len() as u32;
    // The edges that may reach the disk, and the error their displacement can make.
    let mut geom = 0.0;
    let mut inner = vec![false; edges.len()];
    for (i, e) in edges.iter().enumerate() {
        let d = e.deviation();
        let (p, q) = ([e.p.x, e.p.y], [e.q.x, e.q.y]);
        let within = length_within(p, q, r + d);
        if within > 0.0 || p[0].hypot(p[1]) <= r + d {
            inner[i] = true;
            geom += (within + 2.0 * d) * d * f64::from(e.m.unsigned_abs());
        }
    }
    let segs: Vec<Seg> = edges
        .iter()
        .zip(&inner)
        .filter(|(e, _)| e.p.x != e.q.x)
        .map(|(e, &inner)| {
            let (a, b, s) = if e.p.x < e.q.x {
                (e.p, e.q, e.m)
            } else {
                (e.q, e.p, -e.m)
            };
            Seg {
                x0: a.x,
                y0: a.y,
                x1: b.x,
                y1: b.y,
                s,
                inner,
            }
        })
        .filter(|s| s.x1 > -r && s.x0 < r)
        .collect();
    // An edge within its error of the disk but not in it is taken for a boundary: whether it
    // separates w = 0 from w > 0 is only asked where it is inside.
    let grazing = edges.iter().zip(&inner).any(|(e, &inner)| {
        let (p, q) = ([e.p.x, e.p.y], [e.q.x, e.q.y]);
        inner && length_within(p, q, r) == 0.0 && p[0].hypot(p[1]) >= r
    });
    let exact = |covered: bool| Visibility {
        value: if covered { 0.0 } else { 1.0 },
        bound: 0.0,
        casters: 0,
        edges: count,
    };
    if !inner.contains(&true) {
        // w is the same over the whole disk: its value at the centre.
        return exact(w_at(&segs, 0.0, 0.0) > 0);
    }
    // A vertical edge near the disk that separates w = 0 from w > 0 is a boundary.
    let vertical_boundary = edges.iter().zip(&inner).any(|(e, &inner)| {
        if !inner || e.p.x != e.q.x {
            return false;
        }
        // Just right of an edge running up with multiplicity m, w is m less than just left.
        let right = w_at(&segs, e.p.x, 0.5 * (e.p.y + e.q.y));
        let up = if e.p.y < e.q.y { e.m } else { -e.m };
        (right > 0) != (right + up > 0)
    });
    let (covered, err, boundary) = match (integration, convex_cycle(edges)) {
        (Integration::Auto, Some(ring)) => {
            let (a, abs) = polygon_disk_area_abs(&ring, r);
            (
                a,
                16.0 * U * abs + 4.0 * U * disk_area * ring.len() as f64,
                true,
            )
        }
        _ => slabs(edges, &inner, &segs, r),
    };
    if !boundary && !vertical_boundary && !grazing {
        // No edge that separates covered from uncovered comes near the disk.
        return exact(covered > 0.5 * disk_area);
    }
    let value = (1.0 - covered / disk_area).clamp(0.0, 1.0);
    Visibility {
        value,
        // Above 1 it says nothing (an edge whose line could not be bounded).
        bound: ((geom + err) / disk_area + 8.0 * U).min(1.0),
        casters: 0,
        edges: count,
    }
}

/// `w` at `(x, y)` counted from below along the vertical line (edges through `x` half-open,
/// `[x0, x1)`; vertical edges are not counted: `w` just right of them).
fn w_at(segs: &[Seg], x: f64, y: f64) -> i32 {
    segs.iter()
        .filter(|s| s.x0 <= x && x < s.x1 && s.y_at(x) < y)
        .map(|s| s.s)
        .sum()
}

/// The covered area of the disk by slabs, its integration error bound, and whether an edge
/// separates `w = 0` from `w > 0` inside the disk.
fn slabs(edges: &[Edge], inner: &[bool], segs: &[Seg], r: f64) -> (f64, f64, bool) {
    let inner: Vec<usize> = (0..edges.len()).filter(|&i| inner[i]).collect();
    let mut events = vec![-r, r];
    let inside = |x: f64| x > -r && x < r;
    for &i in &inner {
        let e = &edges[i];
        for x in [e.p.x, e.q.x] {
            if inside(x) {
                events.push(x);
            }
        }
        let (ts, n) = circle_params([e.p.x, e.p.y], [e.q.x, e.q.y], r);
        for &t in &ts[..n] {
            let x = e.p.x + t * (e.q.x - e.p.x);
            if inside(x) {
                events.push(x);
            }
        }
    }
    // Crossings of two edges inside the disk (ends shared by a chain are ends already).
    for (k, &i) in inner.iter().enumerate() {
        let e = &edges[i];
        let (ep, eq) = ([e.p.x, e.p.y], [e.q.x, e.q.y]);
        let d1 = [eq[0] - ep[0], eq[1] - ep[1]];
        for &j in &inner[k + 1..] {
            let f = &edges[j];
            let (fp, fq) = ([f.p.x, f.p.y], [f.q.x, f.q.y]);
            if ep == fp || ep == fq || eq == fp || eq == fq {
                continue;
            }
            let d2 = [fq[0] - fp[0], fq[1] - fp[1]];
            let den = d1[0] * d2[1] - d1[1] * d2[0];
            if den == 0.0 {
                continue;
            }
            let w = [fp[0] - ep[0], fp[1] - ep[1]];
            let t = (w[0] * d2[1] - w[1] * d2[0]) / den;
            let s = (w[0] * d1[1] - w[1] * d1[0]) / den;
            if (0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&s) {
                let x = ep[0] + t * d1[0];
                let y = ep[1] + t * d1[1];
                if inside(x) && x.hypot(y) <= r * (1.0 + 1e-9) {
                    events.push(x);
                }
            }
        }
    }
    events.sort_unstable_by(f64::total_cmp);
    events.dedup();
    let g = |x: f64| {
        let x = x.clamp(-r, r);
        0.5 * (x * (r * r - x * x).max(0.0).sqrt() + r * r * (x / r).clamp(-1.0, 1.0).asin())
    };
    let gx: Vec<f64> = events.iter().map(|&x| g(x)).collect();
    let mut total = Sum::default();
    let mut abs = 0.0;
    let mut arcs = 0usize;
    let mut boundary = false;
    // An edge that never comes near the disk lies wholly below or wholly above it over
    // |x| < r (the strip outside the disk has two parts): above, it changes nothing inside;
    // below, it only adds its weight to w at the circle's bottom while x is in [x0, x1).
    let near: Vec<&Seg> = segs.iter().filter(|s| s.inner).collect();
    let mut starts: Vec<(f64, i32)> = Vec::new();
    let mut ends: Vec<(f64, i32)> = Vec::new();
    for s in segs.iter().filter(|s| !s.inner) {
        if s.y_at(0.5 * (s.x0.max(-r) + s.x1.min(r))) < 0.0 {
            starts.push((s.x0, s.s));
            ends.push((s.x1, s.s));
        }
    }
    starts.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    ends.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let (mut si, mut ei, mut base) = (0, 0, 0i32);
    // (y at the slab's middle, weight, integral over the slab, its magnitude, inside the disk)
    let mut active: Vec<(f64, i32, f64, f64, bool)> = Vec::new();
    for k in 0..events.len().saturating_sub(1) {
        let (x0, x1) = (events[k], events[k + 1]);
        if x1 <= x0 {
            continue;
        }
        let xm = 0.5 * (x0 + x1);
        let c = (r * r - xm * xm).max(0.0).sqrt();
        let gd = gx[k + 1] - gx[k];
        while si < starts.len() && starts[si].0 <= xm {
            base += starts[si].1;
            si += 1;
        }
        while ei < ends.len() && ends[ei].0 <= xm {
            base -= ends[ei].1;
            ei += 1;
        }
        active.clear();
        // The circle's bottom and top, with what lies below.
        active.push((f64::NEG_INFINITY, base, -gd, gd.abs(), false));
        active.push((f64::INFINITY, 0, gd, gd.abs(), false));
        for s in &near {
            if !(s.x0 <= xm && xm < s.x1) {
                continue;
            }
            let ym = s.y_at(xm);
            let (val, mag, inside) = if ym >= c {
                (gd, gd.abs(), false)
            } else if ym <= -c {
                (-gd, gd.abs(), false)
            } else {
                let (ya, yb) = (s.y_at(x0), s.y_at(x1));
                (
                    0.5 * (x1 - x0) * (ya + yb),
                    (x1 - x0) * (ya.abs() + yb.abs()),
                    true,
                )
            };
            active.push((ym, s.s, val, mag, inside));
        }
        active.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut w = 0i32;
        for (j, a) in active.iter().enumerate() {
            let below = w;
            w += a.1;
            boundary |= a.4 && ((below > 0) != (w > 0));
            if w > 0 {
                if let Some(b) = active.get(j + 1) {
                    total.add(b.2);
                    total.add(-a.2);
                    abs += a.3 + b.3;
                    arcs += 2;
                }
            }
        }
    }
    let disk_area = std::f64::consts::PI * r * r;
    (
        total.value(),
        16.0 * U * abs + 4.0 * U * disk_area * arcs as f64,
        boundary,
    )
}

/// The edges as one convex counter-clockwise cycle of multiplicity 1, if they are one.
fn convex_cycle(edges: &[Edge]) -> Option<Vec<[f64; 2]>> {
    let n = edges.len();
    if !(3..=FAST_PATH_EDGES).contains(&n) || edges.iter().any(|e| e.m.abs() != 1) {
        return None;
    }
    let directed: Vec<(Pt, Pt)> = edges
        .iter()
        .map(|e| if e.m > 0 { (e.p, e.q) } else { (e.q, e.p) })
        .collect();
    let mut ring = Vec::with_capacity(n);
    let mut used = vec![false; n];
    let mut cur = 0;
    for _ in 0..n {
        if used[cur] {
            return None;
        }
        used[cur] = true;
        ring.push([directed[cur].0.x, directed[cur].0.y]);
        let to = directed[cur].1.key();
        let mut next = None;
        for (j, d) in directed.iter().enumerate() {
            if d.0.key() == to {
                if next.is_some() {
                    return None;
                }
                next = Some(j);
            }
        }
        cur = next?;
    }
    if cur != 0 || used.iter().any(|u| !u) {
        return None;
    }
    let mut turning = 0.0;
    for i in 0..n {
        let (a, b, c) = (ring[i], ring[(i + 1) % n], ring[(i + 2) % n]);
        let (d1, d2) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
        let cross = d1[0] * d2[1] - d1[1] * d2[0];
        let dot = d1[0] * d2[0] + d1[1] * d2[1];
        if cross < 0.0 {
            return None;
        }
        turning += cross.atan2(dot);
    }
    ((turning - std::f64::consts::TAU).abs() < 1e-6).then_some(ring)
}

/// The signed area of a polygon clipped by the disk of radius `r` about the origin: positive
/// for a counter-clockwise ring, in the units of the coordinates squared. Exact up to floating
/// point for any simple polygon (the sum over its edges of the signed area of the triangle
/// `(origin, a, b)` within the disk: a triangle where the edge is inside, a circular sector
/// where it is outside); the closed form for a convex occluder clipped by a light's disk.
#[must_use]
pub fn polygon_disk_area(ring: &[[f64; 2]], r: f64) -> f64 {
    polygon_disk_area_abs(ring, r).0
}

/// [`polygon_disk_area`] and the sum of its terms' magnitudes (for the error bound).
fn polygon_disk_area_abs(ring: &[[f64; 2]], r: f64) -> (f64, f64) {
    let n = ring.len();
    let mut total = Sum::default();
    let mut abs = 0.0;
    let sector = |p: [f64; 2], q: [f64; 2]| {
        let cross = p[0] * q[1] - p[1] * q[0];
        let dot = p[0] * q[0] + p[1] * q[1];
        0.5 * r * r * cross.atan2(dot)
    };
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        let (ts, k) = circle_params(a, b, r);
        let inside_a = a[0] * a[0] + a[1] * a[1] <= r * r;
        let at = |t: f64| [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
        // Pieces of the edge between its ends and its crossings, each inside or outside.
        let mut cuts = vec![0.0];
        cuts.extend_from_slice(&ts[..k]);
        cuts.push(1.0);
        let mut inside = inside_a;
        for w in cuts.windows(2) {
            let (p, q) = (at(w[0]), at(w[1]));
            let mid = at(0.5 * (w[0] + w[1]));
            if k > 0 {
                inside = mid[0] * mid[0] + mid[1] * mid[1] <= r * r;
            }
            let term = if inside {
                0.5 * (p[0] * q[1] - p[1] * q[0])
            } else if p == q {
                0.0
            } else {
                sector(p, q)
            };
            total.add(term);
            abs += term.abs();
        }
    }
    (total.value(), abs)
}

// ---------------------------------------------------------------------------------------------
// Per image.

/// The true visibility of one light's disk for every pixel of a shot.
#[derive(Debug, Clone)]
pub struct SoftReference {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major, top row first: `None` for background, else the visibility of the pixel's
    /// surface point (the hard reference's point: [`crate::surface_points`]).
    pub pixels: Vec<Option<Visibility>>,
}

impl SoftReference {
    /// The largest bound over the covered pixels (0 when none is covered).
    #[must_use]
    pub fn max_bound(&self) -> f64 {
        self.pixels
            .iter()
            .flatten()
            .map(|v| v.bound)
            .fold(0.0, f64::max)
    }
}

/// Checks that `disk` can be light `light`'s.
fn check_light(shot: &Shot<'_>, light: usize, disk: &LightDisk) {
    let l = shot.light(light);
    assert_eq!(
        l[3] == 0.0,
        disk.directional,
        "light {light} and its disk disagree on being directional"
    );
}

/// The true visibility of `disk` (light `light`'s, [`LightDisk::of`] with
/// [`shadowvol_scenes::Scene::light_aim`]) for every pixel with a surface: the share of the disk
/// that pixel's surface point sees past the shot's casters, with its bound ([`Visibility`]).
/// Builds the casters' BVH, then runs over the pixels in parallel (rayon).
///
/// # Panics
/// Panics if `light` is not a light of the shot's scene, or if `disk` is directional and the
/// light is not, or the reverse.
#[must_use]
pub fn visibility_reference(shot: &Shot<'_>, light: usize, disk: &LightDisk) -> SoftReference {
    visibility_reference_with(
        shot,
        &SoftCasters::new(shot),
        light,
        disk,
        Integration::Auto,
    )
}

/// [`visibility_reference`] with casters built once ([`SoftCasters::new`] of the same shot) and
/// a choice of integration.
///
/// # Panics
/// As [`visibility_reference`].
#[must_use]
pub fn visibility_reference_with(
    shot: &Shot<'_>,
    casters: &SoftCasters,
    light: usize,
    disk: &LightDisk,
    integration: Integration,
) -> SoftReference {
    check_light(shot, light, disk);
    let at = PixelPoints::new(shot);
    let pixels = (0..at.pixels())
        .into_par_iter()
        .map(|i| {
            at.point(shot, i)
                .map(|sp| casters.visibility(disk, sp.position, sp.triangle, integration))
        })
        .collect();
    SoftReference {
        width: shot.width,
        height: shot.height,
        pixels,
    }
}

/// A render's per-pixel visibility (`k / N` of its samples) against the true one.
///
/// Pixels are sorted by the reference into *lit* (exactly 1), *umbra* (exactly 0), *penumbra*
/// (strictly between, beyond the bound) and *undecided* (within the bound of 0 or 1 but not
/// exactly it). A lit or umbra pixel whose 3×3 neighbourhood holds a covered pixel of another
/// class is a *border* pixel: its render value may come from a sample's hard shadow boundary
/// within rounding of the surface point (the hard metric's 3×3 rule), so its mismatches are
/// counted apart.
#[derive(Debug, Clone, PartialEq)]
pub struct SoftComparison {
    /// Pixels with a surface.
    pub covered_pixels: usize,
    /// Covered pixels whose true visibility is strictly between 0 and 1, beyond the bound.
    pub penumbra_pixels: usize,
    /// Mean of `|render − true|` over the penumbra pixels (0 when there are none).
    pub penumbra_mean_error: f64,
    /// 99th percentile (nearest rank) of `|render − true|` over the penumbra pixels.
    pub penumbra_p99_error: f64,
    /// Largest `|render − true|` over the penumbra pixels.
    pub penumbra_max_error: f64,
    /// Covered pixels whose true visibility is exactly 1.
    pub lit_pixels: usize,
    /// Lit pixels, not on a border, where the render's visibility is not 1.
    pub lit_mismatched: usize,
    /// Covered pixels whose true visibility is exactly 0.
    pub umbra_pixels: usize,
    /// Umbra pixels, not on a border, where the render's visibility is not 0.
    pub umbra_mismatched: usize,
    /// Lit or umbra pixels on a border (a 3×3 neighbour of another class) where the render
    /// differs: not counted in `lit_mismatched` or `umbra_mismatched`.
    pub border_mismatched: usize,
    /// Covered pixels within the bound of 0 or 1 but not exactly there: left out.
    pub undecided_pixels: usize,
    /// The largest error bound of the reference over the penumbra pixels: the errors above are
    /// true to within it.
    pub reference_bound: f64,
}

/// Compares a render's visibility for light `light` with [`visibility_reference`].
/// `visibility` is row-major, top row first, one value per pixel (background pixels are
/// ignored).
///
/// # Panics
/// As [`visibility_reference`], and if `visibility` does not have one value per pixel.
#[must_use]
pub fn compare_visibility(
    shot: &Shot<'_>,
    light: usize,
    disk: &LightDisk,
    visibility: &[f32],
) -> SoftComparison {
    compare_with_reference(&visibility_reference(shot, light, disk), visibility)
}

/// [`compare_visibility`] against a reference already computed.
///
/// # Panics
/// Panics if `visibility` does not have one value per pixel of `reference`.
#[must_use]
pub fn compare_with_reference(reference: &SoftReference, visibility: &[f32]) -> SoftComparison {
    let (w, h) = (reference.width as usize, reference.height as usize);
    assert_eq!(visibility.len(), w * h, "one visibility per pixel");
    #[derive(Clone, Copy, PartialEq, Eq)]
    enum Class {
        None,
        Lit,
        Umbra,
        Penumbra,
        Undecided,
    }
    let class: Vec<Class> = reference
        .pixels
        .iter()
        .map(|p| match p {
            None => Class::None,
            Some(v) if v.is_lit() => Class::Lit,
            Some(v) if v.is_umbra() => Class::Umbra,
            Some(v) if v.is_penumbra() => Class::Penumbra,
            Some(_) => Class::Undecided,
        })
        .collect();
    let mut out = SoftComparison {
        covered_pixels: 0,
        penumbra_pixels: 0,
        penumbra_mean_error: 0.0,
        penumbra_p99_error: 0.0,
        penumbra_max_error: 0.0,
        lit_pixels: 0,
        lit_mismatched: 0,
        umbra_pixels: 0,
        umbra_mismatched: 0,
        border_mismatched: 0,
        undecided_pixels: 0,
        reference_bound: 0.0,
    };
    let mut errors = Vec::new();
    for i in 0..w * h {
        let Some(v) = reference.pixels[i] else {
            continue;
        };
        out.covered_pixels += 1;
        let render = f64::from(visibility[i]);
        match class[i] {
            Class::Penumbra => {
                out.penumbra_pixels += 1;
                errors.push((render - v.value).abs());
                out.reference_bound = out.reference_bound.max(v.bound);
            }
            Class::Undecided => out.undecided_pixels += 1,
            Class::Lit | Class::Umbra => {
                let lit = class[i] == Class::Lit;
                if lit {
                    out.lit_pixels += 1;
                } else {
                    out.umbra_pixels += 1;
                }
                if render == v.value {
                    continue;
                }
                let (x, y) = (i % w, i / w);
                let border = (y.saturating_sub(1)..=(y + 1).min(h - 1)).any(|ny| {
                    (x.saturating_sub(1)..=(x + 1).min(w - 1)).any(|nx| {
                        let c = class[ny * w + nx];
                        c != Class::None && c != class[i]
                    })
                });
                if border {
                    out.border_mismatched += 1;
                } else if lit {
                    out.lit_mismatched += 1;
                } else {
                    out.umbra_mismatched += 1;
                }
            }
            Class::None => {}
        }
    }
    if !errors.is_empty() {
        errors.sort_unstable_by(f64::total_cmp);
        let n = errors.len();
        out.penumbra_mean_error = errors.iter().sum::<f64>() / n as f64;
        out.penumbra_max_error = errors[n - 1];
        out.penumbra_p99_error = errors[(n * 99).div_ceil(100).max(1) - 1];
    }
    out
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
