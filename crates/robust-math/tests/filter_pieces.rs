//! The filter's pieces (`shadowvol_robust_math::filter`) against integer arithmetic written
//! here: on small integer inputs every `f32` and `f64` operation of the filters is exact, so the
//! determinant must equal the Leibniz 4x4 determinant in `i64` and the permanent the documented
//! sum of absolute products in `i64`, bit for bit.

use proptest::prelude::*;
use shadowvol_robust_math::filter::{
    certify_f32, certify_f64, det_perm_f64, diff_in_range, sign_of_f32, sign_of_f64, TermsF32,
};
use shadowvol_robust_math::{F32_FILTER_MAX, F32_FILTER_MIN};

type P3 = [f32; 3];
type L4 = [f32; 4];

/// The 4x4 determinant of the rows `(A, 1), (B, 1), (L.xyz, L.w), (O, 1)` by the Leibniz
/// formula (24 signed products).
fn det4_leibniz(a: [i64; 3], b: [i64; 3], l: [i64; 4], o: [i64; 3]) -> i64 {
    let m = [
        [a[0], a[1], a[2], 1],
        [b[0], b[1], b[2], 1],
        [l[0], l[1], l[2], l[3]],
        [o[0], o[1], o[2], 1],
    ];
    let mut sum = 0;
    for p0 in 0..4 {
        for p1 in 0..4 {
            for p2 in 0..4 {
                for p3 in 0..4 {
                    let p = [p0, p1, p2, p3];
                    if (0..4).any(|i| (i + 1..4).any(|j| p[i] == p[j])) {
                        continue;
                    }
                    let inversions = (0..4)
                        .map(|i| (i + 1..4).filter(|&j| p[i] > p[j]).count())
                        .sum::<usize>();
                    let sign = if inversions % 2 == 0 { 1 } else { -1 };
                    sum += sign * m[0][p0] * m[1][p1] * m[2][p2] * m[3][p3];
                }
            }
        }
    }
    sum
}

/// The permanent as documented: with `e = A - B`, `v = L.xyz - L.w A`, `d = O - A`,
/// `(|ey vz| + |ez vy|) |dx| + (|ez vx| + |ex vz|) |dy| + (|ex vy| + |ey vx|) |dz|`.
fn perm_int(a: [i64; 3], b: [i64; 3], l: [i64; 4], o: [i64; 3]) -> i64 {
    let e = [0, 1, 2].map(|i| a[i] - b[i]);
    let v = [0, 1, 2].map(|i| l[i] - l[3] * a[i]);
    let d = [0, 1, 2].map(|i| o[i] - a[i]);
    (e[1] * v[2]).abs() * d[0].abs()
        + (e[2] * v[1]).abs() * d[0].abs()
        + (e[2] * v[0]).abs() * d[1].abs()
        + (e[0] * v[2]).abs() * d[1].abs()
        + (e[0] * v[1]).abs() * d[2].abs()
        + (e[1] * v[0]).abs() * d[2].abs()
}

fn to_f32<const N: usize>(x: [i64; N]) -> [f32; N] {
    x.map(|c| c as f32)
}

/// Checks both evaluations on one integer input; every intermediate stays below 2^24.
fn check_int(a: [i64; 3], b: [i64; 3], l: [i64; 4], o: [i64; 3]) {
    let (det, perm) = (det4_leibniz(a, b, l, o), perm_int(a, b, l, o));
    assert!(perm < 1 << 24, "keep every value exact in f32");
    let (fa, fb, fl, fo) = (to_f32(a), to_f32(b), to_f32(l), to_f32(o));
    let input = format!("A {a:?}, B {b:?}, L {l:?}, O {o:?}");
    assert_eq!(
        det_perm_f64(fa, fb, fl, fo),
        (det as f64, perm as f64),
        "f64: {input}"
    );
    let terms = TermsF32::new(fa, fb, fl, fo);
    assert_eq!(terms.det_perm(), (det as f32, perm as f32), "f32: {input}");
    assert_eq!(terms.det(), det as f32, "f32 det alone: {input}");
    // The terms themselves: e = A - B, wa = w A, v = L.xyz - w A, d = O - A.
    for i in 0..3 {
        assert_eq!(terms.e[i], (a[i] - b[i]) as f32, "{input}");
        assert_eq!(terms.wa[i], (l[3] * a[i]) as f32, "{input}");
        assert_eq!(terms.v[i], (l[i] - l[3] * a[i]) as f32, "{input}");
        assert_eq!(terms.d[i], (o[i] - a[i]) as f32, "{input}");
    }
}

#[test]
fn det_and_perm_of_fixed_integer_inputs() {
    // A point light above a unit right triangle in z = 0: det = -5 (det4 of the rows).
    check_int([0, 0, 0], [1, 0, 0], [0, 0, 5, 1], [0, 1, 0]);
    // Every component different and non-zero, a directional light and a w = 3 light.
    check_int([1, 2, 3], [4, -1, 2], [5, 7, -2, 1], [0, 3, 1]);
    check_int([-3, 5, 2], [7, 1, -4], [2, -6, 9, 0], [4, 4, -7]);
    check_int([2, -1, 3], [-5, 6, 1], [9, 3, -8, 3], [6, -2, -4]);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn prop_det_and_perm_are_exact_on_small_integers(
        a in proptest::array::uniform3(-24i64..=24),
        b in proptest::array::uniform3(-24i64..=24),
        o in proptest::array::uniform3(-24i64..=24),
        l in proptest::array::uniform3(-24i64..=24),
        w in -3i64..=3,
    ) {
        check_int(a, b, [l[0], l[1], l[2], w], o);
    }
}

#[test]
fn signs_of_zero_nan_and_extremes() {
    for (x, s) in [
        (0.0, 0),
        (-0.0, 0),
        (f64::NAN, 0),
        (f64::from_bits(1), 1),
        (-f64::from_bits(1), -1),
        (1.0, 1),
        (-2.5, -1),
        (f64::INFINITY, 1),
        (f64::NEG_INFINITY, -1),
    ] {
        assert_eq!(sign_of_f64(x), s, "{x:e}");
        #[allow(clippy::cast_possible_truncation)]
        let y = x as f32;
        let s32 = if x != 0.0 && y == 0.0 { 0 } else { s };
        assert_eq!(sign_of_f32(y), s32, "{y:e}");
    }
    assert_eq!(sign_of_f32(f32::from_bits(1)), 1);
    assert_eq!(sign_of_f32(-f32::from_bits(1)), -1);
}

#[test]
fn certify_at_the_bound_and_with_a_vanished_permanent() {
    // |det| must be strictly above eps * perm (all values exact in binary); at equality, or
    // with det 0 and a non-zero permanent, the sign is uncertain; a permanent of 0 means 0.
    let table: [(f64, f64, f64, Option<i8>); 11] = [
        (3.0, 4.0, 0.75, None),
        (3.0, 4.0, 0.5, Some(1)),
        (-3.0, 4.0, 0.5, Some(-1)),
        (-3.0, 4.0, 0.75, None),
        (0.0, 4.0, 0.5, None),
        (0.0, 0.0, 0.5, Some(0)),
        (-0.0, 0.0, 0.5, Some(0)),
        (2.0, 8.0, 0.125, Some(1)),
        (1.0, 8.0, 0.125, None),
        (-1.0, 8.0, 0.125, None),
        (5.0, 4.0, 1.0, Some(1)),
    ];
    for (det, perm, eps, want) in table {
        assert_eq!(certify_f64(det, perm, eps), want, "f64 {det} {perm} {eps}");
        #[allow(clippy::cast_possible_truncation)]
        let (d, p, e) = (det as f32, perm as f32, eps as f32);
        assert_eq!(certify_f32(d, p, e), want, "f32 {d} {p} {e}");
    }
    // A tiny non-zero permanent is not zero.
    assert_eq!(certify_f64(1e-300, 1e-300, 1.0), None);
    assert_eq!(certify_f64(1e-300, 1e-300, 0.5), Some(1));
    assert_eq!(certify_f32(1e-30, 1e-30, 1.0), None);
    assert_eq!(certify_f32(-1e-30, 1e-30, 0.5), Some(-1));
}

/// The range rule written here: `x == y`, or `|d|` within `F32_FILTER_MIN..=F32_FILTER_MAX`.
fn in_range(x: f32, y: f32, d: f32) -> bool {
    x == y || (d.abs() >= F32_FILTER_MIN && d.abs() <= F32_FILTER_MAX)
}

#[test]
fn one_difference_out_of_range_fails_the_whole_input() {
    let (a, b, l, o): (P3, P3, L4, P3) = (
        [0.0, 2.0, 3.0],
        [4.0, -1.0, 2.0],
        [5.0, 7.0, -2.0, 1.0],
        [0.0, 3.0, 1.0],
    );
    assert!(TermsF32::new(a, b, l, o).diffs_in_range(a, b, l, o));
    let huge = F32_FILTER_MAX * 4.0;
    let mut cases = vec![];
    for i in 0..3 {
        // Only e_i out of range (B moved), only v_i (L moved), only d_i (O moved).
        let (mut b2, mut l2, mut o2) = (b, l, o);
        b2[i] = -huge;
        l2[i] = huge;
        o2[i] = huge;
        cases.extend([(b2, l, o, "e"), (b, l2, o, "v"), (b, l, o2, "d")].map(|c| (i, c)));
    }
    // A non-zero difference below the range: B.x next to A.x = 0.
    let mut b_tiny = b;
    b_tiny[0] = F32_FILTER_MIN / 4.0;
    cases.push((0, (b_tiny, l, o, "e (tiny)")));
    for (i, (b, l, o, what)) in cases {
        let t = TermsF32::new(a, b, l, o);
        let ok = [0, 1, 2].map(|k| {
            [
                in_range(a[k], b[k], t.e[k]),
                in_range(l[k], t.wa[k], t.v[k]),
                in_range(o[k], a[k], t.d[k]),
            ]
        });
        for k in 0..3 {
            let crate_rule = [
                diff_in_range(a[k], b[k], t.e[k]),
                diff_in_range(l[k], t.wa[k], t.v[k]),
                diff_in_range(o[k], a[k], t.d[k]),
            ];
            assert_eq!(crate_rule, ok[k], "{what}{i}, component {k}");
        }
        let failing = ok.iter().flatten().filter(|&&x| !x).count();
        assert_eq!(
            failing, 1,
            "{what}{i}: exactly one difference is out of range: {ok:?}"
        );
        assert!(!ok[i].iter().all(|&x| x), "{what}{i}");
        assert!(!t.diffs_in_range(a, b, l, o), "{what}{i}");
    }
}
