//! The CPU twin of the WGSL functions the silhouette kernel and the renderer's resident pass
//! share (`shaders/silhouette.wgsl`, `shaders/exact_f64.wgsl` and `shaders/exact_int.wgsl`):
//! each function here mirrors one WGSL function, statement for statement. The `wgpu` backend's
//! `twin` runs them as its two kernel steps over a whole scene, the renderer's as its triangle
//! and edge passes. When a GPU disagrees with the `cpu` backend, run the twin on the same input:
//! if the twin is right, the fault is in the device or the WGSL translation; if it is wrong too,
//! it is in the algorithm (vello keeps CPU shaders for the same reason).
//!
//! The only intended difference from the device is floating-point contraction: Rust never fuses
//! `a * b + c`, a GPU compiler may. That can change the last bits of the `f32` modes, never the
//! exact mode, whose filters certify only signs that hold with contraction too.
//!
//! ```
//! use shadowvol_gpu::twin::{orient_int, triangle_sign};
//! use shadowvol_robust_math::{orient_exact, Accuracy};
//! use shadowvol_silhouette::gpu::ExactFilter;
//!
//! let (a, b, o, l) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.2, 0.3, 5.0, 1.0]);
//! assert_eq!(orient_int(a, b, l, o), orient_exact(a, b, l, o));
//! let (sign, fallback) = triangle_sign(Accuracy::Exact, ExactFilter::F32, true, [a, b, o], l);
//! assert_eq!((sign, fallback), (Some(orient_exact(a, b, l, o)), false));
//! ```

use crate::shaders::{GPU_F32_INPUT_MAX, GPU_F32_PERM_MIN, GPU_F64_FILTER_EPS, TOUCH};
use shadowvol_robust_math::filter::{self, TermsF32};
use shadowvol_robust_math::{sign_f32, Accuracy, F32_FILTER_EPS};
use shadowvol_silhouette::gpu::{ExactFilter, TableLayout};

/// Twin of WGSL `filter_f32`: robust-math's `orient_filter_f32` (the same
/// [`TermsF32`] arithmetic, [`F32_FILTER_EPS`], range checks, and only `w` in {0, 1} certified)
/// plus the two device guards [`GPU_F32_INPUT_MAX`] and [`GPU_F32_PERM_MIN`]. `Some(sign)` is
/// certified, `None` is uncertain.
///
/// Whenever it certifies, `orient_filter_f32` certifies the same sign (the guards only add
/// `None`s); a test checks this.
#[must_use]
pub fn filter_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Option<i8> {
    if a.iter()
        .chain(&b)
        .chain(&o)
        .chain(&l)
        .any(|x| x.abs() > GPU_F32_INPUT_MAX)
        || !filter::w_is_exact_f32(l[3])
    {
        return None;
    }
    let t = TermsF32::new(a, b, l, o);
    if !t.diffs_in_range(a, b, l, o) {
        return None;
    }
    let (det, perm) = t.det_perm();
    if perm != 0.0 && perm < GPU_F32_PERM_MIN {
        return None;
    }
    filter::certify_f32(det, perm, F32_FILTER_EPS)
}

/// Twin of WGSL `filter_f64` (shaders/exact_f64.wgsl): robust-math's [`filter::det_perm_f64`]
/// with the bound [`GPU_F64_FILTER_EPS`].
#[must_use]
pub fn filter_f64(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> Option<i8> {
    let (det, perm) = filter::det_perm_f64(a, b, l, o);
    filter::certify_f64(det, perm, GPU_F64_FILTER_EPS)
}

/// Twin of WGSL `exact_filter`: inputs with a subnormal component are never certified (a device
/// may flush them), otherwise the chosen filter decides.
#[must_use]
pub fn exact_filter(
    filter: ExactFilter,
    a: [f32; 3],
    b: [f32; 3],
    l: [f32; 4],
    o: [f32; 3],
) -> Option<i8> {
    if filter::any_subnormal(a, b, l, o) {
        return None;
    }
    match filter {
        ExactFilter::F32 => filter_f32(a, b, l, o),
        ExactFilter::F64 => filter_f64(a, b, l, o),
    }
}

/// Twin of WGSL `triangle_sign_traced`: the sign of the canonical triangle `(p0, p1, p2)` (ids
/// ascending) in `mode`, and whether exact mode needed the fallback (the filter could not
/// certify it). The sign is `None` when exact mode leaves it to the host (`device_exact`
/// false); with `device_exact`, [`orient_int`] decides it.
/// `original` evaluates the one order, as `ordered` does (the kernel's edge step does not use it
/// in that mode; the renderer's caps do).
#[must_use]
pub fn triangle_sign(
    mode: Accuracy,
    filter: ExactFilter,
    device_exact: bool,
    [p0, p1, p2]: [[f32; 3]; 3],
    l: [f32; 4],
) -> (Option<i8>, bool) {
    match mode {
        Accuracy::Exact => match exact_filter(filter, p0, p1, l, p2) {
            Some(s) => (Some(s), false),
            None if device_exact => (Some(orient_int(p0, p1, l, p2)), true),
            None => (None, true),
        },
        Accuracy::Robust => {
            let s0 = sign_f32(p0, p1, l, p2);
            let s1 = sign_f32(p1, p2, l, p0);
            let s2 = sign_f32(p2, p0, l, p1);
            (Some(if s0 == s1 && s1 == s2 { s0 } else { 0 }), false)
        }
        Accuracy::Ordered | Accuracy::Original => (Some(sign_f32(p0, p1, l, p2)), false),
    }
}

/// The inputs of one edge step: the scene's tables, the triangle step's signs
/// (`[light * tri_count + triangle]`) and the object-major lights.
#[derive(Debug, Clone, Copy)]
pub struct EdgeInputs<'a> {
    /// The flattened tables the kernels read.
    pub layout: &'a TableLayout,
    /// The triangle step's signs (unused by `original` unless `touch_signs`).
    pub signs: &'a [i32],
    /// `lights[object * light_count + light]`, object space.
    pub lights: &'a [[f32; 4]],
    /// Lights of the dispatch.
    pub light_count: usize,
    /// WGSL `TOUCH_SIGNS`: skip opposite vertices whose triangle's sign is
    /// [`TOUCH`].
    pub touch_signs: bool,
}

/// Twin of WGSL `edge_multiplicity`: `m` of global edge `e` for light `li`. `original` sums the
/// naive per-(edge, OV) signs; the other modes sum the parity times the signs of the OVs'
/// triangles (a reference's rank 1 is the odd permutation). [`TOUCH`] triangles contribute
/// nothing.
///
/// # Panics
/// Panics if `e`, `li` or the inputs are out of range.
#[must_use]
pub fn edge_multiplicity(x: &EdgeInputs<'_>, e: usize, li: usize, mode: Accuracy) -> i32 {
    let [ia, ib] = x.layout.edges[e];
    let object = x.layout.edge_object(e);
    let row = li * x.layout.tri_count();
    let triangle = |r: u32| row + (r >> 2) as usize;
    let mut m = 0i32;
    if mode == Accuracy::Original {
        let l = x.lights[object * x.light_count + li];
        let (a, b) = (x.layout.position(ia), x.layout.position(ib));
        for k in x.layout.ov_slots(e) {
            let r = x.layout.ov_refs[k];
            if x.touch_signs && x.signs[triangle(r)] == TOUCH {
                continue;
            }
            let o = x.layout.position(x.layout.ref_vertex(r));
            m += i32::from(sign_f32(a, b, l, o));
        }
    } else {
        for k in x.layout.ov_slots(e) {
            let r = x.layout.ov_refs[k];
            let s = x.signs[triangle(r)];
            if s != TOUCH {
                m += if r & 3 == 1 { -s } else { s };
            }
        }
    }
    m
}

// The integer exact sign: the twin of `shaders/exact_int.wgsl`.

/// Number of `u32` limbs of the fixed-point accumulator (1120 bits, least significant bit
/// `2^-596`); [`orient_int`] shows why the determinant always fits. WGSL `XI_LIMBS`.
pub const LIMBS: usize = 35;

/// Index of the pseudo-input "exact 1" (mantissa 1, exponent field 150) in the decoded inputs,
/// the fourth factor of a three-factor monomial. WGSL `XI_ONE`.
pub const ONE: u32 = 13;

/// The 24 monomials of `det4(A, B, L, O)` (WGSL `XI_TERMS`), cofactor expansion along the light's
/// row: `det4 = l0 C0 - l1 C1 + l2 C2 - l3 det3(A, B, O)`, `C_k` the minors of `|A 1; B 1; O 1|`
/// without column `k`.
///
/// Bits 0-3, 4-7, 8-11 and 12-15 are the four factors, as indices of the inputs `a0 a1 a2 = 0 1 2`,
/// `b = 3 4 5`, `o = 6 7 8`, `l = 9 10 11 12` and [`ONE`]; bit 16 set means the monomial is
/// subtracted.
pub const TERMS: [u32; 24] = [
    0x0d519, // + l0 a1 b2
    0x1d429, // - l0 a2 b1
    0x1d819, // - l0 a1 o2
    0x0d729, // + l0 a2 o1
    0x0d849, // + l0 b1 o2
    0x1d759, // - l0 b2 o1
    0x1d50a, // - l1 a0 b2
    0x0d32a, // + l1 a2 b0
    0x0d80a, // + l1 a0 o2
    0x1d62a, // - l1 a2 o0
    0x1d83a, // - l1 b0 o2
    0x0d65a, // + l1 b2 o0
    0x0d40b, // + l2 a0 b1
    0x1d31b, // - l2 a1 b0
    0x1d70b, // - l2 a0 o1
    0x0d61b, // + l2 a1 o0
    0x0d73b, // + l2 b0 o1
    0x1d64b, // - l2 b1 o0
    0x1840c, // - l3 a0 b1 o2
    0x0750c, // + l3 a0 b2 o1
    0x0831c, // + l3 a1 b0 o2
    0x1651c, // - l3 a1 b2 o0
    0x1732c, // - l3 a2 b0 o1
    0x0642c, // + l3 a2 b1 o0
];

/// WGSL `select(0u, 1u, c)`.
#[inline]
fn bit(c: bool) -> u32 {
    u32::from(c)
}

/// Twin of WGSL `xi_mul32`: the exact 64-bit product `a · b` as `[low, high]`, from 16-bit halves
/// (Hacker's Delight `mulhu`), so that it needs no 64-bit type; no partial sum exceeds `2^32 - 1`.
///
/// ```
/// use shadowvol_gpu::twin::mul32;
/// let [lo, hi] = mul32(u32::MAX, u32::MAX);
/// assert_eq!(u64::from(lo) | (u64::from(hi) << 32), u64::from(u32::MAX) * u64::from(u32::MAX));
/// ```
#[must_use]
#[inline]
pub fn mul32(a: u32, b: u32) -> [u32; 2] {
    let a0 = a & 0xffff;
    let a1 = a >> 16;
    let b0 = b & 0xffff;
    let b1 = b >> 16;
    let p00 = a0.wrapping_mul(b0);
    let t = a1.wrapping_mul(b0).wrapping_add(p00 >> 16);
    let w = (t & 0xffff).wrapping_add(a0.wrapping_mul(b1));
    let hi = a1
        .wrapping_mul(b1)
        .wrapping_add(t >> 16)
        .wrapping_add(w >> 16);
    let lo = (w << 16) | (p00 & 0xffff);
    [lo, hi]
}

/// Twin of WGSL `xi_mul96`: the exact product `p · m` for `p < 2^72` (three limbs, least
/// significant first) and `m < 2^24`. The result is below `2^96`, so its top limb cannot wrap.
#[must_use]
#[inline]
fn mul96(p: [u32; 3], m: u32) -> [u32; 3] {
    let x = mul32(p[0], m);
    let y = mul32(p[1], m);
    let r1 = x[1].wrapping_add(y[0]);
    let c = bit(r1 < y[0]);
    [
        x[0],
        r1,
        y[1].wrapping_add(p[2].wrapping_mul(m)).wrapping_add(c),
    ]
}

/// Twin of WGSL `orient_int` (`shaders/exact_int.wgsl`): the exact sign of
/// `det4(A, B, L, O) = |A 1; B 1; L; O 1|`, with `u32` arithmetic only: `-1`, `0` or `+1`.
///
/// It returns the same value as robust-math's
/// [`orient_exact`](shadowvol_robust_math::orient_exact) for every finite `f32` input, without a
/// single floating-point operation: WGSL compilers may contract (FMA) and reassociate float math,
/// so only integer arithmetic on the bit patterns can be trusted to be exact on every device.
/// The WGSL function is this one statement for statement (Rust's `wrapping_*` operations are
/// WGSL's `u32` operations, `if c { x } else { y }` is `select(y, x, c)`); the tests run both on
/// the same inputs.
///
/// # Method
/// * Every finite `f32` is `(-1)^s · m · 2^(e - 150)` with an integer `m < 2^24`: a normal number
///   has the hidden bit added, a subnormal (exponent field 0) is decoded with `e = 1` and no
///   hidden bit; zeros have `m = 0`.
/// * `det4 |A 1; B 1; L; O 1|`, expanded along the light's row, is the signed sum of 24 monomials
///   ([`TERMS`]): 18 products of three inputs (`l0`, `l1`, `l2` times two coordinates) and 6 of
///   four (`l3` times three coordinates). The matrix's 1s are exact; a three-factor monomial gets
///   the exact factor `1 = 1 · 2^(150 - 150)` as its fourth, so every monomial is
///   `±(m0 m1 m2 m3) · 2^(e0 + e1 + e2 + e3 - 600)`.
/// * The mantissa product is an integer below `2^96` (three `u32` limbs), computed with
///   32 × 32 → 64-bit products from 16-bit halves ([`mul32`]; WGSL has no `u64`).
/// * It is shifted into place and added to (or subtracted from) a two's complement fixed-point
///   accumulator of [`LIMBS`] `u32` limbs whose least significant bit is worth `2^-596`; the
///   carry (borrow) loop stops as soon as the carry does.
/// * The sign of the determinant is the sign of the accumulator: its top bit, or the all-zero test.
///
/// # Why 35 limbs suffice
/// The smallest exponent of a product of four `f32`s is `4 · (1 - 150) = -596`, of three
/// `-447`, so every monomial is an integer multiple of `2^-596`: the accumulator position of a
/// monomial is `e0 + e1 + e2 + e3 - 4 >= 0`. Every finite `f32` is below `2^128`, so a
/// four-factor monomial is below `2^512` and a three-factor one below `2^384`; the 24 of them sum
/// to less than `6 · 2^512 + 18 · 2^384 < 2^515`. Scaled by `2^596` that is below `2^1111`, so
/// 1112 bits hold every partial sum in two's complement, and 35 limbs (1120 bits) do. A shifted
/// product starts at limb `pos / 32 <= 31` and spans four limbs, so it ends in limb 34 at most
/// (also for non-finite inputs, whose result is unspecified but which never index out of bounds).
/// The arithmetic is modulo `2^1120`; since the true sum fits, it is exact.
///
/// # Cost
/// Per non-zero monomial: at most five 32 × 32 multiplies ([`mul32`]: four `u32` multiplies and
/// about 11 other operations each) and two plain multiplies, the decode of its term code, the
/// shift into four limbs, four add-with-carry steps and a carry loop that usually stops after a
/// step or two: about 160 `u32` operations for a four-factor monomial, 120 for a three-factor one.
/// With the decode of the 13 inputs and the final scan of the 35 limbs that is about 3,300
/// operations in the worst case (no zero input; every zero input skips the monomials it is in),
/// no memory traffic beyond about 120 words of private arrays, and no floating point. It is meant for
/// the rare inputs a certified filter cannot decide.
///
/// ```
/// use shadowvol_gpu::twin::orient_int;
/// use shadowvol_robust_math::orient_exact;
///
/// let (a, b, o) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
/// let above = [0.3, 0.3, 2.0, 1.0];
/// assert_eq!(orient_int(a, b, above, o), 1);
/// assert_eq!(orient_int(a, b, above, o), orient_exact(a, b, above, o));
/// // The light in the triangle's plane: exactly zero.
/// assert_eq!(orient_int(a, b, [0.3, 0.3, 0.0, 1.0], o), 0);
/// // Subnormal coordinates are decided exactly too.
/// let t = f32::from_bits(1); // 2^-149
/// assert_eq!(orient_int([0.0; 3], [t, 0.0, 0.0], [0.0, 0.0, t, 1.0], [0.0, t, 0.0]), 1);
/// ```
///
/// # Convention
/// robust-math's: the sign of `((A - B) × V) · (O - A)` with `V = L.xyz - L.w · A`, the same
/// value as [`orient_exact`](shadowvol_robust_math::orient_exact) (`l = [x, y, z, w]`; `w = 1`
/// a point light, `w = 0` a directional one, any other `w` homogeneous).
///
/// # Why it is exact
/// Each input is decoded from its bits into an integer mantissa and exponent; the 24 monomials of
/// the determinant are exact integer products placed into a 1120-bit two's complement
/// fixed-point accumulator that holds every partial sum (see "Why 35 limbs suffice"). No
/// floating-point operation is performed, so the result is the same on every device that runs the
/// WGSL twin, for every finite input: zeros of both signs, subnormals, `f32::MAX`, any `w`.
///
/// For NaN or infinite inputs the result is unspecified (they are decoded as if finite); it
/// never panics.
#[must_use]
pub fn orient_int(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i8 {
    let bits: [u32; 13] = [
        a[0].to_bits(),
        a[1].to_bits(),
        a[2].to_bits(),
        b[0].to_bits(),
        b[1].to_bits(),
        b[2].to_bits(),
        o[0].to_bits(),
        o[1].to_bits(),
        o[2].to_bits(),
        l[0].to_bits(),
        l[1].to_bits(),
        l[2].to_bits(),
        l[3].to_bits(),
    ];
    // Decode: value = (-1)^sg · man · 2^(ex - 150); subnormals (field 0) use ex = 1, no hidden bit.
    let mut man = [0u32; 14];
    let mut ex = [0u32; 14];
    let mut sg = [0u32; 14];
    for i in 0..13 {
        let u = bits[i];
        let field = (u >> 23) & 0xff;
        man[i] = (u & 0x7f_ffff) | if field != 0 { 0x80_0000 } else { 0 };
        ex[i] = field.max(1);
        sg[i] = u >> 31;
    }
    man[ONE as usize] = 1;
    ex[ONE as usize] = 150;
    sg[ONE as usize] = 0;

    let terms = TERMS;
    // Two's complement accumulator, little-endian limbs; bit 0 is worth 2^-596.
    let mut acc = [0u32; LIMBS];
    for &code in &terms {
        let i0 = (code & 15) as usize;
        let i1 = ((code >> 4) & 15) as usize;
        let i2 = ((code >> 8) & 15) as usize;
        let i3 = ((code >> 12) & 15) as usize;
        if man[i0] == 0 || man[i1] == 0 || man[i2] == 0 || man[i3] == 0 {
            continue;
        }
        // The mantissa product, < 2^96.
        let [lo, hi] = mul32(man[i0], man[i1]);
        let mut p = mul96([lo, hi, 0], man[i2]);
        if i3 != ONE as usize {
            p = mul96(p, man[i3]);
        }
        // Its place in the accumulator: 2^(sum ex - 600) = 2^-596 · 2^pos.
        let pos = ex[i0]
            .wrapping_add(ex[i1])
            .wrapping_add(ex[i2])
            .wrapping_add(ex[i3])
            .wrapping_sub(4);
        let k = (pos >> 5) as usize;
        let sh = pos & 31;
        let r = 31 - sh; // (x >> 1) >> r is x >> (32 - sh), also for sh = 0
        let s: [u32; 4] = [
            p[0] << sh,
            (p[1] << sh) | ((p[0] >> 1) >> r),
            (p[2] << sh) | ((p[1] >> 1) >> r),
            (p[2] >> 1) >> r,
        ];
        let neg = ((code >> 16) ^ sg[i0] ^ sg[i1] ^ sg[i2] ^ sg[i3]) != 0;
        let mut c = 0u32;
        for j in 0..4 {
            let x = acc[k + j];
            let q = s[j];
            if neg {
                let d = x.wrapping_sub(q);
                acc[k + j] = d.wrapping_sub(c);
                c = bit(x < q || d < c);
            } else {
                let d = x.wrapping_add(q);
                let e = d.wrapping_add(c);
                acc[k + j] = e;
                c = bit(d < q || e < c);
            }
        }
        // The carry (borrow) runs only as far as it propagates.
        let mut i = k + 4;
        while c != 0 && i < LIMBS {
            let x = acc[i];
            if neg {
                acc[i] = x.wrapping_sub(1);
                c = bit(x == 0);
            } else {
                acc[i] = x.wrapping_add(1);
                c = bit(x == 0xffff_ffff);
            }
            i += 1;
        }
    }

    if (acc[LIMBS - 1] >> 31) != 0 {
        return -1;
    }
    let mut nz = 0u32;
    for x in acc {
        nz |= x;
    }
    if nz != 0 {
        1
    } else {
        0
    }
}
