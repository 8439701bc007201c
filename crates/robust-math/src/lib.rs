//! Robust arithmetic for silhouette shadow volumes.
//!
//! # Convention
//! A light is `L = (x, y, z, w)` ([`Light`]). For an edge `(a, b)` with `a < b`, positions
//! `A = P[a]`, `B = P[b]` and an opposite vertex `O`:
//!
//! ```text
//! V = L.xyz - L.w * A
//! s(a, b, o) = sgn( ((A - B) x V) . (O - A) ) = sgn det4 | A 1 ; B 1 ; L ; O 1 |
//! m(a, b)    = sum over opposite vertices o of s(a, b, o)
//! ```
//!
//! The determinant changes sign under an odd permutation of the triangle `(A, B, O)` and keeps it
//! under an even one, so exact signs of the three edges of a triangle always agree and the
//! silhouette is a closed chain. Floating-point evaluation may disagree; the [`Accuracy`] modes
//! differ in how they deal with that:
//!
//! | mode | per (edge, OV) | consistent |
//! |---|---|---|
//! | [`Accuracy::Original`] | one `f32` evaluation ([`sign_f32`]) of the paper's plane test on its own | no |
//! | [`Accuracy::Robust`] | three `f32` evaluations (all sides of the triangle) in the triangle's canonical order; 0 if they disagree | yes |
//! | [`Accuracy::Ordered`] | one `f32` evaluation in the canonical order, times the permutation parity | yes |
//! | [`Accuracy::Exact`] | the exact sign ([`orient_exact`]) | yes, and correct |
//!
//! The canonical order of a triangle is its vertex ids sorted ascending.
//!
//! [`LightBox`] decides, exactly, the sign a triangle shares with every light of a box (a light's
//! samples): see [`light_box`].
//!
//! ```
//! use shadowvol_robust_math::{ov_sign, Accuracy, Light};
//! use glam::Vec3;
//!
//! let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
//! let light = Light::point(Vec3::new(0.2, 0.2, 5.0));
//! // Edge (0, 1) with opposite vertex 2: the light is above the triangle.
//! let s = ov_sign(Accuracy::Exact, &p, 0, 1, 2, light.to_array());
//! assert_eq!(s, ov_sign(Accuracy::Robust, &p, 0, 1, 2, light.to_array()));
//! assert_eq!(s.abs(), 1);
//! ```

mod exact;
pub mod filter;
mod light;
pub mod light_box;

pub use exact::{
    orient_exact, orient_exact_expansion, orient_filter_f32, orient_filter_f64, F32_FILTER_EPS,
    F64_FILTER_EPS,
};
pub use filter::{F32_FILTER_MAX, F32_FILTER_MIN};
pub use light::{Light, LightError};
pub use light_box::{box_sign_f32, BoxFilter, DeviceBox, LightBox, BOX_FILTER_EPS};

use glam::Vec3;

/// How the sign `s(a, b, o)` is evaluated. See the crate documentation for the table.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Accuracy {
    /// Kim et al. 2008 as stated: each (edge, OV) evaluated on its own in `f32`. Can crack.
    Original,
    /// Pečiva et al. 2013: all three sides of the triangle in `f32`; disagreeing triangles count 0.
    Robust,
    /// One `f32` evaluation per triangle in canonical vertex order (1/3 of robust's work).
    Ordered,
    /// The exact sign of the determinant.
    Exact,
}

impl Accuracy {
    /// All modes, in the order used by tables.
    pub const ALL: [Accuracy; 4] = [
        Accuracy::Original,
        Accuracy::Robust,
        Accuracy::Ordered,
        Accuracy::Exact,
    ];

    /// The lower-case name used on the command line and in JSON.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Accuracy::Original => "original",
            Accuracy::Robust => "robust",
            Accuracy::Ordered => "ordered",
            Accuracy::Exact => "exact",
        }
    }

    /// True for the modes whose triangles always agree with themselves (closed chains).
    #[must_use]
    pub fn is_consistent(self) -> bool {
        self != Accuracy::Original
    }
}

impl std::fmt::Display for Accuracy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Error for an unknown accuracy-mode name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown accuracy mode {0:?}; expected one of: original, robust, ordered, exact")]
pub struct UnknownAccuracy(pub String);

impl std::str::FromStr for Accuracy {
    type Err = UnknownAccuracy;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "original" => Ok(Accuracy::Original),
            "robust" => Ok(Accuracy::Robust),
            "ordered" => Ok(Accuracy::Ordered),
            "exact" => Ok(Accuracy::Exact),
            _ => Err(UnknownAccuracy(s.to_owned())),
        }
    }
}

/// The `f32` evaluation of `s(a, b, o)`: the paper's eq. (1)-(2) without the normalisation,
/// evaluated as `N·(O − A)` (the convention's formula above).
///
/// The paper writes the light plane as `LP = (N, −N·A)` and tests `LP·(O, 1) = N·O − N·A`. That
/// is the same number in exact arithmetic, but in `f32` the two dot products cancel: 10⁴ from the
/// origin each is about 10⁴·|N| while their difference may be 10⁻¹·|N|·cos φ, so rounding
/// decides the sign of every triangle the light grazes (in `hard-offset-1e4-*` every mode, the
/// consistent ones included, then disagreed with `exact` on hundreds of edges). `O − A` is exact
/// for nearby points (Sterbenz), so the error stays relative to the triangle's own size. Both
/// forms cost the same (`N·A` shared by the OVs of an edge against one subtraction per OV).
///
/// Exactly this sequence of `f32` operations (no fused multiply-add; Rust never contracts):
///
/// ```text
/// v = (lx - lw*ax, ly - lw*ay, lz - lw*az)
/// e = (ax - bx, ay - by, az - bz)
/// n = (ey*vz - ez*vy, ez*vx - ex*vz, ex*vy - ey*vx)        // (A - B) x V
/// d = (ox - ax, oy - ay, oz - az)
/// s = sgn( (nx*dx + ny*dy) + nz*dz )                       // N . (O - A)
/// ```
///
/// GPU kernels implement the same expression; there, contraction may change the last bits, which
/// is why only [`Accuracy::Exact`] is required to be bit-identical across backends.
#[must_use]
#[inline]
pub fn sign_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i8 {
    filter::sign_of_f32(filter::TermsF32::new(a, b, l, o).det())
}

/// The sign of a whole triangle `(p0, p1, p2)`, given in canonical order (ascending ids), in the
/// `f32` modes:
///
/// * [`Accuracy::Robust`]: `s(p0,p1,p2)`, `s(p1,p2,p0)`, `s(p2,p0,p1)`; their common value, or 0
///   if they disagree;
/// * [`Accuracy::Ordered`] and [`Accuracy::Original`]: `s(p0,p1,p2)`;
/// * [`Accuracy::Exact`]: the exact sign.
#[must_use]
#[inline]
pub fn triangle_sign(mode: Accuracy, p0: Vec3, p1: Vec3, p2: Vec3, l: [f32; 4]) -> i8 {
    let (p0, p1, p2) = (p0.to_array(), p1.to_array(), p2.to_array());
    match mode {
        Accuracy::Robust => {
            let s0 = sign_f32(p0, p1, l, p2);
            let s1 = sign_f32(p1, p2, l, p0);
            let s2 = sign_f32(p2, p0, l, p1);
            if s0 == s1 && s1 == s2 {
                s0
            } else {
                0
            }
        }
        Accuracy::Ordered | Accuracy::Original => sign_f32(p0, p1, l, p2),
        Accuracy::Exact => orient_exact(p0, p1, l, p2),
    }
}

/// Sorts a triangle `(a, b, o)` with `a < b` into canonical order and returns it with the parity
/// of the permutation: `+1` when `o < a` or `o > b` (even), `-1` when `a < o < b` (odd).
///
/// # Panics
/// Debug builds assert `a < b` and `o ∉ {a, b}`.
#[must_use]
#[inline]
pub fn canonical(a: u32, b: u32, o: u32) -> ([u32; 3], i8) {
    debug_assert!(a < b && o != a && o != b);
    if o > b {
        ([a, b, o], 1)
    } else if o < a {
        ([o, a, b], 1)
    } else {
        ([a, o, b], -1)
    }
}

/// The contribution `s(a, b, o)` of opposite vertex `o` to the multiplicity of edge `(a, b)`,
/// `a < b`, in the given mode. `positions` is indexed by the same ids.
///
/// * `Original`: [`sign_f32`]`(A, B, L, O)`.
/// * `Robust`, `Ordered`: [`triangle_sign`] on the canonical triangle, times the parity.
/// * `Exact`: [`orient_exact`]`(A, B, L, O)` (equal to the canonical form by the permutation rule).
///
/// # Panics
/// Panics if an id is out of range of `positions`.
#[must_use]
#[inline]
pub fn ov_sign(mode: Accuracy, positions: &[Vec3], a: u32, b: u32, o: u32, l: [f32; 4]) -> i8 {
    let p = |i: u32| positions[i as usize];
    match mode {
        Accuracy::Original => sign_f32(p(a).to_array(), p(b).to_array(), l, p(o).to_array()),
        Accuracy::Exact => orient_exact(p(a).to_array(), p(b).to_array(), l, p(o).to_array()),
        Accuracy::Robust | Accuracy::Ordered => {
            let ([i0, i1, i2], parity) = canonical(a, b, o);
            triangle_sign(mode, p(i0), p(i1), p(i2), l) * parity
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_matches_filter_on_easy_input() {
        let a = [0.0, 0.0, 0.0];
        let b = [1.0, 0.0, 0.0];
        let o = [0.0, 1.0, 0.0];
        let l = [0.3, 0.3, 2.0, 1.0];
        let f = orient_filter_f64(a, b, l, o).unwrap();
        assert_eq!(f, orient_exact_expansion(a, b, l, o));
        assert_eq!(f, sign_f32(a, b, l, o));
        // Light exactly in the plane: exactly zero.
        let l0 = [0.3, 0.3, 0.0, 1.0];
        assert_eq!(orient_exact(a, b, l0, o), 0);
        assert_eq!(orient_exact_expansion(a, b, l0, o), 0);
    }

    #[test]
    fn parity_rule() {
        assert_eq!(canonical(1, 3, 5), ([1, 3, 5], 1));
        assert_eq!(canonical(1, 3, 0), ([0, 1, 3], 1));
        assert_eq!(canonical(1, 3, 2), ([1, 2, 3], -1));
    }

    #[test]
    fn mode_names_parse_back_and_consistency() {
        let names = Accuracy::ALL.map(Accuracy::name);
        assert_eq!(names, ["original", "robust", "ordered", "exact"]);
        for m in Accuracy::ALL {
            assert_eq!(m.name().parse::<Accuracy>(), Ok(m));
            assert_eq!(m.to_string(), m.name());
            assert_eq!(m.is_consistent(), m != Accuracy::Original);
        }
        assert_eq!(" ROBUST ".parse::<Accuracy>(), Ok(Accuracy::Robust));
        assert!("fast".parse::<Accuracy>().is_err());
    }

    #[test]
    fn light_accessors_and_text() {
        let p = Light::new(1.0, 2.0, 3.0, 1.0).unwrap();
        let d = Light::new(0.0, 0.0, -1.5, 0.0).unwrap();
        assert!(!p.is_directional() && d.is_directional());
        assert_eq!(p.to_vec4(), glam::Vec4::new(1.0, 2.0, 3.0, 1.0));
        assert_eq!(<[f32; 4]>::from(d), [0.0, 0.0, -1.5, 0.0]);
        assert_eq!(d.to_string(), "0,0,-1.5,0");
        assert_eq!(d.to_string().parse::<Light>().unwrap(), d);
    }

    #[test]
    fn light_parse_errors() {
        assert!("1,2,3".parse::<Light>().is_err());
        assert!("1,2,x,1".parse::<Light>().is_err());
        assert!("1,2,3,-1".parse::<Light>().is_err());
        assert!("0,0,0,0".parse::<Light>().is_err());
        assert_eq!(
            "1, 2, 3, 1".parse::<Light>().unwrap().to_array(),
            [1., 2., 3., 1.]
        );
    }
}

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
