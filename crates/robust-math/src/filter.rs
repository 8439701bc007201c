//! The pieces every certified filter is built from: the determinant and its permanent in `f64`
//! and in `f32`, the decision against a relative bound, and the input checks (subnormals, the
//! `f32` range of a difference, the `w` values for which `w * A` is exact).
//!
//! [`orient_filter_f64`](crate::orient_filter_f64) and
//! [`orient_filter_f32`](crate::orient_filter_f32) are these pieces with the crate's bounds. The
//! GPU backends' CPU twins compose the same pieces with their devices' extra guards, so the
//! arithmetic lives here once and a twin only states what its shader adds.
//!
//! Every function evaluates exactly the operations its documentation writes, in that order (Rust
//! never contracts `a * b + c`), so a shader that writes the same sequence computes the same
//! value wherever its device does not contract either.
//!
//! ```
//! use shadowvol_robust_math::filter::{certify_f64, det_perm_f64};
//! use shadowvol_robust_math::F64_FILTER_EPS;
//!
//! let (a, b, o) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
//! let light = [0.2, 0.2, 5.0, 1.0];
//! let (det, perm) = det_perm_f64(a, b, light, o);
//! assert_eq!(certify_f64(det, perm, F64_FILTER_EPS), Some(1));
//! ```

/// Smallest magnitude (other than zero) the `f32` filter accepts for differences; below it,
/// products could leave the normal `f32` range, and the filter reports "uncertain".
pub const F32_FILTER_MIN: f32 = 1.0 / 1_099_511_627_776.0; // 2^-40
/// Largest magnitude the `f32` filter accepts for differences (2^40).
pub const F32_FILTER_MAX: f32 = 1_099_511_627_776.0;

/// The sign of `x`: `1`, `-1`, or `0` for zero and NaN.
#[must_use]
#[inline]
pub fn sign_of_f64(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// The sign of `x`: `1`, `-1`, or `0` for zero and NaN.
#[must_use]
#[inline]
pub fn sign_of_f32(x: f32) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// Whether `x` is subnormal (non-zero and below `f32::MIN_POSITIVE` in magnitude), decided on
/// the bits, as a shader on a flush-to-zero device must decide it.
#[must_use]
#[inline]
pub fn is_subnormal(x: f32) -> bool {
    let u = x.to_bits();
    (u & 0x7f80_0000) == 0 && (u & 0x007f_ffff) != 0
}

/// Whether any of the 13 input components is subnormal. Devices that flush subnormals change
/// such inputs before any filter sees them, so their filters leave these inputs to the host.
#[must_use]
#[inline]
pub fn any_subnormal(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> bool {
    a.iter()
        .chain(&b)
        .chain(&o)
        .chain(&l)
        .any(|&x| is_subnormal(x))
}

/// Whether the light's `w` makes `w * A` exact in `f32`: `w` is 0 or 1. For any other `w` the
/// rounding of `w * A` is relative to `|w A|`, not to `|V|`, and no bound on the computed terms
/// covers a cancellation of `L.xyz - w A`; the `f32` filters leave those lights to the host.
#[must_use]
#[inline]
pub fn w_is_exact_f32(w: f32) -> bool {
    w == 0.0 || w == 1.0
}

/// Whether the `f32` difference `d = x - y` is acceptable to the `f32` filter: `x == y` (then the
/// exact difference is 0), or `|d|` within [`F32_FILTER_MIN`]`..=`[`F32_FILTER_MAX`], where no
/// product of two differences can leave the normal range.
///
/// Comparing `x == y` instead of testing `d == 0` also rejects a non-zero difference that a
/// flush-to-zero device computed as 0; without flushing both forms agree.
#[must_use]
#[inline]
pub fn diff_in_range(x: f32, y: f32, d: f32) -> bool {
    x == y || (F32_FILTER_MIN..=F32_FILTER_MAX).contains(&d.abs())
}

/// The translated terms of `det4(A, B, L, O)` in `f32`: `e = A - B`, `wa = L.w * A`,
/// `v = L.xyz - wa`, `d = O - A`, each component one rounded operation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TermsF32 {
    /// `A - B`.
    pub e: [f32; 3],
    /// `L.w * A`.
    pub wa: [f32; 3],
    /// `V = L.xyz - L.w * A`.
    pub v: [f32; 3],
    /// `O - A`.
    pub d: [f32; 3],
}

impl TermsF32 {
    /// The terms of `(A, B, L, O)`.
    #[must_use]
    #[inline]
    pub fn new(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Self {
        let wa = [l[3] * a[0], l[3] * a[1], l[3] * a[2]];
        Self {
            e: [a[0] - b[0], a[1] - b[1], a[2] - b[2]],
            wa,
            v: [l[0] - wa[0], l[1] - wa[1], l[2] - wa[2]],
            d: [o[0] - a[0], o[1] - a[1], o[2] - a[2]],
        }
    }

    /// Whether every difference passes [`diff_in_range`] (`a`, `l` and `o` are the inputs the
    /// terms were made from).
    #[must_use]
    #[inline]
    pub fn diffs_in_range(&self, a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> bool {
        (0..3).all(|i| {
            diff_in_range(a[i], b[i], self.e[i])
                && diff_in_range(l[i], self.wa[i], self.v[i])
                && diff_in_range(o[i], a[i], self.d[i])
        })
    }

    /// The determinant and its permanent in `f32`:
    ///
    /// ```text
    /// (p1, q1) = (ey*vz, ez*vy); (p2, q2) = (ez*vx, ex*vz); (p3, q3) = (ex*vy, ey*vx)
    /// det  = ((p1 - q1)*dx + (p2 - q2)*dy) + (p3 - q3)*dz
    /// perm = ((|p1| + |q1|)*|dx| + (|p2| + |q2|)*|dy|) + (|p3| + |q3|)*|dz|
    /// ```
    #[must_use]
    #[inline]
    pub fn det_perm(&self) -> (f32, f32) {
        let (e, v, d) = (self.e, self.v, self.d);
        let (p1, q1) = (e[1] * v[2], e[2] * v[1]);
        let (p2, q2) = (e[2] * v[0], e[0] * v[2]);
        let (p3, q3) = (e[0] * v[1], e[1] * v[0]);
        let perm = ((p1.abs() + q1.abs()) * d[0].abs() + (p2.abs() + q2.abs()) * d[1].abs())
            + (p3.abs() + q3.abs()) * d[2].abs();
        (self.det(), perm)
    }

    /// The determinant alone, `((A - B) x V) . (O - A)`, with the operations of
    /// [`det_perm`](Self::det_perm): `((p1 - q1)*dx + (p2 - q2)*dy) + (p3 - q3)*dz`.
    #[must_use]
    #[inline]
    pub fn det(&self) -> f32 {
        let (e, v, d) = (self.e, self.v, self.d);
        let n = [
            e[1] * v[2] - e[2] * v[1],
            e[2] * v[0] - e[0] * v[2],
            e[0] * v[1] - e[1] * v[0],
        ];
        (n[0] * d[0] + n[1] * d[1]) + n[2] * d[2]
    }
}

/// The determinant `det4(A, B, L, O)` and its permanent evaluated in `f64` from the `f32`
/// inputs (each conversion and each product `L.w * A` exact), with the same operations as
/// [`TermsF32::det_perm`].
#[must_use]
#[inline]
pub fn det_perm_f64(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> (f64, f64) {
    let (ax, ay, az) = (f64::from(a[0]), f64::from(a[1]), f64::from(a[2]));
    let lw = f64::from(l[3]);
    let ex = ax - f64::from(b[0]);
    let ey = ay - f64::from(b[1]);
    let ez = az - f64::from(b[2]);
    let vx = f64::from(l[0]) - lw * ax;
    let vy = f64::from(l[1]) - lw * ay;
    let vz = f64::from(l[2]) - lw * az;
    let dx = f64::from(o[0]) - ax;
    let dy = f64::from(o[1]) - ay;
    let dz = f64::from(o[2]) - az;
    let (p1, q1) = (ey * vz, ez * vy);
    let (p2, q2) = (ez * vx, ex * vz);
    let (p3, q3) = (ex * vy, ey * vx);
    let det = ((p1 - q1) * dx + (p2 - q2) * dy) + (p3 - q3) * dz;
    let perm = ((p1.abs() + q1.abs()) * dx.abs() + (p2.abs() + q2.abs()) * dy.abs())
        + (p3.abs() + q3.abs()) * dz.abs();
    (det, perm)
}

/// The certified sign of a determinant computed as `det` with permanent `perm` and relative
/// error at most `eps * perm`: its sign when `|det| > eps * perm`, 0 when `perm == 0` (every
/// term vanished exactly), `None` (uncertain) otherwise.
#[must_use]
#[inline]
pub fn certify_f64(det: f64, perm: f64, eps: f64) -> Option<i8> {
    if det.abs() > eps * perm {
        Some(sign_of_f64(det))
    } else if perm == 0.0 {
        Some(0)
    } else {
        None
    }
}

/// [`certify_f64`] in `f32`.
#[must_use]
#[inline]
pub fn certify_f32(det: f32, perm: f32, eps: f32) -> Option<i8> {
    if det.abs() > eps * perm {
        Some(sign_of_f32(det))
    } else if perm == 0.0 {
        Some(0)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subnormals_are_found_on_the_bits() {
        for x in [
            f32::MIN_POSITIVE / 2.0,
            -f32::from_bits(1),
            f32::from_bits(0x007f_ffff),
        ] {
            assert!(is_subnormal(x), "{x:e}");
        }
        for x in [0.0, -0.0, f32::MIN_POSITIVE, 1.0, f32::INFINITY, f32::NAN] {
            assert!(!is_subnormal(x), "{x:e}");
        }
        let tiny = f32::from_bits(1);
        assert!(any_subnormal(
            [0.0; 3],
            [0.0; 3],
            [0.0, 0.0, 0.0, tiny],
            [0.0; 3]
        ));
        assert!(!any_subnormal(
            [1.0; 3],
            [0.0; 3],
            [0.0, 0.0, 0.0, 1.0],
            [2.0; 3]
        ));
    }

    #[test]
    fn range_of_a_difference() {
        assert!(diff_in_range(3.0, 3.0, 0.0));
        assert!(diff_in_range(3.0, 2.0, 1.0));
        assert!(
            !diff_in_range(3.0, 2.0, 0.0),
            "a flushed non-zero difference"
        );
        assert!(!diff_in_range(1e30, -1e30, 2e30));
        assert!(!diff_in_range(1e-20, 0.0, 1e-20));
        assert!(diff_in_range(F32_FILTER_MAX, 0.0, F32_FILTER_MAX));
        assert!(diff_in_range(F32_FILTER_MIN, 0.0, F32_FILTER_MIN));
    }

    #[test]
    fn det_and_perm_agree_between_f32_and_f64_on_exact_inputs() {
        // Small integers: every operation is exact in both precisions.
        let (a, b, l, o) = (
            [1.0, 2.0, 3.0],
            [4.0, -1.0, 2.0],
            [5.0, 7.0, -2.0, 1.0],
            [0.0, 3.0, 1.0],
        );
        let (d32, p32) = TermsF32::new(a, b, l, o).det_perm();
        let (d64, p64) = det_perm_f64(a, b, l, o);
        assert_eq!((f64::from(d32), f64::from(p32)), (d64, p64));
        // ((A - B) x V) . (O - A) written out: e = (-3, 3, 1), v = (4, 5, -5), d = (-1, 1, -2).
        let n = [
            3.0 * -5.0 - 1.0 * 5.0,
            1.0 * 4.0 - -3.0 * -5.0,
            -3.0 * 5.0 - 3.0 * 4.0,
        ];
        assert_eq!(d64, -n[0] + n[1] - 2.0 * n[2]);
        assert!(p64 >= d64.abs());
    }

    #[test]
    fn certify_decides_only_beyond_the_bound() {
        assert_eq!(certify_f64(1.0, 1.0, 0.5), Some(1));
        assert_eq!(certify_f64(-1.0, 1.0, 0.5), Some(-1));
        assert_eq!(certify_f64(0.5, 1.0, 0.5), None);
        assert_eq!(certify_f64(0.0, 0.0, 0.5), Some(0));
        assert_eq!(certify_f64(0.0, 1.0, 0.5), None);
        assert_eq!(certify_f32(2.0, 3.0, 0.5), Some(1));
        assert_eq!(certify_f32(-1.5, 3.0, 0.5), None);
        assert_eq!(certify_f32(0.0, 0.0, 0.5), Some(0));
        assert!(w_is_exact_f32(0.0) && w_is_exact_f32(1.0) && !w_is_exact_f32(0.5));
    }
}
