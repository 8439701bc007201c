//! The exact predicate and the certified filters against an independent big-integer oracle
//! (`tests/oracle/mod.rs`: translated triple product in `BigInt`, checked against a Leibniz
//! 4x4 determinant), on random near-degenerate inputs, permutations and exponent extremes.

mod oracle;

use proptest::prelude::*;
use shadowvol_robust_math::{
    orient_exact, orient_exact_expansion, orient_filter_f32, orient_filter_f64, ov_sign, sign_f32,
    Accuracy,
};

type P3 = [f32; 3];
type L4 = [f32; 4];

/// Checks every predicate of the crate against the oracle on one input; returns the oracle sign.
fn check(a: P3, b: P3, l: L4, o: P3) -> i8 {
    let want = oracle::sign_exact(a, b, l, o);
    assert_eq!(
        orient_exact(a, b, l, o),
        want,
        "orient_exact({a:?}, {b:?}, {l:?}, {o:?})"
    );
    assert_eq!(
        orient_exact_expansion(a, b, l, o),
        want,
        "orient_exact_expansion({a:?}, {b:?}, {l:?}, {o:?})"
    );
    if let Some(s) = orient_filter_f64(a, b, l, o) {
        assert_eq!(s, want, "orient_filter_f64({a:?}, {b:?}, {l:?}, {o:?})");
    }
    if let Some(s) = orient_filter_f32(a, b, l, o) {
        assert_eq!(s, want, "orient_filter_f32({a:?}, {b:?}, {l:?}, {o:?})");
    }
    want
}

/// Steps `x` by `k` ulps (negative: down).
fn ulps(mut x: f32, k: i32) -> f32 {
    for _ in 0..k.unsigned_abs() {
        x = if k > 0 { x.next_up() } else { x.next_down() };
    }
    x
}

fn lerp3(p: P3, q: P3, r: P3, s: f32, t: f32) -> P3 {
    // p + s (q - p) + t (r - p), rounded in f32: on the plane up to rounding.
    [0, 1, 2].map(|i| p[i] + s * (q[i] - p[i]) + t * (r[i] - p[i]))
}

// ---- the oracle itself ------------------------------------------------------------------------

#[test]
fn oracle_decomposes_exactly() {
    for x in [
        0.0f32,
        -0.0,
        1.0,
        -1.5,
        1e-45,
        f32::MIN_POSITIVE,
        f32::MAX,
        f32::MIN,
        3.3e-39,
        123_456.79,
    ] {
        let (m, e) = oracle::decompose(x);
        assert_eq!(f64::from(x), m as f64 * 2f64.powi(e), "{x}");
    }
}

#[test]
fn oracle_known_values() {
    // Unit triangle in z = 0, point light at height h: ((A-B) x V).(O-A) with A=0, B=x, O=y,
    // V = (0.2, 0.2, h): (-1,0,0) x (0.2,0.2,h) = (0, h, -0.2); . (0,1,0) = h.
    let (a, b, o) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    assert_eq!(oracle::sign_exact(a, b, [0.2, 0.2, 3.0, 1.0], o), 1);
    assert_eq!(oracle::sign_exact(a, b, [0.2, 0.2, -3.0, 1.0], o), -1);
    assert_eq!(oracle::sign_exact(a, b, [0.2, 0.2, 0.0, 1.0], o), 0);
    // Integer inputs: the determinant value itself, scaled by 2^(-4g).
    let (det, g) = oracle::det_exact(
        [1.0, 2.0, 3.0],
        [4.0, 5.0, 7.0],
        [1.0, 0.0, 2.0, 1.0],
        [2.0, 9.0, 1.0],
    );
    // e = (-3,-3,-4), v = (0,-2,-1), d = (1,7,-2): e x v = (3-8, 0-3, 6-0) = (-5,-3,6);
    // . d = -5 - 21 - 12 = -38. The finest exponent is that of 1.0 (2^23 * 2^-23): g = -23.
    assert_eq!(g, -23);
    assert_eq!(det, num_bigint::BigInt::from(-38) << (4 * 23));
    assert_eq!(
        oracle::det4_leibniz(
            [1.0, 2.0, 3.0],
            [4.0, 5.0, 7.0],
            [1.0, 0.0, 2.0, 1.0],
            [2.0, 9.0, 1.0]
        ),
        -1
    );
}

// ---- deterministic hard families --------------------------------------------------------------

/// A tiny deterministic generator (splitmix64) so the families below are reproducible.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn p3(&mut self, scale: f32, offset: f32) -> P3 {
        [0, 1, 2].map(|_| offset + scale * self.unit())
    }
}

#[test]
fn coplanar_families_agree_with_oracle_and_are_hard() {
    let mut rng = Rng(2013);
    let mut uncertain64 = 0;
    let mut zeros = 0;
    let mut disagree_f32 = 0;
    let n = 6000;
    for i in 0..n {
        let offset = [0.0, 1.0, 1e4, -1e4, 3.0e5][i % 5];
        let scale = [1.0, 1e-3, 10.0][i % 3];
        let a = rng.p3(scale, offset);
        let b = rng.p3(scale, offset);
        let o = rng.p3(scale, offset);
        // Point light in (or, rounded, very near) the plane of the triangle.
        let mut lp = lerp3(a, b, o, rng.unit() * 3.0, rng.unit() * 3.0);
        let mut o2 = o;
        // Perturb a few coordinates by a few ulps.
        for _ in 0..rng.below(3) {
            let k = rng.below(7) as i32 - 3;
            match rng.below(2) {
                0 => {
                    let c = rng.below(3) as usize;
                    lp[c] = ulps(lp[c], k);
                }
                _ => {
                    let c = rng.below(3) as usize;
                    o2[c] = ulps(o2[c], k);
                }
            }
        }
        let l = [lp[0], lp[1], lp[2], 1.0];
        let s = check(a, b, l, o2);
        if orient_filter_f64(a, b, l, o2).is_none() {
            uncertain64 += 1;
        }
        if s == 0 {
            zeros += 1;
        }
        if sign_f32(a, b, l, o2) != s {
            disagree_f32 += 1;
        }
        // Directional light parallel to the face: along an edge, or a combination of two edges.
        let dir = match i % 3 {
            0 => [0, 1, 2].map(|c| b[c] - a[c]),
            1 => [0, 1, 2].map(|c| o[c] - a[c]),
            _ => [0, 1, 2].map(|c| (b[c] - a[c]) + 0.5 * (o[c] - a[c])),
        };
        if dir != [0.0; 3] {
            check(a, b, [dir[0], dir[1], dir[2], 0.0], o);
            check(b, o, [dir[0], dir[1], dir[2], 0.0], a);
        }
    }
    // The family must really be hard: f32 gets many wrong, many are exactly degenerate, and
    // some need the exact fallback.
    assert!(
        uncertain64 > n / 100,
        "only {uncertain64} of {n} needed the fallback"
    );
    // (`sign_f32`'s `N·(O − A)` gets about 9 % of these wrong; the paper's expanded
    // `N·O − N·A`, which cancels at the 1e4 and 3e5 offsets, got more than 10 %.)
    assert!(
        disagree_f32 > n / 20,
        "f32 got only {disagree_f32} of {n} wrong"
    );
    assert!(zeros > n / 20, "only {zeros} of {n} exactly degenerate");
}

#[test]
fn tilted_plane_tiny_perturbations_need_the_fallback() {
    // Integer points on the tilted plane x + 2y + 3z = c, a light exactly in it, then one zero
    // coordinate of O replaced by a tiny value: the determinant is non-zero but far below the
    // f64 filter's bound, so only the exact fallback decides it.
    let mut rng = Rng(31);
    let mut fallback_nonzero = 0;
    for _ in 0..3000 {
        let c = rng.below(21) as i64 - 10;
        let mut on_plane = |zero_z: bool| -> P3 {
            let y = rng.below(41) as i64 - 20;
            let z = if zero_z { 0 } else { rng.below(41) as i64 - 20 };
            let x = c - 2 * y - 3 * z;
            [x as f32, y as f32, z as f32]
        };
        let (a, b) = (on_plane(false), on_plane(false));
        let mut o = on_plane(true);
        let lp = on_plane(false);
        let tiny = [1e-30f32, -1e-30, 1e-45, -3e-42, 1e-20][rng.below(5) as usize];
        o[2] = tiny;
        for l in [
            [lp[0], lp[1], lp[2], 1.0],
            [a[0] - b[0], a[1] - b[1], a[2] - b[2], 0.0],
        ] {
            let s = check(a, b, l, o);
            if s != 0 && orient_filter_f64(a, b, l, o).is_none() {
                fallback_nonzero += 1;
            }
        }
    }
    assert!(
        fallback_nonzero > 1000,
        "only {fallback_nonzero} non-zero cases reached the exact fallback"
    );
}

#[test]
fn exactly_coplanar_integer_geometry_is_zero() {
    // Axis-aligned faces with the light exactly in their plane: the determinant is exactly 0.
    let mut rng = Rng(7);
    for _ in 0..2000 {
        let mut q = || (rng.below(2001) as f32 - 1000.0) * 0.25;
        let z = q();
        let (a, b, o) = ([q(), q(), z], [q(), q(), z], [q(), q(), z]);
        let l = [q(), q(), z, 1.0];
        assert_eq!(check(a, b, l, o), 0);
        // Directional light parallel to the plane z = const.
        let d = [q(), q(), 0.0, 0.0];
        if d != [0.0, 0.0, 0.0, 0.0] {
            assert_eq!(check(a, b, d, o), 0);
        }
        // Light on the line of the edge (a, b) (exactly: the midpoint of integer/4 coordinates
        // is representable).
        let m = [0, 1, 2].map(|c| 0.5 * (a[c] + b[c]));
        let o3 = [o[0], o[1], z + 1.0];
        assert_eq!(check(a, b, [m[0], m[1], m[2], 1.0], o3), 0);
        // Light at a vertex.
        assert_eq!(check(a, b, [a[0], a[1], a[2], 1.0], o3), 0);
        assert_eq!(check(a, b, [b[0], b[1], b[2], 1.0], o3), 0);
    }
}

/// The 6 orderings of a triangle `(p0, p1, p2)` with their parity.
fn permutations(p: [P3; 3]) -> [([P3; 3], i8); 6] {
    let [x, y, z] = p;
    [
        ([x, y, z], 1),
        ([y, z, x], 1),
        ([z, x, y], 1),
        ([y, x, z], -1),
        ([x, z, y], -1),
        ([z, y, x], -1),
    ]
}

fn check_parity(p: [P3; 3], l: L4) {
    let s = oracle::sign_exact(p[0], p[1], l, p[2]);
    for (q, parity) in permutations(p) {
        assert_eq!(
            orient_exact(q[0], q[1], l, q[2]),
            s * parity,
            "permutation {q:?} (parity {parity}) of {p:?}, light {l:?}"
        );
        assert_eq!(orient_exact_expansion(q[0], q[1], l, q[2]), s * parity);
        assert_eq!(oracle::sign_exact(q[0], q[1], l, q[2]), s * parity);
    }
}

#[test]
fn permutation_parity_on_near_degenerate_inputs() {
    let mut rng = Rng(99);
    let mut nonzero = 0;
    for i in 0..1500 {
        let offset = if i % 2 == 0 { 0.0 } else { 1e4 };
        let a = rng.p3(1.0, offset);
        let b = rng.p3(1.0, offset);
        let o = rng.p3(1.0, offset);
        let mut lp = lerp3(a, b, o, rng.unit(), rng.unit());
        let c = rng.below(3) as usize;
        lp[c] = ulps(lp[c], rng.below(5) as i32 - 2);
        let l = [lp[0], lp[1], lp[2], 1.0];
        check_parity([a, b, o], l);
        if oracle::sign_exact(a, b, l, o) != 0 {
            nonzero += 1;
        }
    }
    assert!(
        nonzero > 100,
        "parity was only checked on {nonzero} non-zero cases"
    );
}

// ---- exponent extremes ------------------------------------------------------------------------

const EXTREMES: [f32; 16] = [
    0.0,
    -0.0,
    1e-45,
    -1e-45,
    2e-45,
    f32::MIN_POSITIVE,
    -f32::MIN_POSITIVE,
    1.1754942e-38, // largest subnormal
    f32::MAX,
    -f32::MAX,
    3.4028233e38, // one ulp below MAX
    1.0,
    -1.0,
    1.0e-30,
    1.0e30,
    0.5,
];

#[test]
fn exponent_extremes_exhaustive_sample() {
    let mut rng = Rng(4242);
    for _ in 0..20_000 {
        let mut pick = || EXTREMES[rng.below(EXTREMES.len() as u64) as usize];
        let a = [pick(), pick(), pick()];
        let b = [pick(), pick(), pick()];
        let o = [pick(), pick(), pick()];
        let l = [pick(), pick(), pick(), pick()];
        check(a, b, l, o);
    }
}

#[test]
fn subnormal_and_huge_mixed() {
    // All-subnormal geometry, a light at f32::MAX; and the other way around.
    let a = [1e-45, 0.0, 0.0];
    let b = [0.0, 2e-45, 0.0];
    let o = [0.0, 0.0, 3e-45];
    assert_eq!(check(a, b, [f32::MAX, f32::MAX, f32::MAX, 1.0], o), 1);
    assert_eq!(check(a, b, [-f32::MAX, -f32::MAX, -f32::MAX, 1.0], o), -1);
    assert_ne!(check(a, b, [1e-45, 1e-45, 1e-45, 1.0], o), 0);
    // Huge geometry, subnormal light components and w.
    let a = [f32::MAX, 0.0, 0.0];
    let b = [0.0, f32::MAX, 0.0];
    let o = [0.0, 0.0, f32::MAX];
    check(a, b, [1e-45, -1e-45, 1e-45, 1e-45], o);
    check(a, b, [f32::MAX, f32::MAX, f32::MAX, 1e-45], o);
    check(a, b, [1.0, 1.0, 1.0, 0.0], o);
    // Products that underflow f32 entirely (w * A below the subnormal range) are exact here.
    let a = [1e-20, 2e-20, 0.0];
    let b = [-1e-20, 0.0, 3e-20];
    let o = [0.0, 1e-20, 1e-20];
    check(a, b, [0.0, 0.0, 0.0, 1e-30], o);
    check(a, b, [1e-45, 0.0, 0.0, 1e-30], o);
}

#[test]
fn f32_filter_never_certifies_a_wrong_zero_when_w_a_underflows() {
    // Regression: with a tiny w, w * A rounds to 0 in f32, V = L.xyz - w A vanished, the
    // permanent was 0 and the f32 filter certified a zero determinant that is not zero.
    let a = [0.3f32, 0.0, 0.0];
    let b = [0.0f32, 0.5, 0.0];
    let o = [0.0f32, 0.0, 1.0];
    let l = [0.0f32, 0.0, 0.0, 1e-45];
    let want = oracle::sign_exact(a, b, l, o);
    assert_eq!(want, -1, "det = -0.15 w");
    assert_eq!(check(a, b, l, o), want);
    assert_ne!(orient_filter_f32(a, b, l, o), Some(0));
}

#[test]
fn f32_filter_is_sound_for_general_w() {
    // Regression: for w not in {0, 1}, fl(w * A) can round to exactly L.xyz, so the computed
    // V = L.xyz - w A is 0 while the exact one is not; its error is relative to |w A|, not to
    // |V|, and the filter certified a wrong 0.
    let w = 1.1f32;
    let a = [1.3f32, 0.0, 0.0];
    let b = [1.3f32, -1.0, -2.0];
    let o = [1.3f32, 3.0, 1.0];
    let l = [w * a[0], 0.0, 0.0, w];
    let want = oracle::sign_exact(a, b, l, o);
    assert_ne!(
        want, 0,
        "w * A is inexact in f32, so V.x != 0 and det = 5 V.x"
    );
    assert_eq!(check(a, b, l, o), want);
    // Many general-w lights near such cancellations.
    let mut rng = Rng(77);
    for _ in 0..20_000 {
        let w = 1.0 + rng.unit().abs() * 3.0;
        let a = [rng.unit() * 4.0, rng.unit() * 4.0, rng.unit() * 4.0];
        let b = [a[0], a[1] + rng.unit(), a[2] + rng.unit()];
        let o = [a[0], a[1] + rng.unit(), a[2] + rng.unit()];
        let mut l = [w * a[0], w * a[1], w * a[2], w];
        let c = rng.below(3) as usize;
        l[c] = ulps(l[c], rng.below(3) as i32 - 1);
        check(a, b, l, o);
    }
}

// ---- proptests --------------------------------------------------------------------------------

fn finite_f32() -> impl Strategy<Value = f32> {
    use proptest::num::f32 as f;
    prop_oneof![
        4 => -1e3f32..1e3f32,
        2 => f::POSITIVE | f::NEGATIVE | f::NORMAL | f::SUBNORMAL | f::ZERO,
        1 => proptest::sample::select(EXTREMES.to_vec()),
        1 => (-1e4f32..1e4f32).prop_map(|x| x.round()),
    ]
}

fn p3() -> impl Strategy<Value = P3> {
    [finite_f32(), finite_f32(), finite_f32()]
}

/// Near-degenerate: a triangle around a common offset, a light near its plane (point or
/// directional parallel to it), then a few ulps of perturbation.
fn near_degenerate() -> impl Strategy<Value = (P3, P3, L4, P3)> {
    let offset = prop_oneof![Just(0.0f32), Just(1e4), Just(-1e4), Just(1.0), -1e5f32..1e5];
    let scale = prop_oneof![Just(1.0f32), Just(1e-3), Just(1e3), 1e-6f32..1e6];
    (
        offset,
        scale,
        proptest::array::uniform9(-1.0f32..1.0),
        (-4.0f32..4.0, -4.0f32..4.0),
        proptest::array::uniform4(-4i32..=4),
        0u8..3,
    )
        .prop_map(|(off, sc, r, (s, t), k, kind)| {
            let a = [off + sc * r[0], off + sc * r[1], off + sc * r[2]];
            let b = [off + sc * r[3], off + sc * r[4], off + sc * r[5]];
            let o = [off + sc * r[6], off + sc * r[7], off + sc * r[8]];
            let l = match kind {
                0 => {
                    let p = lerp3(a, b, o, s, t);
                    [p[0], p[1], p[2], 1.0]
                }
                1 => {
                    // On the line of edge (a, b).
                    let p = lerp3(a, b, o, s, 0.0);
                    [p[0], p[1], p[2], 1.0]
                }
                _ => {
                    let d = [0, 1, 2].map(|c| s * (b[c] - a[c]) + t * (o[c] - a[c]));
                    [d[0], d[1], d[2], 0.0]
                }
            };
            let l = [ulps(l[0], k[0]), ulps(l[1], k[1]), ulps(l[2], k[2]), l[3]];
            let o = [ulps(o[0], k[3]), o[1], o[2]];
            (a, b, l, o)
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn prop_arbitrary_finite_inputs(a in p3(), b in p3(), o in p3(),
                                    l in [finite_f32(), finite_f32(), finite_f32(), finite_f32()]) {
        check(a, b, l, o);
    }

    #[test]
    fn prop_near_degenerate((a, b, l, o) in near_degenerate()) {
        check(a, b, l, o);
    }

    #[test]
    fn prop_parity((a, b, l, o) in near_degenerate()) {
        check_parity([a, b, o], l);
    }

    #[test]
    fn prop_oracle_self_consistent(a in p3(), b in p3(), o in p3(),
                                   l in [finite_f32(), finite_f32(), finite_f32(), finite_f32()]) {
        prop_assert_eq!(oracle::sign_exact(a, b, l, o), oracle::det4_leibniz(a, b, l, o));
    }

    #[test]
    fn prop_oracle_self_consistent_near_degenerate((a, b, l, o) in near_degenerate()) {
        prop_assert_eq!(oracle::sign_exact(a, b, l, o), oracle::det4_leibniz(a, b, l, o));
    }

    /// The local form of the closed-chain invariant: in every consistent mode, the three edges
    /// of one triangle (ids 0 < 1 < 2) get s(0,1,2) = s(1,2,0) = -s(0,2,1); in exact mode that
    /// common value is the oracle's sign.
    #[test]
    fn prop_consistent_modes_agree_on_a_triangle((a, b, l, o) in near_degenerate()) {
        let p = [glam::Vec3::from(a), glam::Vec3::from(b), glam::Vec3::from(o)];
        for mode in [Accuracy::Robust, Accuracy::Ordered, Accuracy::Exact] {
            let s01 = ov_sign(mode, &p, 0, 1, 2, l);
            let s12 = ov_sign(mode, &p, 1, 2, 0, l);
            let s02 = ov_sign(mode, &p, 0, 2, 1, l);
            prop_assert_eq!(s01, s12, "mode {}", mode);
            prop_assert_eq!(s01, -s02, "mode {}", mode);
            if mode == Accuracy::Exact {
                prop_assert_eq!(s01, oracle::sign_exact(a, b, l, o));
            }
        }
    }
}

// ---- the f32 modes against an emulated evaluation ---------------------------------------------

/// The mode's rule, written here: `original` evaluates `(a, b, o)` as given; `ordered` the
/// canonical order (ids sorted) times the parity of the sorting permutation (inversions
/// counted); `robust` the three rotations of the canonical order, 0 unless they agree, times the
/// parity. Each evaluation is [`oracle::sign_f32_emulated`].
fn mode_rule(mode: Accuracy, p: &[P3], a: u32, b: u32, o: u32, l: L4) -> i8 {
    let ids = [a, b, o];
    let inversions = (0..3)
        .flat_map(|i| (i + 1..3).map(move |j| (i, j)))
        .filter(|&(i, j)| ids[i] > ids[j])
        .count();
    let parity = if inversions % 2 == 0 { 1 } else { -1 };
    let mut c = ids;
    c.sort_unstable();
    let ev = |x: u32, y: u32, z: u32| {
        oracle::sign_f32_emulated(p[x as usize], p[y as usize], l, p[z as usize])
    };
    match mode {
        Accuracy::Original => ev(a, b, o),
        Accuracy::Ordered => ev(c[0], c[1], c[2]) * parity,
        Accuracy::Robust => {
            let s = [
                ev(c[0], c[1], c[2]),
                ev(c[1], c[2], c[0]),
                ev(c[2], c[0], c[1]),
            ];
            if s[0] == s[1] && s[1] == s[2] {
                s[0] * parity
            } else {
                0
            }
        }
        Accuracy::Exact => oracle::sign_exact(p[a as usize], p[b as usize], l, p[o as usize]),
    }
}

#[test]
fn emulated_f32_rounds_like_the_hardware() {
    // The emulation itself: single operations on awkward values, subnormal results included.
    let mut rng = Rng(99);
    let vals = |rng: &mut Rng| {
        let m = rng.unit();
        let e = rng.below(60) as i32 - 30;
        m * 2f32.powi(e)
    };
    for _ in 0..20_000 {
        let (x, y) = (vals(&mut rng), vals(&mut rng));
        let ex = |f: fn(&oracle::Exact, &oracle::Exact) -> oracle::Exact| {
            f(&oracle::Exact::of(x), &oracle::Exact::of(y)).round()
        };
        assert_eq!(
            ex(oracle::Exact::add).to_bits(),
            (x + y).to_bits(),
            "{x} + {y}"
        );
        assert_eq!(
            ex(oracle::Exact::sub).to_bits(),
            (x - y).to_bits(),
            "{x} - {y}"
        );
        let p = ex(oracle::Exact::mul);
        assert!(p == x * y, "{x} * {y}: {p} vs {}", x * y);
    }
    let tiny = f32::MIN_POSITIVE;
    for (x, y) in [
        (tiny, 0.75),
        (tiny * 3.0, 0.5),
        (1e-30, 1e-15),
        (tiny, tiny),
    ] {
        let p = oracle::Exact::of(x).mul(&oracle::Exact::of(y)).round();
        assert_eq!(p.to_bits(), (x * y).to_bits(), "{x:e} * {y:e}");
    }
}

#[test]
fn f32_modes_equal_the_emulated_evaluation_and_their_rules() {
    let mut rng = Rng(2024);
    let (mut robust_zeros, mut wrong_vs_exact, mut total) = (0, 0, 0);
    for i in 0..3000 {
        let offset = [0.0, 1.0, 1e4, -1e4, 3.0e5][i % 5];
        let scale = [1.0, 1e-3, 10.0][i % 3];
        let p = [
            rng.p3(scale, offset),
            rng.p3(scale, offset),
            rng.p3(scale, offset),
        ];
        // A light in (or near) the plane of the triangle, or a directional light along an edge.
        let mut lp = lerp3(p[0], p[1], p[2], rng.unit() * 3.0, rng.unit() * 3.0);
        let c = rng.below(3) as usize;
        lp[c] = ulps(lp[c], rng.below(5) as i32 - 2);
        let l = if i % 4 == 3 {
            let d = [0, 1, 2].map(|c| p[1][c] - p[0][c]);
            [d[0], d[1], d[2], 0.0]
        } else {
            [lp[0], lp[1], lp[2], 1.0]
        };
        let positions: Vec<glam::Vec3> = p.iter().map(|&q| glam::Vec3::from_array(q)).collect();
        // The three (edge, opposite vertex) pairs of the triangle: o > b, a < o < b, o < a.
        for (a, b, o) in [(0, 1, 2), (0, 2, 1), (1, 2, 0)] {
            for mode in [Accuracy::Original, Accuracy::Ordered, Accuracy::Robust] {
                let want = mode_rule(mode, &p, a, b, o, l);
                let got = ov_sign(mode, &positions, a, b, o, l);
                assert_eq!(
                    got, want,
                    "{mode} s({a}, {b}, {o}) with positions {p:?}, light {l:?}"
                );
                total += 1;
                if mode == Accuracy::Robust
                    && got == 0
                    && mode_rule(Accuracy::Ordered, &p, a, b, o, l) != 0
                {
                    robust_zeros += 1;
                }
                if got != mode_rule(Accuracy::Exact, &p, a, b, o, l) {
                    wrong_vs_exact += 1;
                }
            }
        }
    }
    // The family must be hard: the modes often differ from exact, and robust's disagreement
    // rule decides many triangles (0 where ordered's evaluation is not).
    assert!(wrong_vs_exact > total / 50, "{wrong_vs_exact} of {total}");
    assert!(
        robust_zeros > 100,
        "{robust_zeros} triangles whose evaluations disagree"
    );
}

#[test]
fn filters_certify_well_conditioned_inputs() {
    // Triangles in [-1, 1]^3 with a light anywhere in [-4, 4]^3 (point or directional): both
    // filters must decide nearly all of them. A filter that is always uncertain is correct but
    // sends every pair to the exact fallback (the host, on the GPU backends).
    let mut rng = Rng(5);
    let (mut by_f32, mut by_f64, mut n) = (0, 0, 0);
    for i in 0..3000 {
        let (a, b, o) = (rng.p3(1.0, 0.0), rng.p3(1.0, 0.0), rng.p3(1.0, 0.0));
        let w = if i % 3 == 0 { 0.0 } else { 1.0 };
        let l = [rng.unit() * 4.0, rng.unit() * 4.0, rng.unit() * 4.0, w];
        if check(a, b, l, o) == 0 {
            continue;
        }
        n += 1;
        by_f32 += usize::from(orient_filter_f32(a, b, l, o).is_some());
        by_f64 += usize::from(orient_filter_f64(a, b, l, o).is_some());
    }
    assert!(by_f32 * 10 > n * 9, "f32 filter decided {by_f32} of {n}");
    assert!(by_f64 * 100 > n * 99, "f64 filter decided {by_f64} of {n}");
}
