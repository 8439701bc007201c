//! The exact sign of the orientation determinant.
//!
//! `det4(A, B, L, O) = | A 1 ; B 1 ; L ; O 1 |` equals `((A - B) x V) . (O - A)` with
//! `V = L.xyz - L.w * A` (see the crate documentation). For `f32` inputs it is decided in two steps:
//!
//! 1. [`orient_filter_f64`]: the translated formula evaluated in `f64` with a forward error bound
//!    computed from the absolute values of the same terms (a semi-static filter). It certifies the
//!    sign, or says it cannot.
//! 2. [`orient_exact_expansion`]: Laplace expansion of the 4x4 determinant into six products of
//!    2x2 minors. Every minor is a difference of two products of two `f32` values, which `f64`
//!    holds exactly, so a minor is an exact 2-term expansion; the products of minors are expanded
//!    with Dekker's error-free product and summed with Shewchuk's error-free expansion growth.
//!
//! # Why no overflow or underflow can occur
//! Every finite `f32` is an integer multiple of 2^-149 below 2^128. Products of two are multiples
//! of 2^-298 below 2^256, minors are below 2^257, and products of two minors are multiples of
//! 2^-596 below 2^514. All of these, and every error term of the error-free transformations
//! applied to them, lie in the normal `f64` range (2^-1022 .. 2^1024), so every step is exact.

/// Relative error constant of [`orient_filter_f64`]: the computed value differs from the exact
/// determinant by at most `gamma_8 * P` for the permanent `P`, plus the rounding of `P` itself;
/// `9u` covers it (`8u (1 + 16u)` suffices), and `1e-15 > 9u`.
pub const F64_FILTER_EPS: f64 = 1.0e-15;

/// Relative error constant of [`orient_filter_f32`]: with `w` in `{0, 1}` (`w * A` exact), every
/// term passes through at most 8 roundings in `f32` (the three differences, the product, the
/// 2x2 minor, the product with `O - A`, two sums), so the error is below `gamma_8 * P` (about
/// `8 * 2^-24` times the permanent `P`), plus the roundings of `P`; we use `32 * 2^-24 = 2^-19`,
/// a safety factor of about 4 that also absorbs FMA contraction and reassociation on GPUs
/// (neither adds roundings along any path). Underflow cannot hurt: the range checks keep every
/// non-zero product of two differences at or above 2^-80 and the permanent, when non-zero, at or
/// above 2^-120, far above the absolute error (a few 2^-150) of a subnormal last product.
pub const F32_FILTER_EPS: f32 = 1.0 / 524_288.0;

use crate::filter::{
    certify_f32, certify_f64, det_perm_f64, sign_of_f64, w_is_exact_f32, TermsF32,
};

/// Certified `f64` filter for `sgn det4(A, B, L, O)`.
///
/// Returns `Some(sign)` when the sign is proven, `None` when `|det|` is within the error bound
/// (the caller must then use [`orient_exact_expansion`]). Exact zeros are certified when every
/// term vanishes (for example axis-aligned geometry with a light on an axis).
///
/// It is [`det_perm_f64`] decided by [`certify_f64`] with [`F64_FILTER_EPS`].
///
/// Inputs must be finite; this holds for every [`crate::Light`] and validated mesh.
#[must_use]
#[inline]
pub fn orient_filter_f64(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Option<i8> {
    let (det, perm) = det_perm_f64(a, b, l, o);
    certify_f64(det, perm, F64_FILTER_EPS)
}

/// Certified `f32` filter for `sgn det4(A, B, L, O)`: the CPU twin of the filter used by shaders
/// without `f64`.
///
/// Evaluates the same formula as [`orient_filter_f64`] in `f32` ([`TermsF32`]). It returns
/// `None` (uncertain) when
/// * the light's `w` is neither 0 nor 1 ([`w_is_exact_f32`]: only then is `w * A` exact in
///   `f32`; otherwise its rounding is not bounded relative to `V = L.xyz - w A`, which may cancel
///   to 0),
/// * a non-zero difference (`A - B`, `V`, `O - A`) lies outside
///   `[F32_FILTER_MIN, F32_FILTER_MAX]` (where products could underflow or overflow),
/// * the permanent is not finite,
/// * or `|det| <= F32_FILTER_EPS * P` for the permanent `P` of the same terms ([`certify_f32`]).
///
/// Shader ports must keep every one of these checks (the `w` check included). On
/// flush-to-zero hardware, subnormal inputs are flushed before this function would see them;
/// the range check on the differences then still holds for the flushed values, but the
/// certified sign is about the flushed inputs, so such devices must route subnormal inputs to
/// the host.
#[must_use]
#[inline]
pub fn orient_filter_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Option<i8> {
    if !w_is_exact_f32(l[3]) {
        return None;
    }
    let t = TermsF32::new(a, b, l, o);
    if !t.diffs_in_range(a, b, l, o) {
        return None;
    }
    let (det, perm) = t.det_perm();
    if !perm.is_finite() {
        return None;
    }
    certify_f32(det, perm, F32_FILTER_EPS)
}

// ---- error-free transformations -------------------------------------------------------------

#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    let err = (a - (s - bb)) + (b - bb);
    (s, err)
}

/// Veltkamp split for Dekker's product; exact for |a| < 2^996, which always holds here.
#[inline]
fn split(a: f64) -> (f64, f64) {
    const SPLITTER: f64 = 134_217_729.0; // 2^27 + 1
    let c = SPLITTER * a;
    let hi = c - (c - a);
    (hi, a - hi)
}

#[inline]
fn two_product(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    let err = al * bl - (((p - ah * bh) - al * bh) - ah * bl);
    (p, err)
}

/// Fixed-capacity expansion: non-overlapping components in increasing magnitude, zeros removed.
///
/// [`orient_exact_expansion`] grows it by 48 values and each growth adds at most one component,
/// so 64 slots always suffice.
struct Expansion {
    c: [f64; 64],
    n: usize,
}

impl Expansion {
    fn new() -> Self {
        Self { c: [0.0; 64], n: 0 }
    }

    /// Shewchuk's GROW-EXPANSION with zero elimination: adds one `f64` exactly.
    fn grow(&mut self, b: f64) {
        if b == 0.0 {
            return;
        }
        let mut q = b;
        let mut out = 0;
        for i in 0..self.n {
            let (s, h) = two_sum(q, self.c[i]);
            q = s;
            if h != 0.0 {
                self.c[out] = h;
                out += 1;
            }
        }
        if q != 0.0 {
            self.c[out] = q;
            out += 1;
        }
        self.n = out;
    }

    fn sign(&self) -> i8 {
        // The largest component (last) carries the sign of a non-overlapping expansion.
        (0..self.n)
            .rev()
            .map(|i| sign_of_f64(self.c[i]))
            .find(|&s| s != 0)
            .unwrap_or(0)
    }
}

/// A 2x2 minor `p - q` of exact products, as a 2-term expansion `(hi, lo)`.
#[inline]
fn minor(a: f64, d: f64, b: f64, c: f64) -> (f64, f64) {
    // a*d and b*c are products of two f32 values: exact in f64.
    two_sum(a * d, -(b * c))
}

/// Exact sign of `det4(A, B, L, O)` by expansion arithmetic, for any finite `f32` inputs.
///
/// Slower than the filter (a few hundred flops); see the module documentation for the method and
/// why it is exact.
#[must_use]
pub fn orient_exact_expansion(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i8 {
    let r1 = [f64::from(a[0]), f64::from(a[1]), f64::from(a[2]), 1.0];
    let r2 = [f64::from(b[0]), f64::from(b[1]), f64::from(b[2]), 1.0];
    let r3 = [
        f64::from(l[0]),
        f64::from(l[1]),
        f64::from(l[2]),
        f64::from(l[3]),
    ];
    let r4 = [f64::from(o[0]), f64::from(o[1]), f64::from(o[2]), 1.0];
    // Laplace expansion along rows {1,2} / {3,4}:
    // det = sum over column pairs (i<j) of (-1)^(1+2+i+j) * M12(i,j) * M34(complement).
    const PAIRS: [(usize, usize, usize, usize, f64); 6] = [
        (0, 1, 2, 3, 1.0),
        (0, 2, 1, 3, -1.0),
        (0, 3, 1, 2, 1.0),
        (1, 2, 0, 3, 1.0),
        (1, 3, 0, 2, -1.0),
        (2, 3, 0, 1, 1.0),
    ];
    let mut acc = Expansion::new();
    for (i, j, k, m, sign) in PAIRS {
        let (h1, l1) = minor(r1[i], r2[j], r1[j], r2[i]);
        let (h2, l2) = minor(r3[k], r4[m], r3[m], r4[k]);
        for (x, y) in [(h1, h2), (h1, l2), (l1, h2), (l1, l2)] {
            let (p, e) = two_product(x, y);
            acc.grow(sign * e);
            acc.grow(sign * p);
        }
    }
    acc.sign()
}

/// Exact sign of `det4(A, B, L, O)`: the `f64` filter, then the expansion fallback.
///
/// Correct for every finite `f32` input, any `w` (directional lights, `w = 1` and general
/// homogeneous `w`), subnormals and values up to `f32::MAX` included. Never panics; for NaN or
/// infinite inputs (which [`crate::Light`] and a validated mesh exclude) the result is
/// unspecified.
#[must_use]
#[inline]
pub fn orient_exact(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i8 {
    orient_filter_f64(a, b, l, o).unwrap_or_else(|| orient_exact_expansion(a, b, l, o))
}
