//! Independent exact oracle for the sign of the silhouette determinant, in big integers.
//!
//! Shared by the test crates without duplicating it: `crates/robust-math/tests/*.rs` use
//! `mod oracle;`, other crates' tests include this file with
//! `#[path = "<relative path>/robust-math/tests/oracle/mod.rs"] mod oracle;`. It deliberately
//! depends on nothing but `num-bigint` (no `shadowvol-*` crate), so it is a reference that
//! shares no code with the predicates it checks.
//!
//! # Method
//! Every finite `f32` is `m * 2^e` with an integer `m` (|m| < 2^24) and `e >= -149`. All inputs
//! are put on one integer grid `2^g` (`g` = the smallest exponent among them), so each becomes
//! an exact [`BigInt`]. With `A, B, O` and `L = (l, w)` on that grid,
//!
//! ```text
//! V = l * 2^g - w * A          (on the grid 2^(2g): the scaled L.xyz - L.w * A)
//! det = ((A - B) x V) . (O - A) (on the grid 2^(4g), a positive factor)
//! ```
//!
//! This is the translated triple product, not the crate's Laplace expansion into 2x2 minors.
//! [`det4_leibniz`] evaluates the same determinant a third way (the 24-term Leibniz sum of the
//! 4x4 matrix) so the oracle can be checked against itself.
#![allow(dead_code)]

use num_bigint::{BigInt, Sign};

/// `x = mantissa * 2^exponent` exactly, for a finite `f32`.
///
/// # Panics
/// Panics on NaN or infinity.
pub fn decompose(x: f32) -> (i64, i32) {
    assert!(x.is_finite(), "oracle input must be finite, got {x}");
    let bits = x.to_bits();
    let sign = if bits >> 31 == 1 { -1i64 } else { 1 };
    let exp_bits = ((bits >> 23) & 0xff) as i32;
    let frac = i64::from(bits & 0x7f_ffff);
    if exp_bits == 0 {
        (sign * frac, -149)
    } else {
        (sign * (frac | 0x80_0000), exp_bits - 150)
    }
}

/// The integer `x / 2^grid`, which must be exact (`grid` <= the exponent of `x`).
pub fn on_grid(x: f32, grid: i32) -> BigInt {
    let (m, e) = decompose(x);
    if m == 0 {
        return BigInt::from(0);
    }
    assert!(e >= grid, "grid 2^{grid} is finer than the exponent of {x}");
    BigInt::from(m) << ((e - grid) as usize)
}

fn min_exponent(values: &[f32]) -> i32 {
    values
        .iter()
        .filter(|v| **v != 0.0)
        .map(|&v| decompose(v).1)
        .min()
        .unwrap_or(0)
}

fn sign_of(x: &BigInt) -> i8 {
    match x.sign() {
        Sign::Plus => 1,
        Sign::Minus => -1,
        Sign::NoSign => 0,
    }
}

/// `((A - B) x V) . (O - A)` exactly, as an integer: the true value times a positive power of
/// two (so it has the sign of `det4 | A 1 ; B 1 ; L ; O 1 |`), and the grid exponent `g` used.
pub fn det_exact(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> (BigInt, i32) {
    let all = [
        a[0], a[1], a[2], b[0], b[1], b[2], l[0], l[1], l[2], l[3], o[0], o[1], o[2],
    ];
    let g = min_exponent(&all);
    let q = |x: f32| on_grid(x, g);
    let (ai, bi, oi) = (a.map(q), b.map(q), o.map(q));
    let lw = q(l[3]);
    // In grid units: true l = li 2^g and true w A = (lw ai) 2^(2g). V is scaled by one positive
    // power of two for all three components, which keeps the sign of the determinant.
    let e: Vec<BigInt> = (0..3).map(|i| &ai[i] - &bi[i]).collect();
    let d: Vec<BigInt> = (0..3).map(|i| &oi[i] - &ai[i]).collect();
    let v: Vec<BigInt> = (0..3)
        .map(|i| {
            let li = q(l[i]);
            let wa = &lw * &ai[i];
            if g <= 0 {
                // true = li 2^g - wa 2^(2g) = 2^(2g) (li 2^(-g) - wa)
                (li << ((-g) as usize)) - wa
            } else {
                // true = 2^g (li - wa 2^g)
                li - (wa << (g as usize))
            }
        })
        .collect();
    let n = [
        &e[1] * &v[2] - &e[2] * &v[1],
        &e[2] * &v[0] - &e[0] * &v[2],
        &e[0] * &v[1] - &e[1] * &v[0],
    ];
    let det = &n[0] * &d[0] + &n[1] * &d[1] + &n[2] * &d[2];
    (det, g)
}

/// Exact sign of `det4 | A 1 ; B 1 ; L ; O 1 |` (= `s(a, b, o)` for exact arithmetic).
pub fn sign_exact(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i8 {
    sign_of(&det_exact(a, b, l, o).0)
}

/// Sign of the same 4x4 determinant by the Leibniz formula over all 24 permutations, with all 16
/// entries on one grid (the `1` entries included). A third, independent evaluation.
pub fn det4_leibniz(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i8 {
    let rows = [
        [a[0], a[1], a[2], 1.0],
        [b[0], b[1], b[2], 1.0],
        l,
        [o[0], o[1], o[2], 1.0],
    ];
    let all: Vec<f32> = rows.iter().flatten().copied().collect();
    let g = min_exponent(&all);
    let m: Vec<Vec<BigInt>> = rows
        .iter()
        .map(|r| r.iter().map(|&x| on_grid(x, g)).collect())
        .collect();
    let mut total = BigInt::from(0);
    // Every 4-tuple of column indices; the ones with a repeated index are not permutations.
    for p0 in 0..4 {
        for p1 in 0..4 {
            for p2 in 0..4 {
                for p3 in 0..4 {
                    let perm = [p0, p1, p2, p3];
                    let mut seen = [false; 4];
                    if perm.iter().any(|&p| std::mem::replace(&mut seen[p], true)) {
                        continue;
                    }
                    let mut inversions = 0;
                    for i in 0..4 {
                        for j in i + 1..4 {
                            if perm[i] > perm[j] {
                                inversions += 1;
                            }
                        }
                    }
                    let prod = &m[0][perm[0]] * &m[1][perm[1]] * &m[2][perm[2]] * &m[3][perm[3]];
                    if inversions % 2 == 0 {
                        total += prod;
                    } else {
                        total -= prod;
                    }
                }
            }
        }
    }
    sign_of(&total)
}

/// `m(a, b)` of one edge by the oracle: the sum of [`sign_exact`] over its opposite vertices.
pub fn multiplicity(positions: &[[f32; 3]], a: u32, b: u32, ovs: &[u32], light: [f32; 4]) -> i32 {
    ovs.iter()
        .map(|&o| {
            i32::from(sign_exact(
                positions[a as usize],
                positions[b as usize],
                light,
                positions[o as usize],
            ))
        })
        .sum()
}

// ---- an emulation of f32 arithmetic, exact big-integer operations rounded once -------------

/// A finite `f32`-representable value `m * 2^e` kept exactly.
#[derive(Clone, Debug)]
pub struct Exact {
    m: BigInt,
    e: i32,
}

impl Exact {
    /// The exact value of a finite `f32`.
    pub fn of(x: f32) -> Exact {
        let (m, e) = decompose(x);
        Exact {
            m: BigInt::from(m),
            e,
        }
    }

    fn aligned(&self, other: &Exact) -> (BigInt, BigInt, i32) {
        let e = self.e.min(other.e);
        (
            &self.m << ((self.e - e) as usize),
            &other.m << ((other.e - e) as usize),
            e,
        )
    }

    /// The exact sum.
    pub fn add(&self, other: &Exact) -> Exact {
        let (a, b, e) = self.aligned(other);
        Exact { m: a + b, e }
    }

    /// The exact difference.
    pub fn sub(&self, other: &Exact) -> Exact {
        let (a, b, e) = self.aligned(other);
        Exact { m: a - b, e }
    }

    /// The exact product.
    pub fn mul(&self, other: &Exact) -> Exact {
        Exact {
            m: &self.m * &other.m,
            e: self.e + other.e,
        }
    }

    /// The sign, -1, 0 or 1.
    pub fn sign(&self) -> i8 {
        sign_of(&self.m)
    }

    /// Rounded to the nearest `f32`, ties to even, subnormals included (IEEE 754 binary32
    /// round-to-nearest).
    ///
    /// # Panics
    /// Panics when the rounded value overflows the `f32` range: the callers keep their inputs
    /// where every intermediate is finite.
    pub fn round(&self) -> f32 {
        if self.m.sign() == Sign::NoSign {
            return 0.0;
        }
        let negative = self.m.sign() == Sign::Minus;
        let mag = self.m.magnitude().clone();
        let bits = mag.bits() as i32;
        // The exponent of the last significand bit: 24 bits, but never below 2^-149.
        let q = (self.e + bits - 24).max(-149);
        let r = if q <= self.e {
            mag << ((self.e - q) as usize)
        } else {
            let shift = (q - self.e) as usize;
            let r = &mag >> shift;
            let rem = &mag - (&r << shift);
            let half = num_bigint::BigUint::from(1u8) << (shift - 1);
            let odd = r.bit(0);
            if rem > half || (rem == half && odd) {
                r + 1u8
            } else {
                r
            }
        };
        let r = u64::try_from(r).expect("at most 2^24");
        assert!(r <= 1 << 24);
        let v = r as f64 * 2f64.powi(q);
        assert!(v < 2f64.powi(128), "f32 overflow in the emulation");
        let v = v as f32; // exact: r has at most 25 significant bits, and r = 2^24 is a power of 2
        if negative {
            -v
        } else {
            v
        }
    }
}

/// One `f32` operation emulated: exact result, rounded once.
fn op(x: f32, y: f32, f: impl Fn(&Exact, &Exact) -> Exact) -> f32 {
    f(&Exact::of(x), &Exact::of(y)).round()
}

/// The `f32` evaluation of `sgn(((A - B) x V) . (O - A))` with `V = L.xyz - L.w * A`, operation by
/// operation in the documented order, every operation emulated by [`Exact`]:
///
/// ```text
/// v = (lx - lw*ax, ly - lw*ay, lz - lw*az); e = A - B; d = O - A
/// n = (ey*vz - ez*vy, ez*vx - ex*vz, ex*vy - ey*vx)
/// s = sgn((nx*dx + ny*dy) + nz*dz)
/// ```
pub fn sign_f32_emulated(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i8 {
    let add = |x, y| op(x, y, Exact::add);
    let sub = |x, y| op(x, y, Exact::sub);
    let mul = |x, y| op(x, y, Exact::mul);
    let v: Vec<f32> = (0..3).map(|i| sub(l[i], mul(l[3], a[i]))).collect();
    let e: Vec<f32> = (0..3).map(|i| sub(a[i], b[i])).collect();
    let d: Vec<f32> = (0..3).map(|i| sub(o[i], a[i])).collect();
    let n = [
        sub(mul(e[1], v[2]), mul(e[2], v[1])),
        sub(mul(e[2], v[0]), mul(e[0], v[2])),
        sub(mul(e[0], v[1]), mul(e[1], v[0])),
    ];
    let s = add(add(mul(n[0], d[0]), mul(n[1], d[1])), mul(n[2], d[2]));
    Exact::of(s).sign()
}
