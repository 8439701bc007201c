//! Exact segment–triangle occlusion for the ray-traced reference.
//!
//! A caster triangle `T = (a, b, c)` blocks the surface point `o` from the light `L` when the
//! open segment from `o` to `L` (for a directional light, the open ray from `o` towards it)
//! crosses `T`:
//!
//! 1. `o` and `L` lie strictly on opposite sides of `T`'s plane:
//!    `sgn H(a, b, c, o) = −sgn H(a, b, c, L) ≠ 0`;
//! 2. the line through `o` and `L` meets the closed triangle: the three edge volumes
//!    `E(a, b)`, `E(b, c)`, `E(c, a)` are not of mixed strict signs,
//!
//! with `H(p, q, r, X) = | p 1 ; q 1 ; r 1 ; X |` (`X` homogeneous, `L = (x, y, z, w)`, `w ≥ 0`)
//! and `E(p, q) = det₃(l − w·o, p − o, q − o) = −H(o, L, p, q)`. A light in the plane of `T` (a
//! triangle edge-on to the light, whose shadow has no volume) or on `T` itself (touching it only
//! at `L`) gives `H(a, b, c, L) = 0`: such a triangle never blocks. That is the convention of the
//! volumes' sign 0 (an edge-on triangle casts nothing), so the raster and the reference judge the
//! same geometry.
//!
//! # What the inputs are
//! The caster vertices are the `f32` positions the GPU drew (exact in `f64`), the light is its
//! `f32` homogeneous vector, and `o` is the `f64` point the reference computed from the pixel-centre
//! ray and the rasterized triangle's plane. `o` is taken as an exact input, with one exception:
//! it is only known to `f64` rounding, so a caster whose plane passes within
//! [`CONTACT`]` × (|o|∞ + |eye|∞)` of it *touches* it (the surface point lies on that caster, as on
//! a coplanar neighbour of its own triangle or at a shared edge) and does not block, since a
//! segment that starts on a plane cannot cross it. When, in addition, the shadow ray grazes that
//! plane (`sin` of the angle below [`GRAZING`]) and the line meets the caster, where the line
//! crosses the plane depends on `o`'s last bits: that is the one case reported as
//! [`Crossing::Undecidable`].
//!
//! # How the signs are decided
//! Every sign is first evaluated in `f64` with a forward error bound (a semi-static filter); only
//! when the value lies within the bound is it decided exactly:
//! * `H(a, b, c, o)` and, for point lights with `w = 1`, `E(p, q)`: the georust `robust` crate's
//!   adaptive `orient3d` (Shewchuk's predicates), exact for `f64` inputs whose magnitudes keep
//!   every intermediate product in the normal range (checked: nonzero inputs in `2^±200`);
//! * `E(p, q)` for directional (`w = 0`) and homogeneous (`w ∉ {0, 1}`) lights, and any input
//!   outside that range: the 4×4 homogeneous determinant in big integers (every `f64` is an
//!   integer times a power of two; each row is scaled by a power of two, which keeps the sign).
//!   `shadowvol-robust-math`'s exact kernel takes `f32` inputs only (its error-free minors rely on
//!   products of two `f32` being exact in `f64`), so it cannot take the `f64` surface point;
//! * `H(a, b, c, L)` (caster and light only, once per caster and light):
//!   `shadowvol_robust_math::orient_exact`, the same exact predicate the `exact` mode uses.

use glam::{DVec3, Vec3};
use num_bigint::BigInt;
use shadowvol_robust_math::orient_exact;

/// Contact distance, relative to `|o|∞ + |eye|∞`: casters whose plane passes this close to the
/// surface point touch it (`2⁻³⁶ ≈ 1.5·10⁻¹¹`, about `10⁵` times the `f64` rounding of the
/// surface point and `10⁻⁴` of one `f32` step of the geometry).
pub const CONTACT: f64 = 1.0 / 68_719_476_736.0;

/// Sine of the angle between the shadow ray and a touching caster's plane below which the
/// crossing point is not determined by the `f64` surface point (`2⁻¹²`): with [`CONTACT`], the
/// line then meets the plane up to `2⁻²⁴` (one `f32` step) of the scene's scale away from `o`.
pub const GRAZING: f64 = 1.0 / 4096.0;

/// `f64` unit roundoff `2⁻⁵³`.
const U: f64 = 1.0 / 9_007_199_254_740_992.0;

/// Error constant of the edge-volume filter: Shewchuk's `orient3d` bound is `(7 + 56u)u` times
/// the permanent, and the permanent is at most `2 |d|₁ · max|p − o| · max|q − o|`; `20u` covers
/// `2 (7 + 56u) u` with the roundings of the bound itself.
const EDGE_EPS: f64 = 20.0 * U;

/// Error constant of the plane filter `n · (a − o)` with `n = (b − a) × (c − a)` from exact
/// differences: at most `8u` times `Σ nperm_i |a − o|_i` (three roundings in `n`, one in `a − o`,
/// three in the dot product), with margin.
const PLANE_EPS: f64 = 12.0 * U;

/// The answer for one caster.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Crossing {
    /// The open segment crosses the caster: the light is blocked.
    Blocks,
    /// It does not (including a light in the caster's plane and a caster touching `o`).
    Clear,
    /// The caster touches the surface point and the shadow ray grazes its plane into it: the
    /// answer hangs on the surface point's last bits.
    Undecidable,
}

/// A caster triangle with the data its filter reuses for every shadow ray.
#[derive(Debug, Clone, Copy)]
pub struct Caster {
    /// The vertices (the `f32` positions, exactly in `f64`).
    pub v: [DVec3; 3],
    /// `(b − a) × (c − a)` in `f64`.
    n: DVec3,
    /// Per component of `n`, the sum of the absolute values of its two products.
    nperm: DVec3,
    /// `|n|`.
    nlen: f64,
    /// Both differences `b − a` and `c − a` are exact in `f64` (the plane filter needs it).
    exact_edges: bool,
}

impl Caster {
    /// Prepares a caster from its `f32` vertices.
    #[must_use]
    pub fn new(t: [Vec3; 3]) -> Self {
        let v = [t[0].as_dvec3(), t[1].as_dvec3(), t[2].as_dvec3()];
        let e1 = v[1] - v[0];
        let e2 = v[2] - v[0];
        let exact = |x: DVec3, y: DVec3, d: DVec3| {
            (0..3).all(|k| d[k].is_finite() && two_diff_tail(x[k], y[k], d[k]) == 0.0)
        };
        let exact_edges = exact(v[1], v[0], e1) && exact(v[2], v[0], e2);
        let n = e1.cross(e2);
        let nperm = DVec3::new(
            (e1.y * e2.z).abs() + (e1.z * e2.y).abs(),
            (e1.z * e2.x).abs() + (e1.x * e2.z).abs(),
            (e1.x * e2.y).abs() + (e1.y * e2.x).abs(),
        );
        Self {
            v,
            n,
            nperm,
            nlen: n.length(),
            exact_edges,
        }
    }
}

/// The rounding error of `x − y` given its rounded value `d` (Knuth's two-sum tail; 0 iff the
/// difference is exact).
fn two_diff_tail(x: f64, y: f64, d: f64) -> f64 {
    let bv = x - d;
    let av = d + bv;
    (x - av) + (bv - y)
}

/// `sgn H(a, b, c, L)`: which side of the caster's plane the light is on (0: in the plane, the
/// caster never blocks it). Exact for any finite `f32` input.
#[must_use]
pub fn light_side(t: [Vec3; 3], l: [f32; 4]) -> i8 {
    // orient_exact(a, b, l, c) is sgn det(a 1; b 1; L; c 1), the rows of H(a, b, c, L) with the
    // last two swapped.
    -orient_exact(t[0].to_array(), t[1].to_array(), l, t[2].to_array())
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// `w = 1`.
    Point,
    /// `w = 0` or any other `w`.
    Homogeneous,
}

/// One shadow ray: a surface point and a light, with what every caster test reuses.
#[derive(Debug, Clone, Copy)]
pub struct ShadowRay {
    o: DVec3,
    l: [f64; 4],
    /// `l − w·o` rounded (for `w = 0` the exact direction).
    d: DVec3,
    /// `|d|₁`, enlarged by the rounding of `d` where `w ∉ {0, 1}`.
    dn1: f64,
    dlen: f64,
    /// Contact distance at `o`.
    contact: f64,
    kind: Kind,
}

impl ShadowRay {
    /// The shadow ray from surface point `o` to light `l` (`w ≥ 0`: a point light at `xyz / w`,
    /// or for `w = 0` the direction towards a directional light). `eye` is the camera position
    /// `o` was computed from; it sets the contact distance ([`CONTACT`]).
    #[must_use]
    pub fn new(o: DVec3, l: [f32; 4], eye: DVec3) -> Self {
        let l = l.map(f64::from);
        let xyz = DVec3::new(l[0], l[1], l[2]);
        let w = l[3];
        let (d, dn1, kind) = if w == 1.0 {
            let d = xyz - o;
            (d, d.abs().element_sum(), Kind::Point)
        } else if w == 0.0 {
            (xyz, xyz.abs().element_sum(), Kind::Homogeneous)
        } else {
            // Two roundings per component; the extra terms bound them.
            let d = xyz - w * o;
            let slack = xyz.abs().element_sum() + w.abs() * o.abs().element_sum();
            (d, d.abs().element_sum() + slack, Kind::Homogeneous)
        };
        Self {
            o,
            l,
            d,
            dn1,
            dlen: d.length(),
            contact: CONTACT * (o.abs().max_element() + eye.abs().max_element()),
            kind,
        }
    }

    /// Whether the caster blocks this shadow ray; `side` is [`light_side`] of the caster and the
    /// same light.
    #[must_use]
    pub fn crossing(&self, c: &Caster, side: i8) -> Crossing {
        if side == 0 {
            return Crossing::Clear;
        }
        let a = c.v[0] - self.o;
        let so_f = c.n.dot(a);
        if so_f.abs() <= self.contact * c.nlen {
            // The caster touches the surface point.
            let nd = c.n.dot(self.d).abs();
            if nd >= GRAZING * c.nlen * self.dlen {
                return Crossing::Clear;
            }
            return if self.line_meets(c, a) {
                Crossing::Undecidable
            } else {
                Crossing::Clear
            };
        }
        let bound = PLANE_EPS * c.nperm.dot(a.abs());
        let so = if c.exact_edges && so_f.abs() > bound {
            sgn(so_f)
        } else {
            self.orient_o_exact(c)
        };
        if so != -side {
            return Crossing::Clear;
        }
        if self.line_meets(c, a) {
            Crossing::Blocks
        } else {
            Crossing::Clear
        }
    }

    /// True when the line through `o` and the light meets the closed caster (the three edge
    /// volumes are not of mixed strict signs). `a` is `v[0] − o` rounded.
    fn line_meets(&self, c: &Caster, a: DVec3) -> bool {
        let p = [a, c.v[1] - self.o, c.v[2] - self.o];
        let m = p.map(|x| x.abs().max_element());
        let mut pos = false;
        let mut neg = false;
        let mut unknown = [false; 3];
        for k in 0..3 {
            let j = (k + 1) % 3;
            let e = self.d.dot(p[k].cross(p[j]));
            let bound = EDGE_EPS * self.dn1 * m[k] * m[j];
            if e > bound {
                pos = true;
            } else if e < -bound {
                neg = true;
            } else if !(e == 0.0 && bound == 0.0) {
                unknown[k] = true;
            }
            if pos && neg {
                return false;
            }
        }
        for (k, _) in unknown.iter().enumerate().filter(|(_, &u)| u) {
            match self.edge_exact(c.v[k], c.v[(k + 1) % 3]) {
                1 => pos = true,
                -1 => neg = true,
                _ => {}
            }
            if pos && neg {
                return false;
            }
        }
        true
    }

    /// Exact `sgn H(a, b, c, o)`.
    fn orient_o_exact(&self, c: &Caster) -> i8 {
        let [a, b, cc] = c.v;
        if [a, b, cc, self.o].iter().all(|p| in_shewchuk_range(*p)) {
            sgn(robust::orient3d(
                coord(a),
                coord(b),
                coord(cc),
                coord(self.o),
            ))
        } else {
            det4_sign([row(a, 1.0), row(b, 1.0), row(cc, 1.0), row(self.o, 1.0)])
        }
    }

    /// Exact `sgn E(p, q) = sgn det₃(l − w·o, p − o, q − o)`.
    fn edge_exact(&self, p: DVec3, q: DVec3) -> i8 {
        let lxyz = DVec3::new(self.l[0], self.l[1], self.l[2]);
        if self.kind == Kind::Point && [lxyz, p, q, self.o].iter().all(|v| in_shewchuk_range(*v)) {
            // orient3d(L, p, q, o) = det₃(L − o, p − o, q − o).
            sgn(robust::orient3d(
                coord(lxyz),
                coord(p),
                coord(q),
                coord(self.o),
            ))
        } else {
            -det4_sign([row(self.o, 1.0), self.l, row(p, 1.0), row(q, 1.0)])
        }
    }
}

fn sgn(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

fn coord(p: DVec3) -> robust::Coord3D<f64> {
    robust::Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

fn row(p: DVec3, w: f64) -> [f64; 4] {
    [p.x, p.y, p.z, w]
}

/// Nonzero magnitudes in `[2⁻²⁰⁰, 2²⁰⁰]`: products of three differences and their error terms
/// then stay in the normal `f64` range, where Shewchuk's adaptive predicates are exact.
fn in_shewchuk_range(p: DVec3) -> bool {
    const LO: f64 = 6.223_015_277_861_142e-61; // 2^-200
    const HI: f64 = 1.606_938_044_258_990_3e60; // 2^200
    p.to_array()
        .iter()
        .all(|&x| x == 0.0 || (x.abs() >= LO && x.abs() <= HI))
}

/// `(m, e)` with `x = m · 2^e` exactly (`x` finite).
pub(crate) fn decompose(x: f64) -> (i64, i32) {
    let bits = x.to_bits();
    let exp = ((bits >> 52) & 0x7ff) as i32;
    let frac = (bits & ((1u64 << 52) - 1)) as i64;
    let (m, e) = if exp == 0 {
        (frac, -1074)
    } else {
        (frac | (1i64 << 52), exp - 1075)
    };
    (if x < 0.0 { -m } else { m }, e)
}

/// `f64` values as integers, all scaled by one power of two (a positive factor).
pub(crate) fn scaled_ints(values: &[f64]) -> Vec<BigInt> {
    let parts: Vec<(i64, i32)> = values.iter().map(|&x| decompose(x)).collect();
    let e_min = parts
        .iter()
        .filter(|(m, _)| *m != 0)
        .map(|&(_, e)| e)
        .min()
        .unwrap_or(0);
    parts
        .iter()
        .map(|&(m, e)| {
            if m == 0 {
                BigInt::from(0)
            } else {
                BigInt::from(m) << ((e - e_min) as usize)
            }
        })
        .collect()
}

/// Exact sign of the 4×4 determinant of finite `f64` rows, in big integers: each row is scaled by
/// a power of two that makes its entries integers (a positive factor, so the sign is kept), then
/// the determinant is expanded by its 2×2 minors of rows {0, 1} and {2, 3}.
fn det4_sign(rows: [[f64; 4]; 4]) -> i8 {
    let ints: Vec<Vec<BigInt>> = rows.iter().map(|r| scaled_ints(r)).collect();
    let minor = |r1: usize, r2: usize, i: usize, j: usize| {
        &ints[r1][i] * &ints[r2][j] - &ints[r1][j] * &ints[r2][i]
    };
    // (columns of rows {0,1}, complementary columns of rows {2,3}, sign).
    const PAIRS: [(usize, usize, usize, usize, bool); 6] = [
        (0, 1, 2, 3, true),
        (0, 2, 1, 3, false),
        (0, 3, 1, 2, true),
        (1, 2, 0, 3, true),
        (1, 3, 0, 2, false),
        (2, 3, 0, 1, true),
    ];
    let mut det = BigInt::from(0);
    for (i, j, k, m, plus) in PAIRS {
        let t = minor(0, 1, i, j) * minor(2, 3, k, m);
        if plus {
            det += t;
        } else {
            det -= t;
        }
    }
    match det.sign() {
        num_bigint::Sign::Plus => 1,
        num_bigint::Sign::Minus => -1,
        num_bigint::Sign::NoSign => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The big-integer determinant agrees with the `f64` one where that is far from 0, and is
    /// exactly 0 for a singular matrix `f64` gets wrong.
    #[test]
    fn det4_sign_matches_f64_and_sees_exact_zero() {
        let m = [
            [1.0, 2.0, 3.0, 1.0],
            [-2.0, 0.5, 4.0, 1.0],
            [0.25, -3.0, 1.0, 1.0],
            [5.0, 1.0, -1.0, 1.0],
        ];
        let f = glam::DMat4::from_cols_array_2d(&m).determinant();
        assert_eq!(det4_sign(m), sgn(f));
        let mut swapped = m;
        swapped.swap(0, 1);
        assert_eq!(det4_sign(swapped), -sgn(f));
        // The second row is twice the first (exact in f64), so the matrix is singular; the
        // other rows span 600 binary orders of magnitude.
        let (x, y) = (0.1f64, 0.7f64);
        let s = [
            [x, y, 1.0, 1.0],
            [2.0 * x, 2.0 * y, 2.0, 2.0],
            [3.0, 4.0, 5.0, 1.0],
            [1e-300, 7.0, 1e300, 1.0],
        ];
        assert_eq!(det4_sign(s), 0);
    }

    /// `light_side` is `sgn H(a, b, c, L)`, the same determinant as `det4_sign` of its rows.
    #[test]
    fn light_side_is_h_of_the_rows() {
        let t = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        for l in [
            [0.3f32, 0.2, 2.0, 1.0],
            [0.3, 0.2, -2.0, 1.0],
            [0.0, 0.0, 1.0, 0.0],
            [1.0, 5.0, 0.0, 0.0],
            [4.0, 2.0, 3.0, 0.5],
        ] {
            let rows = [
                row(t[0].as_dvec3(), 1.0),
                row(t[1].as_dvec3(), 1.0),
                row(t[2].as_dvec3(), 1.0),
                l.map(f64::from),
            ];
            assert_eq!(light_side(t, l), det4_sign(rows), "{l:?}");
        }
    }
}
