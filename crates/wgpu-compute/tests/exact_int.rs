//! The integer-only exact orientation sign (`shaders/exact_int.wgsl` and its CPU twin
//! `twin::orient_int`):
//!
//! * the twin equals robust-math's `orient_exact` (and an independent big-integer determinant) on
//!   random, exactly degenerate, near-degenerate (one ulp off), subnormal, huge, mixed huge/tiny
//!   inputs, with point (`w = 1`), directional (`w = 0`) and general-`w` lights;
//! * naga validates the WGSL module alone and composed with a test entry point;
//! * `gpu_*`: on a real wgpu device the WGSL gives exactly the twin's results. Without an adapter
//!   the device test is ignored with the reason (`ignored (wgpu backend unavailable: ...)`), except under
//!   `CI=true`, where it fails (`shadowvol_test_support::skip`).

mod common;

use naga::valid::{Capabilities, ValidationFlags, Validator};
use num_bigint::BigInt;
use proptest::prelude::*;
use shadowvol_gpu::shaders::EXACT_INT_WGSL;
use shadowvol_gpu::twin::{mul32, orient_int};
use shadowvol_robust_math::orient_exact;
use shadowvol_test_support::{main, Outcome};
use shadowvol_wgpu_compute::{WgpuBackend, WgpuOptions};

main!(
    twin_equals_orient_exact_and_big_integers_on_the_adversarial_set,
    constructed_degenerate_inputs_are_zero_and_one_ulp_off_mostly_not,
    special_values_every_combination_on_a_pattern,
    prop_mul32_is_the_64_bit_product,
    prop_twin_equals_orient_exact_on_wild_inputs,
    prop_twin_is_zero_on_degenerate_and_exact_one_ulp_off,
    prop_twin_flips_under_odd_and_keeps_under_even_permutations,
    naga_validates_exact_int_wgsl_alone_without_capabilities,
    naga_validates_the_composed_test_kernel,
    gpu_orient_int_equals_twin_and_orient_exact,
);

/// One input `(A, B, L, O)`.
type Input = ([f32; 3], [f32; 3], [f32; 4], [f32; 3]);

// ---- independent reference --------------------------------------------------------------------

/// `x · 2^149` as a big integer (every finite `f32` is an integer multiple of `2^-149`).
fn big(x: f32) -> BigInt {
    let u = x.to_bits();
    let field = (u >> 23) & 0xff;
    let m = (u & 0x7f_ffff) | if field != 0 { 1 << 23 } else { 0 };
    let v = BigInt::from(m) << (field.max(1) - 1);
    if u >> 31 != 0 {
        -v
    } else {
        v
    }
}

/// Determinant by cofactor expansion along the first row (generic, no shared code with the twin).
fn det(m: &[Vec<BigInt>]) -> BigInt {
    if m.len() == 1 {
        return m[0][0].clone();
    }
    let mut sum = BigInt::from(0);
    for j in 0..m.len() {
        let minor: Vec<Vec<BigInt>> = m[1..]
            .iter()
            .map(|row| {
                row.iter()
                    .enumerate()
                    .filter(|&(c, _)| c != j)
                    .map(|(_, v)| v.clone())
                    .collect()
            })
            .collect();
        let t = &m[0][j] * det(&minor);
        if j % 2 == 0 {
            sum += t;
        } else {
            sum -= t;
        }
    }
    sum
}

/// The sign of `det4 |A 1; B 1; L; O 1|` with every entry (the 1s included) scaled by `2^149`.
fn sign_big((a, b, l, o): Input) -> i8 {
    let one: BigInt = BigInt::from(1) << 149;
    let row = |p: [f32; 3]| vec![big(p[0]), big(p[1]), big(p[2]), one.clone()];
    let m = vec![row(a), row(b), l.iter().map(|&x| big(x)).collect(), row(o)];
    let d = det(&m);
    match d.sign() {
        num_bigint::Sign::Minus => -1,
        num_bigint::Sign::NoSign => 0,
        num_bigint::Sign::Plus => 1,
    }
}

fn show((a, b, l, o): Input) -> String {
    let bits = |v: &[f32]| {
        v.iter()
            .map(|x| format!("{:#010x}", x.to_bits()))
            .collect::<Vec<_>>()
            .join(",")
    };
    format!(
        "A={a:?} B={b:?} L={l:?} O={o:?} (bits A[{}] B[{}] L[{}] O[{}])",
        bits(&a),
        bits(&b),
        bits(&l),
        bits(&o)
    )
}

/// Twin against `orient_exact` (the contract) and the big-integer reference (who is right).
fn check(input: Input) -> i8 {
    let (a, b, l, o) = input;
    let got = orient_int(a, b, l, o);
    let want = orient_exact(a, b, l, o);
    assert_eq!(
        got,
        want,
        "orient_int != orient_exact (big-integer reference: {}) for {}",
        sign_big(input),
        show(input)
    );
    got
}

// ---- inputs -----------------------------------------------------------------------------------

/// splitmix64: a small deterministic generator for the fixed sets.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn int(&mut self, r: i32) -> i32 {
        (self.below(2 * r as u64 + 1) as i64 - i64::from(r)) as i32
    }
}

/// The special values: zeros, the subnormal ends, the normal ends, f32::MAX, ones, powers.
const SPECIALS: [f32; 20] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    f32::MAX,
    -f32::MAX,
    f32::MIN_POSITIVE,
    -f32::MIN_POSITIVE,
    f32::from_bits(1),           // 2^-149, the smallest subnormal
    f32::from_bits(0x8000_0001), // -2^-149
    f32::from_bits(0x007f_ffff), // the largest subnormal
    f32::from_bits(0x807f_ffff),
    f32::from_bits(0x3f80_0001), // 1 + 2^-23
    f32::from_bits(0x3f7f_ffff), // 1 - 2^-24
    3.0,
    0.5,
    f32::from_bits(0x5f80_0000), // 2^64
    f32::from_bits(0x1f80_0000), // 2^-64
    f32::from_bits(0x7f00_0000), // 2^127
    f32::MAX / 3.0,
];

/// A component for the wild sets: random finite bits (uniform exponents: huge and tiny mixed),
/// a special value, a small integer, or a small integer times a random power of two.
fn wild(r: &mut Rng) -> f32 {
    match r.below(4) {
        0 => loop {
            let x = f32::from_bits(r.next() as u32);
            if x.is_finite() {
                break x;
            }
        },
        1 => SPECIALS[r.below(SPECIALS.len() as u64) as usize],
        2 => r.int(8) as f32,
        _ => {
            let m = r.int(1 << 12) as f32;
            let k = r.below(149 + 115) as i32 - 149;
            exact(f64::from(m) * 2f64.powi(k)).unwrap_or(m)
        }
    }
}

fn wild_input(r: &mut Rng) -> Input {
    let mut v = [0f32; 13];
    for x in &mut v {
        *x = wild(r);
    }
    // Half the lights are point or directional lights.
    match r.below(4) {
        0 => v[9 + 3] = 1.0,
        1 => v[9 + 3] = 0.0,
        _ => {}
    }
    (
        [v[0], v[1], v[2]],
        [v[3], v[4], v[5]],
        [v[9], v[10], v[11], v[12]],
        [v[6], v[7], v[8]],
    )
}

/// `x` as an `f32`, if it is one exactly.
fn exact(x: f64) -> Option<f32> {
    let f = x as f32;
    (f.is_finite() && f64::from(f) == x).then_some(f)
}

/// How a degenerate input is made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// O = A + t (B - A).
    Collinear,
    /// B = A.
    RepeatedVertex,
    /// A point light in the triangle's plane.
    PointInPlane,
    /// A directional light parallel to the triangle's plane.
    DirectionalInPlane,
    /// (w P, w) with P in the plane, w general.
    HomogeneousInPlane,
    /// A point light on the line AB.
    PointOnEdgeLine,
    /// A point light at a vertex.
    PointAtVertex,
}

const KINDS: [Kind; 7] = [
    Kind::Collinear,
    Kind::RepeatedVertex,
    Kind::PointInPlane,
    Kind::DirectionalInPlane,
    Kind::HomogeneousInPlane,
    Kind::PointOnEdgeLine,
    Kind::PointAtVertex,
];

/// General `w` values for homogeneous lights (exact small multiples keep `w P` exact).
const WS: [f64; 9] = [
    2.0,
    0.5,
    -3.0,
    7.0,
    0.375,
    -1.0,
    1.0 / 1_048_576.0,
    1_073_741_824.0,
    5.0,
];

/// Parameters of a degenerate input: integer corners, integer or dyadic coefficients, the kind,
/// the general `w` index and the scale `2^k` applied to the first three columns (it scales the
/// determinant by `2^(3k)`, so zero stays zero).
#[derive(Debug, Clone, Copy)]
struct Degenerate {
    a: [i32; 3],
    b: [i32; 3],
    o: [i32; 3],
    s: i32,
    u: i32,
    /// t = t_num / 8.
    t_num: i32,
    kind: Kind,
    w: usize,
    k: i32,
}

impl Degenerate {
    /// The exactly degenerate input (det4 = 0), if every coordinate is an exact `f32`.
    fn build(&self) -> Option<Input> {
        let f = |p: [i32; 3]| p.map(f64::from);
        let (a, mut b, mut o) = (f(self.a), f(self.b), f(self.o));
        let t = f64::from(self.t_num) / 8.0;
        let (s, u) = (f64::from(self.s), f64::from(self.u));
        let lin = |p: [f64; 3], q: [f64; 3], r: [f64; 3], x: f64, y: f64| {
            [0, 1, 2].map(|i| p[i] + x * (q[i] - p[i]) + y * (r[i] - p[i]))
        };
        let l: [f64; 4];
        match self.kind {
            Kind::Collinear => {
                o = lin(a, b, b, t, 0.0);
                l = [f64::from(self.s), f64::from(self.u), 5.0, 1.0];
            }
            Kind::RepeatedVertex => {
                b = a;
                l = [f64::from(self.s), 3.0, f64::from(self.u), 1.0];
            }
            Kind::PointInPlane => {
                let p = lin(a, b, o, s, u);
                l = [p[0], p[1], p[2], 1.0];
            }
            Kind::DirectionalInPlane => {
                let z = [0.0; 3];
                let d = lin(
                    z,
                    [0, 1, 2].map(|i| b[i] - a[i]),
                    [0, 1, 2].map(|i| o[i] - a[i]),
                    s,
                    u,
                );
                l = [d[0], d[1], d[2], 0.0];
            }
            Kind::HomogeneousInPlane => {
                let w = WS[self.w % WS.len()];
                let p = lin(a, b, o, s, u);
                l = [w * p[0], w * p[1], w * p[2], w];
            }
            Kind::PointOnEdgeLine => {
                let p = lin(a, b, b, t, 0.0);
                l = [p[0], p[1], p[2], 1.0];
            }
            Kind::PointAtVertex => {
                l = [o[0], o[1], o[2], 1.0];
            }
        }
        let sc = 2f64.powi(self.k);
        let p3 = |p: [f64; 3]| -> Option<[f32; 3]> {
            Some([exact(p[0] * sc)?, exact(p[1] * sc)?, exact(p[2] * sc)?])
        };
        let l4 = [
            exact(l[0] * sc)?,
            exact(l[1] * sc)?,
            exact(l[2] * sc)?,
            exact(l[3])?,
        ];
        Some((p3(a)?, p3(b)?, l4, p3(o)?))
    }
}

fn random_degenerate(r: &mut Rng) -> Degenerate {
    // Corner ranges from tiny integers to 2^20, so that scaled coordinates reach every exponent.
    let range = [4, 64, 1024, 1 << 20][r.below(4) as usize];
    let mut p = || [r.int(range), r.int(range), r.int(range)];
    let (a, b, o) = (p(), p(), p());
    Degenerate {
        a,
        b,
        o,
        s: r.int(6),
        u: r.int(6),
        t_num: r.int(24),
        kind: KINDS[r.below(KINDS.len() as u64) as usize],
        w: r.below(WS.len() as u64) as usize,
        k: [
            -149, -140, -130, -126, -120, -100, -60, -20, 0, 20, 60, 100, 104, 110,
        ][r.below(14) as usize],
    }
}

/// `x` moved by one ulp up or down (through zero to the smallest subnormal).
fn ulp(x: f32, up: bool) -> f32 {
    if up {
        x.next_up()
    } else {
        x.next_down()
    }
}

/// The input with component `i` (0..13: A, B, O, L) moved by one ulp.
fn nudge((mut a, mut b, mut l, mut o): Input, i: usize, up: bool) -> Option<Input> {
    let x = match i {
        0..=2 => &mut a[i],
        3..=5 => &mut b[i - 3],
        6..=8 => &mut o[i - 6],
        _ => &mut l[i - 9],
    };
    *x = ulp(*x, up);
    x.is_finite().then_some((a, b, l, o))
}

/// Hand-made extremes: f32::MAX and the subnormal ends in exactly degenerate and near ones.
fn extremes() -> Vec<Input> {
    let m = f32::MAX;
    let t = f32::from_bits(1); // 2^-149
    let big_sub = f32::from_bits(0x007f_ffff);
    let n = f32::MIN_POSITIVE;
    vec![
        // Huge triangle, light in its plane (z = 0) and just off it.
        (
            [m, 0.0, 0.0],
            [0.0, m, 0.0],
            [m, m, 0.0, 1.0],
            [-m, -m, 0.0],
        ),
        ([m, 0.0, 0.0], [0.0, m, 0.0], [m, m, t, 1.0], [-m, -m, 0.0]),
        ([m, 0.0, 0.0], [0.0, m, 0.0], [m, m, -t, 0.0], [-m, -m, 0.0]),
        ([m, m, m], [-m, -m, -m], [m, -m, m, 1.0], [m, -m, -m]),
        ([m, m, m], [-m, -m, -m], [m, -m, m, m], [m, -m, -m]),
        ([m, m, m], [-m, -m, -m], [m, -m, m, -m], [m, -m, -m]),
        // The largest determinant magnitudes: all products near 2^512.
        ([m, -m, m], [-m, m, m], [m, m, -m, m], [m, m, m]),
        ([-m, -m, m], [m, -m, -m], [-m, m, m, -m], [m, -m, m]),
        // Tiny triangles: subnormal coordinates, exact zero and one ulp off.
        (
            [0.0, 0.0, 0.0],
            [t, 0.0, 0.0],
            [0.0, 0.0, t, 1.0],
            [0.0, t, 0.0],
        ),
        (
            [0.0, 0.0, 0.0],
            [t, 0.0, 0.0],
            [t, t, 0.0, 1.0],
            [0.0, t, 0.0],
        ),
        ([t, t, t], [-t, -t, -t], [t, -t, t, t], [t, -t, -t]),
        (
            [big_sub, n, t],
            [n, big_sub, -t],
            [t, t, -n, 0.0],
            [-big_sub, t, n],
        ),
        (
            [big_sub, n, t],
            [n, big_sub, -t],
            [t, t, -n, t],
            [-big_sub, t, n],
        ),
        // Mixed: the smallest products against the largest.
        ([m, t, 0.0], [t, m, 0.0], [t, t, m, t], [0.0, 0.0, t]),
        ([m, t, t], [t, m, t], [m, m, m, t], [t, t, m]),
        ([t, m, t], [m, t, m], [m, t, m, m], [t, t, t]),
        // w general with cancellation L.xyz = w A exactly (V = 0: the light at A).
        (
            [3.0, 5.0, 7.0],
            [1.0, 2.0, 3.0],
            [0.375 * 3.0, 0.375 * 5.0, 0.375 * 7.0, 0.375],
            [4.0, 1.0, -2.0],
        ),
        (
            [3.0, 5.0, 7.0],
            [1.0, 2.0, 3.0],
            [1.125, 1.875, 2.625_000_2, 0.375],
            [4.0, 1.0, -2.0],
        ),
    ]
}

/// The fixed adversarial set (exact degenerate, one ulp off, extremes) plus wild inputs.
fn adversarial_set() -> (Vec<Input>, usize) {
    let mut r = Rng(0x005e_ed0e_1ac7_u64);
    let mut out = extremes();
    let mut degenerate = 0;
    while degenerate < 900 {
        let Some(input) = random_degenerate(&mut r).build() else {
            continue;
        };
        degenerate += 1;
        out.push(input);
        let i = r.below(13) as usize;
        if let Some(near) = nudge(input, i, r.below(2) == 0) {
            out.push(near);
        }
    }
    let adversarial = out.len();
    for _ in 0..1500 {
        out.push(wild_input(&mut r));
    }
    (out, adversarial)
}

// ---- CPU tests --------------------------------------------------------------------------------

fn twin_equals_orient_exact_and_big_integers_on_the_adversarial_set() {
    let (inputs, adversarial) = adversarial_set();
    let mut counts = [0usize; 3];
    for &input in &inputs {
        let s = check(input);
        assert_eq!(s, sign_big(input), "big-integer reference: {}", show(input));
        counts[(s + 1) as usize] += 1;
    }
    eprintln!(
        "{} inputs ({adversarial} adversarial): {} negative, {} zero, {} positive",
        inputs.len(),
        counts[0],
        counts[1],
        counts[2]
    );
    assert!(
        counts[1] >= 900,
        "the degenerate constructions are not exactly degenerate"
    );
    assert!(counts[0] > 200 && counts[2] > 200);
}

fn constructed_degenerate_inputs_are_zero_and_one_ulp_off_mostly_not() {
    let mut r = Rng(7);
    let (mut built, mut nonzero_near, mut near) = (0, 0, 0);
    let mut per_kind = [0usize; KINDS.len()];
    for _ in 0..4000 {
        let d = random_degenerate(&mut r);
        let Some(input) = d.build() else { continue };
        built += 1;
        per_kind[KINDS.iter().position(|&k| k == d.kind).unwrap()] += 1;
        assert_eq!(check(input), 0, "{d:?} is not degenerate: {}", show(input));
        for i in 0..13 {
            if let Some(n) = nudge(input, i, i % 2 == 0) {
                near += 1;
                nonzero_near += usize::from(check(n) != 0);
            }
        }
    }
    eprintln!("{built} degenerate inputs {per_kind:?}; {nonzero_near} of {near} one-ulp neighbours non-zero");
    assert!(built > 2000 && per_kind.iter().all(|&n| n > 100));
    assert!(nonzero_near * 2 > near);
}

fn special_values_every_combination_on_a_pattern() {
    // Every special value in every slot, against two base inputs.
    let bases: [Input; 2] = [
        (
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.3, 0.3, 2.0, 1.0],
            [0.0, 1.0, 0.0],
        ),
        (
            [f32::MAX, 1.0e-45, -3.0],
            [-1.0e-45, f32::MAX, 0.5],
            [1.0, -2.0, 3.0, 0.0],
            [2.0, 1.0e-40, -f32::MAX],
        ),
    ];
    let mut n = 0;
    for base in bases {
        for i in 0..13 {
            for j in 0..13 {
                for &x in &SPECIALS {
                    for &y in &SPECIALS[..6] {
                        let (mut a, mut b, mut l, mut o) = base;
                        let mut set = |k: usize, v: f32| match k {
                            0..=2 => a[k] = v,
                            3..=5 => b[k - 3] = v,
                            6..=8 => o[k - 6] = v,
                            _ => l[k - 9] = v,
                        };
                        set(i, x);
                        set(j, y);
                        check((a, b, l, o));
                        n += 1;
                    }
                }
            }
        }
    }
    assert_eq!(n, 2 * 13 * 13 * SPECIALS.len() * 6);
}

fn component() -> impl Strategy<Value = f32> {
    prop_oneof![
        any::<u32>()
            .prop_map(f32::from_bits)
            .prop_filter("finite", |x| x.is_finite()),
        (0..SPECIALS.len()).prop_map(|i| SPECIALS[i]),
        (-8i32..=8).prop_map(|i| i as f32),
        (-4096i32..=4096, -149i32..=115)
            .prop_map(|(m, k)| exact(f64::from(m) * 2f64.powi(k)).unwrap_or(m as f32)),
        (0u32..0x0080_0000).prop_map(f32::from_bits),
    ]
}

fn light_w() -> impl Strategy<Value = f32> {
    prop_oneof![Just(1.0f32), Just(0.0f32), component()]
}

fn degenerate() -> impl Strategy<Value = Degenerate> {
    let corner = |r: i32| [-r..=r, -r..=r, -r..=r];
    (
        prop_oneof![Just(4), Just(1024), Just(1 << 20)],
        0..KINDS.len(),
        0..WS.len(),
        prop_oneof![-149i32..=-120, -40i32..=40, 90i32..=110],
        -6i32..=6,
        -6i32..=6,
        -24i32..=24,
    )
        .prop_flat_map(move |(r, kind, w, k, s, u, t_num)| {
            (corner(r), corner(r), corner(r)).prop_map(move |(a, b, o)| Degenerate {
                a,
                b,
                o,
                s,
                u,
                t_num,
                kind: KINDS[kind],
                w,
                k,
            })
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    fn prop_mul32_is_the_64_bit_product(a in any::<u32>(), b in any::<u32>()) {
        let [lo, hi] = mul32(a, b);
        prop_assert_eq!(u64::from(lo) | (u64::from(hi) << 32), u64::from(a) * u64::from(b));
    }

    fn prop_twin_equals_orient_exact_on_wild_inputs(
        a in [component(), component(), component()],
        b in [component(), component(), component()],
        l in [component(), component(), component()],
        w in light_w(),
        o in [component(), component(), component()],
    ) {
        check((a, b, [l[0], l[1], l[2], w], o));
    }

    fn prop_twin_is_zero_on_degenerate_and_exact_one_ulp_off(
        d in degenerate(),
        i in 0usize..13,
        up in any::<bool>(),
    ) {
        if let Some(input) = d.build() {
            prop_assert_eq!(check(input), 0, "{:?}", d);
            if let Some(near) = nudge(input, i, up) {
                prop_assert_eq!(check(near), sign_big(near));
            }
        }
    }

    fn prop_twin_flips_under_odd_and_keeps_under_even_permutations(
        a in [component(), component(), component()],
        b in [component(), component(), component()],
        l in [component(), component(), component(), component()],
        o in [component(), component(), component()],
    ) {
        // Swapping A and B flips the sign, rotating (A, B, O) keeps it.
        let s = check((a, b, l, o));
        prop_assert_eq!(check((b, a, l, o)), -s);
        prop_assert_eq!(check((o, a, l, b)), s);
    }
}

// ---- naga ------------------------------------------------------------------------------------

fn validate(name: &str, source: &str) -> (naga::Module, naga::valid::ModuleInfo) {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string_with_path(source, name)));
    let info = Validator::new(ValidationFlags::all(), Capabilities::empty())
        .validate(&module)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string_with_path(source, name)));
    (module, info)
}

/// The floating-point arithmetic of a module: every unary, binary (comparisons included),
/// built-in function or value conversion whose operand is a float (bitcasts are not arithmetic).
fn float_arithmetic(module: &naga::Module, info: &naga::valid::ModuleInfo) -> Vec<String> {
    let mut found = Vec::new();
    for (handle, f) in module.functions.iter() {
        let fi = &info[handle];
        let is_float = |e: naga::Handle<naga::Expression>| {
            fi[e].ty.inner_with(&module.types).scalar_kind() == Some(naga::ScalarKind::Float)
        };
        for (h, e) in f.expressions.iter() {
            let operand = match *e {
                naga::Expression::Unary { expr, .. } => Some(expr),
                naga::Expression::Binary { left, .. } => Some(left),
                naga::Expression::Math { arg, .. } => Some(arg),
                naga::Expression::As {
                    expr,
                    convert: Some(_),
                    ..
                } => Some(expr),
                _ => None,
            };
            if operand.is_some_and(is_float) {
                found.push(format!("{}: {h:?} {e:?}", f.name.as_deref().unwrap_or("?")));
            }
        }
    }
    found
}

/// The test kernel: 13 `u32` bit patterns per input (A, B, L, O), one `i32` result each.
fn test_kernel() -> String {
    format!(
        "{EXACT_INT_WGSL}
// ---- test entry point (tests/exact_int.rs) ----
@group(0) @binding(0) var<storage, read> xi_inputs: array<u32>;
@group(0) @binding(1) var<storage, read_write> xi_results: array<i32>;

fn xi_at(i: u32) -> f32 {{
    return bitcast<f32>(xi_inputs[i]);
}}

@compute @workgroup_size(64)
fn xi_main(@builtin(global_invocation_id) gid: vec3<u32>) {{
    let i = gid.x;
    if i >= arrayLength(&xi_results) {{
        return;
    }}
    let k = i * 13u;
    let a = vec3<f32>(xi_at(k), xi_at(k + 1u), xi_at(k + 2u));
    let b = vec3<f32>(xi_at(k + 3u), xi_at(k + 4u), xi_at(k + 5u));
    let l = vec4<f32>(xi_at(k + 6u), xi_at(k + 7u), xi_at(k + 8u), xi_at(k + 9u));
    let o = vec3<f32>(xi_at(k + 10u), xi_at(k + 11u), xi_at(k + 12u));
    xi_results[i] = orient_int(a, b, l, o);
}}
"
    )
}

fn naga_validates_exact_int_wgsl_alone_without_capabilities() {
    let on_disk = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders/exact_int.wgsl"),
    )
    .unwrap();
    assert_eq!(on_disk, EXACT_INT_WGSL, "rebuild the crate");
    let (m, info) = validate("exact_int.wgsl", EXACT_INT_WGSL);
    assert!(
        m.entry_points.is_empty(),
        "no entry points in the library module"
    );
    let f = m
        .functions
        .iter()
        .find(|(_, f)| f.name.as_deref() == Some("orient_int"))
        .expect("orient_int")
        .1;
    assert_eq!(f.arguments.len(), 4);
    // Every other function is an xi_ helper; every constant an XI_ one.
    for (_, g) in m.functions.iter() {
        let name = g.name.as_deref().unwrap();
        assert!(name == "orient_int" || name.starts_with("xi_"), "{name}");
    }
    for (_, c) in m.constants.iter() {
        let name = c.name.as_deref().unwrap_or("XI_?");
        assert!(name.starts_with("XI_"), "{name}");
    }
    // No floating-point arithmetic anywhere: the inputs are only bitcast.
    let float_ops = float_arithmetic(&m, &info);
    assert!(float_ops.is_empty(), "float arithmetic: {float_ops:#?}");
}

fn naga_validates_the_composed_test_kernel() {
    let (m, info) = validate("exact_int.wgsl + test entry point", &test_kernel());
    assert_eq!(m.entry_points.len(), 1);
    assert!(float_arithmetic(&m, &info).is_empty());
}

// ---- device ----------------------------------------------------------------------------------

/// Runs the test kernel on `inputs` and returns the device's `orient_int` results.
fn run_on_device(b: &WgpuBackend, inputs: &[Input]) -> Vec<i32> {
    use wgpu::util::DeviceExt;
    let device = b.device();
    let words: Vec<u32> = inputs
        .iter()
        .flat_map(|(a, b, l, o)| a.iter().chain(b).chain(l).chain(o).map(|x| x.to_bits()))
        .collect();
    let scopes = [
        device.push_error_scope(wgpu::ErrorFilter::Validation),
        device.push_error_scope(wgpu::ErrorFilter::Internal),
    ];
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("exact_int test kernel"),
        source: wgpu::ShaderSource::Wgsl(test_kernel().into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("exact_int"),
        layout: None,
        module: &module,
        entry_point: Some("xi_main"),
        compilation_options: wgpu::PipelineCompilationOptions::default(),
        cache: None,
    });
    let input_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("inputs"),
        contents: bytemuck::cast_slice(&words),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let size = (inputs.len() * 4) as u64;
    let out = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("results"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("staging"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: input_buf.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: out.as_entire_binding(),
            },
        ],
    });
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(inputs.len().div_ceil(64) as u32, 1, 1);
    }
    enc.copy_buffer_to_buffer(&out, 0, &staging, 0, size);
    b.queue().submit([enc.finish()]);
    for scope in scopes.into_iter().rev() {
        if let Some(e) = pollster::block_on(scope.pop()) {
            panic!("device error: {e}");
        }
    }
    staging.map_async(wgpu::MapMode::Read, .., |r| r.unwrap());
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let v = staging.get_mapped_range(..).unwrap();
    bytemuck::cast_slice::<u8, i32>(&v).to_vec()
}

fn gpu_orient_int_equals_twin_and_orient_exact() -> Outcome {
    let b = common::backend(
        "gpu_orient_int_equals_twin_and_orient_exact",
        WgpuOptions::default(),
    )?;
    let (mut inputs, adversarial) = adversarial_set();
    // The special-value pattern too, in every slot.
    for i in 0..13 {
        for &x in &SPECIALS {
            let (mut a, mut bb, mut l, mut o) = extremes()[i % 4];
            match i {
                0..=2 => a[i] = x,
                3..=5 => bb[i - 3] = x,
                6..=8 => o[i - 6] = x,
                _ => l[i - 9] = x,
            }
            inputs.push((a, bb, l, o));
        }
    }
    let got = run_on_device(&b, &inputs);
    assert_eq!(got.len(), inputs.len());
    let mut mismatches = Vec::new();
    let mut counts = [0usize; 3];
    for (&input, &g) in inputs.iter().zip(&got) {
        let (a, bb, l, o) = input;
        let twin = orient_int(a, bb, l, o);
        assert_eq!(twin, orient_exact(a, bb, l, o), "twin: {}", show(input));
        counts[(twin + 1) as usize] += 1;
        if g != i32::from(twin) {
            mismatches.push(format!("device {g}, twin {twin}: {}", show(input)));
        }
    }
    eprintln!(
        "{} inputs ({adversarial} adversarial) on the device: {counts:?} (neg, zero, pos)",
        inputs.len()
    );
    assert!(
        mismatches.is_empty(),
        "{} of {} device results differ; first: {:#?}",
        mismatches.len(),
        inputs.len(),
        &mismatches[..mismatches.len().min(8)]
    );
    Ok(())
}
