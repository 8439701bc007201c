//! One sign for every light of a box: the triangles a light's samples share.
//!
//! For lights with one common `w`, the determinant `det4(A, B, L, O) = N·(L.xyz − w A)` with
//! `N = (O − A) × (A − B)` is affine in `L.xyz`. Over the axis-aligned box spanned by the lights
//! it takes its extremes at the box's corners, so a triangle whose plane does not cut the box has
//! one sign for every light in it. [`LightBox::sign`] decides that sign exactly:
//!
//! 1. [`LightBox::filter`], a certified `f64` filter: the value at the box's centre `c`, plus or
//!    minus the radius `Σ |N_i| h_i`, with a forward error bound. It proves "one sign for the
//!    whole box" ([`BoxFilter::Shared`]) or "both signs in the box" ([`BoxFilter::Cut`]), or
//!    says it cannot ([`BoxFilter::Uncertain`]);
//! 2. only then, [`LightBox::sign_at_corners`]: the exact predicate ([`orient_exact`]) at the
//!    box's 8 corners (`f32` values: the lights' minima and maxima).
//!
//! The result is a property of the box, not of the lights: a triangle shared by the box has, for
//! every light in the box, exactly the sign `orient_exact` gives that light alone.
//!
//! # The filter and its bound
//! With `u = 2⁻⁵³`, inputs `A`, `B`, `O` (`f32`), the lights' minima `lo` and maxima `hi`
//! (`f32`) and their `w` (`f32`), every operation below is one `f64` operation, in this order:
//!
//! ```text
//! c_i = (lo_i + hi_i) * 0.5     h_i = (hi_i - lo_i) * 0.5     g_i = h_i + |c_i|  (once a box)
//! e = A - B                     d = O - A
//! (p1, q1, p2, q2, p3, q3) = (d.y*e.z, d.z*e.y, d.z*e.x, d.x*e.z, d.x*e.y, d.y*e.x)
//! N = (p1 - q1, p2 - q2, p3 - q3)          M = (|p1| + |q1|, |p2| + |q2|, |p3| + |q3|)
//! v_i = c_i - w*A_i
//! f = (N.x*v.x + N.y*v.y) + N.z*v.z
//! r = (|N.x|*h.x + |N.y|*h.y) + |N.z|*h.z
//! p = (M.x*(|v.x| + g.x) + M.y*(|v.y| + g.y)) + M.z*(|v.z| + g.z)
//! shared +1 when f - r > ε p;  shared −1 when −(f + r) > ε p;  else shared 0 when p = 0;
//! cut when −(f − r) > ε p and f + r > ε p;  uncertain otherwise.      ε = 2⁻⁴⁸ = 32 u
//! ```
//!
//! Every value is finite and no non-zero result falls below `2⁻⁷⁰⁰` (the inputs are `f32`:
//! multiples of `2⁻¹⁴⁹` below `2¹²⁸`; `w A` is exact in `f64`), so each operation is exact up to
//! one relative rounding `(1 + δ)`, `|δ| ≤ u`. Then, for every light `L` in the box:
//!
//! * `|L_i − c_i| ≤ h_i + 2u g_i` (the roundings of `c` and `h`);
//! * for the exact `N*` and `M*_i = |p*_i| + |q*_i|`: `|N_i − N*_i| ≤ γ₄ M*_i` and
//!   `M*_i ≤ M_i / (1 − γ₄)` (`γ_k = k u / (1 − k u)`), so the computed `f` is within
//!   `8.01 u Σ M_i |v_i|` of `N*·(c − w A)`, and `Σ |N*_i| (h_i + 2u g_i) ≤ r + 9.04 u Σ M_i g_i`;
//! * so `N*·(L.xyz − w A)` lies within `f ± (r + 9.05 u p)`.
//!
//! `ε p` exceeds `9.05 u p` with every rounding of the test included (a safety factor above 3),
//! so a shared sign is proven for every light in the box. `p = 0` means every term of every
//! light's determinant is 0. [`BoxFilter::Cut`] is proven the same way against the exact box
//! (`17.1 u p`): the determinant is negative at one corner and positive at another.

mod device;

pub use device::{box_sign_f32, device_input_ok, DeviceBox, BOX_INPUT_MAX, BOX_PERM_MIN};

use crate::exact::orient_exact;
use crate::filter::sign_of_f64;

/// Relative error constant of [`LightBox::filter`] (`2⁻⁴⁸ = 32 u`; the module documentation
/// proves `9.05 u` for a shared sign and `17.1 u` for a cut).
pub const BOX_FILTER_EPS: f64 = 1.0 / 281_474_976_710_656.0;

/// What [`LightBox::filter`] proves about a triangle and a box of lights.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoxFilter {
    /// Every light of the box gives the triangle this sign (`1`, `-1`, or `0` for a triangle
    /// whose determinant vanishes over the whole box).
    Shared(i8),
    /// The triangle's plane cuts the box: its determinant is negative at one corner and positive
    /// at another.
    Cut,
    /// The filter cannot tell: decide at the corners ([`LightBox::sign_at_corners`]).
    Uncertain,
}

/// The axis-aligned box spanned by several lights with one common `w` (object-space `f32`
/// lights, as the backends evaluate them), with the terms [`LightBox::filter`] needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightBox {
    lo: [f32; 3],
    hi: [f32; 3],
    w: f32,
    centre: [f64; 3],
    half: [f64; 3],
    reach: [f64; 3],
}

impl LightBox {
    /// The box of `lights` (`[x, y, z, w]`), or `None` when there are none or their `w` differ.
    ///
    /// For a fixed `w` the determinant is affine in `L.xyz`, which is what the box relies on;
    /// points (`w = 1`), directions (`w = 0`) and any other common `w` qualify. Lights with
    /// different `w` (points mixed with directions) span no such box: each is decided on its own.
    #[must_use]
    pub fn of(lights: &[[f32; 4]]) -> Option<Self> {
        let first = lights.first()?;
        let w = first[3];
        let (mut lo, mut hi) = (
            [first[0], first[1], first[2]],
            [first[0], first[1], first[2]],
        );
        for l in lights {
            if l[3] != w {
                return None;
            }
            for i in 0..3 {
                lo[i] = lo[i].min(l[i]);
                hi[i] = hi[i].max(l[i]);
            }
        }
        Some(Self::from_bounds(lo, hi, w))
    }

    /// The box from its corners `lo <= hi` (per coordinate, finite) and the lights' common `w`.
    ///
    /// # Panics
    /// Debug builds assert `lo <= hi` and finite values.
    #[must_use]
    pub fn from_bounds(lo: [f32; 3], hi: [f32; 3], w: f32) -> Self {
        debug_assert!((0..3).all(|i| lo[i] <= hi[i] && hi[i].is_finite() && lo[i].is_finite()));
        let mut centre = [0.0; 3];
        let mut half = [0.0; 3];
        let mut reach = [0.0; 3];
        for i in 0..3 {
            let (l, h) = (f64::from(lo[i]), f64::from(hi[i]));
            centre[i] = (l + h) * 0.5;
            half[i] = (h - l) * 0.5;
            reach[i] = half[i] + centre[i].abs();
        }
        Self {
            lo,
            hi,
            w,
            centre,
            half,
            reach,
        }
    }

    /// The smallest coordinates of the lights.
    #[must_use]
    pub fn lo(&self) -> [f32; 3] {
        self.lo
    }

    /// The largest coordinates of the lights.
    #[must_use]
    pub fn hi(&self) -> [f32; 3] {
        self.hi
    }

    /// The lights' common `w`.
    #[must_use]
    pub fn w(&self) -> f32 {
        self.w
    }

    /// The filter's `c`: `(lo + hi) * 0.5` in `f64`.
    #[must_use]
    pub fn centre(&self) -> [f64; 3] {
        self.centre
    }

    /// The filter's `h`: `(hi - lo) * 0.5` in `f64`.
    #[must_use]
    pub fn half(&self) -> [f64; 3] {
        self.half
    }

    /// The filter's `g`: `h + |c|` in `f64`.
    #[must_use]
    pub fn reach(&self) -> [f64; 3] {
        self.reach
    }

    /// Whether `light` lies in the box (the same `w`, every coordinate within the bounds).
    #[must_use]
    pub fn contains(&self, light: [f32; 4]) -> bool {
        light[3] == self.w && (0..3).all(|i| self.lo[i] <= light[i] && light[i] <= self.hi[i])
    }

    /// The 8 corners as lights `[x, y, z, w]`; corner `k` takes `hi` in coordinate `i` where bit
    /// `i` of `k` is set.
    #[must_use]
    pub fn corners(&self) -> [[f32; 4]; 8] {
        std::array::from_fn(|k| {
            let c = |i: usize| {
                if k >> i & 1 == 1 {
                    self.hi[i]
                } else {
                    self.lo[i]
                }
            };
            [c(0), c(1), c(2), self.w]
        })
    }

    /// The certified filter of the module documentation for the triangle `(a, b, o)` (any
    /// vertex order; the sign is that of `det4(A, B, L, O)`).
    #[must_use]
    #[inline]
    pub fn filter(&self, a: [f32; 3], b: [f32; 3], o: [f32; 3]) -> BoxFilter {
        let (f, r, p) = self.terms(a, b, o);
        decide(f, r, p)
    }

    /// The filter's `(f, r, p)` for the triangle `(a, b, o)`, with the operations (and order)
    /// of the module documentation.
    #[must_use]
    #[inline]
    pub fn terms(&self, a: [f32; 3], b: [f32; 3], o: [f32; 3]) -> (f64, f64, f64) {
        let a = a.map(f64::from);
        let b = b.map(f64::from);
        let o = o.map(f64::from);
        let w = f64::from(self.w);
        let e = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let d = [o[0] - a[0], o[1] - a[1], o[2] - a[2]];
        let pq = [
            d[1] * e[2],
            d[2] * e[1],
            d[2] * e[0],
            d[0] * e[2],
            d[0] * e[1],
            d[1] * e[0],
        ];
        let n = [pq[0] - pq[1], pq[2] - pq[3], pq[4] - pq[5]];
        let m = [
            pq[0].abs() + pq[1].abs(),
            pq[2].abs() + pq[3].abs(),
            pq[4].abs() + pq[5].abs(),
        ];
        let (c, h, g) = (self.centre, self.half, self.reach);
        let v = [c[0] - w * a[0], c[1] - w * a[1], c[2] - w * a[2]];
        let f = (n[0] * v[0] + n[1] * v[1]) + n[2] * v[2];
        let r = (n[0].abs() * h[0] + n[1].abs() * h[1]) + n[2].abs() * h[2];
        let p =
            (m[0] * (v[0].abs() + g[0]) + m[1] * (v[1].abs() + g[1])) + m[2] * (v[2].abs() + g[2]);
        (f, r, p)
    }

    /// The exact sign shared by the whole box, from the exact predicate at its 8 corners:
    /// `Some(s)` when every corner gives `s` (an affine function with one sign at a box's
    /// corners has it everywhere in the box; 0 at every corner is 0 everywhere), `None` when
    /// two corners differ.
    #[must_use]
    pub fn sign_at_corners(&self, a: [f32; 3], b: [f32; 3], o: [f32; 3]) -> Option<i8> {
        // Opposite corners first: a plane through the box most often separates them.
        const ORDER: [usize; 8] = [0, 7, 1, 6, 2, 5, 3, 4];
        let corners = self.corners();
        let first = orient_exact(a, b, corners[ORDER[0]], o);
        ORDER[1..]
            .iter()
            .all(|&k| orient_exact(a, b, corners[k], o) == first)
            .then_some(first)
    }

    /// The exact sign the triangle `(a, b, o)` has for every light in the box, or `None` when
    /// its plane cuts the box: [`LightBox::filter`], then, where it cannot tell,
    /// [`LightBox::sign_at_corners`].
    #[must_use]
    #[inline]
    pub fn sign(&self, a: [f32; 3], b: [f32; 3], o: [f32; 3]) -> Option<i8> {
        match self.filter(a, b, o) {
            BoxFilter::Shared(s) => Some(s),
            BoxFilter::Cut => None,
            BoxFilter::Uncertain => self.sign_at_corners(a, b, o),
        }
    }
}

/// The decision of [`LightBox::filter`] from its `(f, r, p)`, with [`BOX_FILTER_EPS`].
#[must_use]
#[inline]
pub fn decide(f: f64, r: f64, p: f64) -> BoxFilter {
    let bound = BOX_FILTER_EPS * p;
    let (low, high) = (f - r, f + r);
    if low > bound || -high > bound {
        BoxFilter::Shared(sign_of_f64(f))
    } else if p == 0.0 {
        BoxFilter::Shared(0)
    } else if -low > bound && high > bound {
        BoxFilter::Cut
    } else {
        BoxFilter::Uncertain
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A xorshift32 generator (deterministic test inputs; the device filter's tests use it too).
    pub(super) fn xorshift(mut x: u32) -> impl FnMut() -> u32 {
        move || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        }
    }

    #[test]
    fn box_of_lights_and_its_corners() {
        let lights = [
            [1.0, -2.0, 3.0, 1.0],
            [0.5, 4.0, 3.0, 1.0],
            [2.0, 0.0, -1.0, 1.0],
        ];
        let b = LightBox::of(&lights).unwrap();
        assert_eq!(
            (b.lo(), b.hi(), b.w()),
            ([0.5, -2.0, -1.0], [2.0, 4.0, 3.0], 1.0)
        );
        assert_eq!(b.corners()[0], [0.5, -2.0, -1.0, 1.0]);
        assert_eq!(b.corners()[5], [2.0, -2.0, 3.0, 1.0]);
        assert!(lights.iter().all(|&l| b.contains(l)));
        assert!(!b.contains([0.5, -2.0, -1.0, 0.0]));
        assert_eq!(b.centre(), [1.25, 1.0, 1.0]);
        assert_eq!(b.half(), [0.75, 3.0, 2.0]);
        assert_eq!(b.reach(), [2.0, 4.0, 3.0]);
        // Points mixed with directions span no box; nor does an empty list.
        assert!(LightBox::of(&[[1.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0]]).is_none());
        assert!(LightBox::of(&[]).is_none());
    }

    /// The filter's decisions against the exact corner test, and a shared sign against the
    /// exact sign of every light inside the box, on random, touching and degenerate inputs.
    #[test]
    fn filter_and_sign_agree_with_the_exact_corners() {
        let mut rnd = xorshift(0x1234_5679);
        let mut f = move || (rnd() % 2001) as f32 / 100.0 - 10.0;
        let (mut shared, mut cut, mut uncertain, mut touching) = (0, 0, 0, 0);
        for round in 0..20_000u32 {
            let w = [1.0, 0.0, 0.5][(round % 3) as usize];
            let (a, b, o) = ([f(), f(), f()], [f(), f(), f()], [f(), f(), f()]);
            let size = [0.0, 1e-3, 0.1, 2.0][(round / 3 % 4) as usize];
            let base = [f(), f(), f()];
            let mut lights: Vec<[f32; 4]> = (0..5)
                .map(|_| {
                    let mut s = || f() / 10.0 * size;
                    [base[0] + s(), base[1] + s(), base[2] + s(), w]
                })
                .collect();
            if round % 5 == 0 {
                // A light on the triangle's plane: at a vertex, or along an edge for w = 0.
                lights.push(if w == 0.0 {
                    [a[0] - b[0], a[1] - b[1], a[2] - b[2], 0.0]
                } else {
                    [a[0] * w, a[1] * w, a[2] * w, w]
                });
            }
            let bx = LightBox::of(&lights).unwrap();
            let exact = bx.sign_at_corners(a, b, o);
            match bx.filter(a, b, o) {
                BoxFilter::Shared(s) => {
                    shared += 1;
                    assert_eq!(Some(s), exact, "{a:?} {b:?} {o:?} {bx:?}");
                }
                BoxFilter::Cut => {
                    cut += 1;
                    assert_eq!(exact, None, "{a:?} {b:?} {o:?} {bx:?}");
                }
                BoxFilter::Uncertain => uncertain += 1,
            }
            assert_eq!(bx.sign(a, b, o), exact);
            if let Some(s) = exact {
                for l in &lights {
                    assert_eq!(orient_exact(a, b, *l, o), s, "{l:?} in {bx:?}");
                }
            } else if lights.iter().any(|&l| orient_exact(a, b, l, o) == 0) {
                touching += 1;
            }
        }
        assert!(shared > 1000 && cut > 1000, "{shared} shared, {cut} cut");
        assert!(uncertain > 0 && touching > 0, "{uncertain} {touching}");
    }

    /// A box with a corner exactly on the triangle's plane and the rest on one side: the value
    /// at the corner is 0, so no sign is shared; the filter must not claim one.
    #[test]
    fn a_box_touching_the_plane_at_a_corner_shares_no_sign() {
        let (a, b, o) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        // The plane z = 0; lights at z in [0, 0.5].
        let bx = LightBox::of(&[[0.2, 0.2, 0.0, 1.0], [0.7, 0.4, 0.5, 1.0]]).unwrap();
        assert_eq!(bx.filter(a, b, o), BoxFilter::Uncertain);
        assert_eq!(bx.sign(a, b, o), None);
        // Lifted off the plane, one sign for the whole box, proven by the filter alone.
        let up = LightBox::of(&[[0.2, 0.2, 0.25, 1.0], [0.7, 0.4, 0.5, 1.0]]).unwrap();
        let s = orient_exact(a, b, [0.2, 0.2, 0.25, 1.0], o);
        assert_eq!(up.filter(a, b, o), BoxFilter::Shared(s));
        // A degenerate box (every light the same) is its one light's sign.
        let one = LightBox::of(&[[0.3, 0.1, 0.0, 1.0]; 3]).unwrap();
        assert_eq!(one.sign(a, b, o), Some(0));
        // A flat box lying in the plane: 0 for every light, shared.
        let flat = LightBox::of(&[[0.3, 0.1, 0.0, 1.0], [2.0, -5.0, 0.0, 1.0]]).unwrap();
        assert_eq!(flat.sign(a, b, o), Some(0));
    }

    /// Tilted triangles with their vertex `B` at a corner of the box and the box on one side
    /// of their plane: the value at `B` is exactly 0, and `f - r` is rounding noise around 0
    /// (`f` is evaluated from `A`), so no non-zero sign may be certified.
    #[test]
    fn tilted_planes_through_a_corner_are_never_certified() {
        let mut rnd = xorshift(0xBEEF_0001);
        let mut f = move || (rnd() % 200_001) as f32 / 10_000.0 - 10.0;
        let mut touching = 0;
        for _ in 0..20_000 {
            let (a, b, o) = ([f(), f(), f()], [f(), f(), f()], [f(), f(), f()]);
            let (d, e) = (
                [0, 1, 2].map(|i| o[i] - a[i]),
                [0, 1, 2].map(|i| a[i] - b[i]),
            );
            let n = [
                d[1] * e[2] - d[2] * e[1],
                d[2] * e[0] - d[0] * e[2],
                d[0] * e[1] - d[1] * e[0],
            ];
            let step = [0.5f32, 0.25, 0.125];
            let mut lo = b;
            let mut hi = b;
            for i in 0..3 {
                if n[i] >= 0.0 {
                    hi[i] = b[i] + step[i];
                } else {
                    lo[i] = b[i] - step[i];
                }
            }
            let bx = LightBox::from_bounds(lo, hi, 1.0);
            let got = bx.filter(a, b, o);
            assert!(
                !matches!(got, BoxFilter::Shared(s) if s != 0),
                "corner B is on the plane: {a:?} {b:?} {o:?} {got:?}"
            );
            assert!(!matches!(bx.sign(a, b, o), Some(s) if s != 0));
            touching += usize::from(got == BoxFilter::Uncertain);
        }
        assert!(touching > 10_000, "{touching}");
    }
}
