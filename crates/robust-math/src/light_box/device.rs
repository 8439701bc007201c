//! The box filter in `f32`, as a GPU evaluates it: the CPU twin of `box_sign` in
//! `shaders/resident_extract.wgsl`, operation for operation.
//!
//! WGSL has no `f64`, so the GPU pipeline certifies a shared sign with `f32` arithmetic. The box
//! is given as a centre `c` and a half-extent `h` ([`DeviceBox`], computed on the host) whose
//! real box `[c − h, c + h]` contains every light of the [`LightBox`] exactly, so no rounding of
//! the box enters the bound. With `u = 2⁻²⁴` the operations are those of the `f64` filter:
//!
//! ```text
//! e = A - B    d = O - A    v_i = c_i - w*A_i    g_i = h_i + |c_i|
//! (p1, q1, p2, q2, p3, q3) = (d.y*e.z, d.z*e.y, d.z*e.x, d.x*e.z, d.x*e.y, d.y*e.x)
//! N = (p1 - q1, p2 - q2, p3 - q3)          M = (|p1| + |q1|, |p2| + |q2|, |p3| + |q3|)
//! f = (N.x*v.x + N.y*v.y) + N.z*v.z
//! r = (|N.x|*h.x + |N.y|*h.y) + |N.z|*h.z
//! p = (M.x*(|v.x| + g.x) + M.y*(|v.y| + g.y)) + M.z*(|v.z| + g.z)
//! +1 when f - r > ε p;  −1 when −(f + r) > ε p;  else none.       ε = 2⁻¹⁹ = 32 u
//! ```
//!
//! The argument of [`super`] (each operation one relative rounding; `w A` exact for `w` in
//! {0, 1}) bounds `N*·(L.xyz − w A)` for every `L` in the box by `f ± (r + 9.05 u p)`; here
//! `|L_i − c_i| ≤ h_i` holds exactly, which only tightens it. The guards keep that argument valid
//! on a device that contracts `a * b + c` into a fused operation (one rounding instead of two, the
//! same bound) or flushes subnormals to zero:
//! - `w` is 0 or 1;
//! - every coordinate of `A`, `B`, `O` and `c`, and every `h_i`, is 0 or of magnitude in
//!   `[2⁻⁴⁰, 2³⁹]`: differences of such values are multiples of `2⁻⁶³`, never subnormal, and
//!   below `2⁴⁰`;
//! - every `e_i`, `d_i`, `v_i` is 0 or of magnitude at least `2⁻⁴⁰`, so the products are normal;
//! - `p ≥ 2⁻⁶⁰`: what underflow can still lose in `f` and `r` (a few times `2⁻¹²⁶` absolute, even
//!   flushed) is far below `(32 − 9.05) u p ≥ 2⁻⁷⁹`.
//!
//! Only a strict shared sign is reported. A triangle the filter leaves (its plane cuts the box,
//! or it cannot tell, or the determinant vanishes) is decided for each light on its own, which is
//! exact. A strict sign for the box also means no light of the box lies on the triangle's plane,
//! so none touches a vertex.

use super::LightBox;
use crate::filter::{sign_of_f32, F32_FILTER_MIN};
use crate::F32_FILTER_EPS;

/// Largest magnitude of an input coordinate, `c_i` or `h_i` ([`device_input_ok`]): `2³⁹`.
pub const BOX_INPUT_MAX: f32 = 549_755_813_888.0;
/// Smallest `p` the `f32` box filter certifies against (`2⁻⁶⁰`).
pub const BOX_PERM_MIN: f32 = 1.0 / 1_152_921_504_606_846_976.0;

/// A [`LightBox`] as the GPU reads it: `f32` centre and half-extent whose real box contains the
/// lights' box exactly, and the lights' `w`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviceBox {
    /// The centre `c`.
    pub centre: [f32; 3],
    /// The half-extent `h` (non-negative): `[c − h, c + h] ⊇ [lo, hi]` in real arithmetic.
    pub half: [f32; 3],
    /// The lights' common `w`.
    pub w: f32,
}

/// Whether `x` is 0 or of magnitude in `[2⁻⁴⁰, 2³⁹]`: the inputs the `f32` box filter takes.
#[must_use]
#[inline]
pub fn device_input_ok(x: f32) -> bool {
    let m = x.abs();
    x == 0.0 || (F32_FILTER_MIN..=BOX_INPUT_MAX).contains(&m)
}

/// Whether a difference `x` is 0 or of magnitude at least `2⁻⁴⁰`.
#[inline]
fn diff_ok(x: f32) -> bool {
    x == 0.0 || x.abs() >= F32_FILTER_MIN
}

/// The smallest `f32` at least `x` for finite `x >= 0`.
fn up(x: f64) -> f32 {
    let r = x as f32;
    if f64::from(r) >= x {
        r
    } else {
        f32::from_bits(r.to_bits() + 1)
    }
}

impl LightBox {
    /// The box as the GPU pipeline's triangle pass reads it: `c` the `f32` nearest the centre,
    /// `h` the smallest `f32` with `[c − h, c + h] ⊇ [lo, hi]` (both in real arithmetic), or
    /// `None` when `w` is not 0 or 1, or a coordinate of `c` or `h` is outside what
    /// [`box_sign_f32`] takes ([`device_input_ok`]): such a box is not shared on the device.
    #[must_use]
    pub fn device_box(&self) -> Option<DeviceBox> {
        if self.w != 0.0 && self.w != 1.0 {
            return None;
        }
        let (lo, hi) = (self.lo, self.hi);
        let mut centre = [0.0f32; 3];
        let mut half = [0.0f32; 3];
        for i in 0..3 {
            let (l, h) = (f64::from(lo[i]), f64::from(hi[i]));
            let c = ((l + h) * 0.5) as f32;
            // The larger distance from `c` to an end, rounded up in `f64` and again in `f32`:
            // `f64` differences of these `f32` values are exact unless their exponents are far
            // apart, and one `f64` ulp more covers that case.
            let c64 = f64::from(c);
            let d = (h - c64).max(c64 - l);
            half[i] = if d == 0.0 {
                0.0
            } else {
                up(d * (1.0 + f64::EPSILON))
            };
            centre[i] = c;
        }
        let ok = centre.iter().chain(&half).all(|&x| device_input_ok(x));
        ok.then_some(DeviceBox {
            centre,
            half,
            w: self.w,
        })
    }
}

/// The sign every light of `bx` gives the triangle `(a, b, o)` (that of `det4(A, B, L, O)`),
/// when the `f32` filter of the module documentation certifies a strict one: `Some(1)` or
/// `Some(-1)`; `None` otherwise (the plane cuts the box, or the filter cannot tell). The CPU
/// twin of the GPU pipeline's `box_sign`.
#[must_use]
pub fn box_sign_f32(a: [f32; 3], b: [f32; 3], o: [f32; 3], bx: &DeviceBox) -> Option<i8> {
    let (c, h, w) = (bx.centre, bx.half, bx.w);
    if w != 0.0 && w != 1.0 {
        return None;
    }
    let inputs = a.iter().chain(&b).chain(&o).chain(&c).chain(&h);
    if !inputs.into_iter().all(|&x| device_input_ok(x)) {
        return None;
    }
    let e = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let d = [o[0] - a[0], o[1] - a[1], o[2] - a[2]];
    let v = [c[0] - w * a[0], c[1] - w * a[1], c[2] - w * a[2]];
    if !e.iter().chain(&d).chain(&v).all(|&x| diff_ok(x)) {
        return None;
    }
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
    let g = [h[0] + c[0].abs(), h[1] + c[1].abs(), h[2] + c[2].abs()];
    let f = (n[0] * v[0] + n[1] * v[1]) + n[2] * v[2];
    let r = (n[0].abs() * h[0] + n[1].abs() * h[1]) + n[2].abs() * h[2];
    let p = (m[0] * (v[0].abs() + g[0]) + m[1] * (v[1].abs() + g[1])) + m[2] * (v[2].abs() + g[2]);
    if p < BOX_PERM_MIN {
        return None;
    }
    let bound = F32_FILTER_EPS * p;
    if f - r > bound || -(f + r) > bound {
        Some(sign_of_f32(f))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::xorshift;
    use super::*;
    use crate::exact::orient_exact;

    #[test]
    fn the_device_box_contains_the_lights_box() {
        let lights = [[0.1f32, -3.0, 1e-3, 1.0], [0.3, 2.5, 7.0, 1.0]];
        let bx = LightBox::of(&lights).unwrap().device_box().unwrap();
        for l in lights {
            for (i, &x) in l.iter().take(3).enumerate() {
                let (c, h) = (f64::from(bx.centre[i]), f64::from(bx.half[i]));
                assert!(c - h <= f64::from(x) && f64::from(x) <= c + h, "{bx:?}");
            }
        }
        // One light: a box of no extent, centred on it exactly.
        let one = LightBox::of(&lights[..1]).unwrap().device_box().unwrap();
        assert_eq!((one.centre, one.half), ([0.1, -3.0, 1e-3], [0.0; 3]));
        // No device box for w outside {0, 1}, nor for a coordinate beyond 2^39.
        assert!(LightBox::of(&[[0.0, 0.0, 0.0, 0.5]])
            .unwrap()
            .device_box()
            .is_none());
        assert!(LightBox::of(&[[1e12, 0.0, 0.0, 1.0]])
            .unwrap()
            .device_box()
            .is_none());
    }

    /// A certified sign is the exact sign of every light in the box, on random triangles and
    /// on boxes with a light exactly on the triangle's plane (where a filter that ignores its
    /// rounding would claim a strict sign).
    #[test]
    fn a_certified_sign_is_every_lights_exact_sign() {
        let mut rnd = xorshift(0x2468_ace1);
        let mut f = move || (rnd() % 40_001) as f32 / 2000.0 - 10.0;
        let (mut shared, mut left) = (0, 0);
        for round in 0..30_000u32 {
            let w = [1.0, 0.0][(round % 2) as usize];
            let (a, b, o) = ([f(), f(), f()], [f(), f(), f()], [f(), f(), f()]);
            let size = [0.0, 1e-4, 1e-2, 0.5][(round / 2 % 4) as usize];
            let base = [f(), f(), f()];
            let mut lights: Vec<[f32; 4]> = (0..6)
                .map(|_| {
                    let mut s = || f() / 10.0 * size;
                    [base[0] + s(), base[1] + s(), base[2] + s(), w]
                })
                .collect();
            if round % 3 == 0 {
                // A light on the plane: at a vertex (points) or along an edge (directions).
                lights.push(if w == 0.0 {
                    [a[0] - b[0], a[1] - b[1], a[2] - b[2], 0.0]
                } else {
                    [a[0], a[1], a[2], 1.0]
                });
            }
            let Some(bx) = LightBox::of(&lights).unwrap().device_box() else {
                continue;
            };
            match box_sign_f32(a, b, o, &bx) {
                Some(s) => {
                    shared += 1;
                    for &l in &lights {
                        assert_eq!(orient_exact(a, b, l, o), s, "{a:?} {b:?} {o:?} {l:?}");
                    }
                }
                None => left += 1,
            }
        }
        assert!(shared > 10_000 && left > 1_000, "{shared} {left}");
    }

    /// Near-coplanar boxes: a light a few ulps off the plane. Every certified sign is exact.
    #[test]
    fn boxes_grazing_the_plane_are_never_certified_wrongly() {
        let mut rnd = xorshift(0x1357_9bdf);
        let mut f = move || (rnd() % 2001) as f32 / 100.0 - 10.0;
        for _ in 0..20_000 {
            let (a, b, o) = ([f(), f(), f()], [f(), f(), f()], [f(), f(), f()]);
            // A point on the plane (a + s(b - a) + t(o - a)), rounded to f32, then nudged.
            let (s, t) = (f() / 20.0, f() / 20.0);
            let on: [f32; 3] =
                std::array::from_fn(|i| a[i] + s * (b[i] - a[i]) + t * (o[i] - a[i]));
            let nudged: [f32; 3] = std::array::from_fn(|i| {
                f32::from_bits(on[i].to_bits().wrapping_add((f() as i32 % 3) as u32))
            });
            let lights = [
                [on[0], on[1], on[2], 1.0],
                [nudged[0], nudged[1], nudged[2], 1.0],
            ];
            let Some(bx) = LightBox::of(&lights).unwrap().device_box() else {
                continue;
            };
            if let Some(s) = box_sign_f32(a, b, o, &bx) {
                for &l in &lights {
                    assert_eq!(orient_exact(a, b, l, o), s, "{a:?} {b:?} {o:?} {l:?}");
                }
            }
        }
    }
}
