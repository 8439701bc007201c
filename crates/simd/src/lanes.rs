//! Lane types the kernels are generic over.
//!
//! Two instruction-set levels implement the same small vocabulary:
//!
//! * [`Wide`]: the `wide` crate's `f32x8` / `f64x4`. `wide` chooses its instructions at compile
//!   time from the enabled target features; in a default x86-64 build that is SSE2 (each 8-lane
//!   vector is two 128-bit halves).
//! * [`Avx2`] (x86-64 only): 256-bit `std::arch` intrinsics. Its methods are
//!   `#[inline(always)]` and are only ever executed inside functions compiled with
//!   `#[target_feature(enable = "avx2")]`, entered after `is_x86_feature_detected!("avx2")`.
//!
//! Every operation is a single IEEE-754 operation in the lane type (no fused multiply-add, no
//! reassociation), so both levels produce bit-identical values, equal to the scalar code of
//! `shadowvol_robust_math`.

use std::ops::{Add, Mul, Sub};

/// Ors light `k`'s sign bits into the several-light sign bytes `acc[i]`: bit `k` for the lanes
/// set in `pos`, bit `4 + k` for those set in `neg` (disjoint masks, lane `i` = bit `i`).
#[inline(always)]
pub(crate) fn or_sign_mask_bits(acc: &mut [u32; 8], pos: u32, neg: u32, k: u32) {
    for (i, r) in acc.iter_mut().enumerate() {
        *r |= (pos >> i & 1) << k | (neg >> i & 1) << (4 + k);
    }
}

/// What the `f32` and the `f64` lanes share: IEEE-754 arithmetic and comparisons to bits.
pub(crate) trait Arith:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self>
{
    /// Lane-wise absolute value (clears the sign bit; exact).
    fn abs(self) -> Self;
    /// Bit `i` set when `self[i] > other[i]` (false for NaN lanes).
    fn gt_bits(self, other: Self) -> u32;
    /// Bit `i` set when lane `i` equals `0.0` (either sign).
    fn zero_bits(self) -> u32;
}

/// Eight `f32` lanes.
pub(crate) trait F32V: Arith {
    /// All lanes `x`.
    fn splat(x: f32) -> Self;
    /// Lane `i` = `base[idx[i]]`.
    ///
    /// # Safety
    /// `idx` has at least 8 entries, each `< base.len()`, and `base.len() <= i32::MAX`.
    #[cfg(test)]
    unsafe fn gather(base: &[f32], idx: &[u32]) -> Self;
    /// `(positive, negative)`: bit `i` set when lane `i` is `> 0` / `< 0`.
    fn sign_bits(self) -> (u32, u32);
    /// Per lane `+1.0`, `-1.0` or `0.0` for positive, negative and zero (or NaN) lanes.
    fn signum0(self) -> Self;
    /// Truncates to integers (the lanes are small exact integers here).
    fn to_i32(self) -> [i32; 8];
    /// Ors lane `i`'s sign into the several-light sign byte `acc[i]` of light `k` (0 to 3):
    /// bit `k` for `+1`, bit `4 + k` for `-1`, nothing for zero or NaN. Those bits of `acc[i]`
    /// must be 0.
    fn or_sign_bits(self, acc: &mut [u32; 8], k: u32) {
        let (pos, neg) = self.sign_bits();
        or_sign_mask_bits(acc, pos, neg, k);
    }
    /// [`F32V::or_sign_bits`] for the agreement of three lanes: `+1` where `self`, `b` and `c`
    /// are all positive, `-1` where all three are negative, nothing otherwise (any zero or NaN,
    /// or a disagreement): `robust` mode's sign of a triangle from its three plane tests.
    fn or_sign_bits3(self, b: Self, c: Self, acc: &mut [u32; 8], k: u32) {
        let (pa, na) = self.sign_bits();
        let (pb, nb) = b.sign_bits();
        let (pc, nc) = c.sign_bits();
        let (pos, neg) = (pa & pb & pc, na & nb & nc);
        or_sign_mask_bits(acc, pos, neg, k);
    }
    /// Bit `i` set unless lane `i` is zero or its magnitude lies in `[min, max]` (NaN lanes
    /// are set): the range check of `orient_filter_f32` on one difference.
    fn out_of_range_bits(self, min: f32, max: f32) -> u32;
    /// Truncates to integers, writes them to `dst[..8]` (a streaming store that bypasses the
    /// caches where the level has one and `dst` is suitably aligned: results are written once
    /// and not read back by the kernel) and returns the bits of the non-zero lanes.
    ///
    /// # Panics
    /// If `dst.len() < 8`.
    fn store_i32(self, dst: &mut [i32]) -> u32 {
        // No streaming store at this level: the ordinary store.
        self.store_i32_cached(dst)
    }
    /// [`F32V::store_i32`] with an ordinary (cached) store: for several output rows written
    /// in turn, where streaming stores thrash the write-combining buffers.
    ///
    /// # Panics
    /// If `dst.len() < 8`.
    fn store_i32_cached(self, dst: &mut [i32]) -> u32 {
        let m = self.to_i32();
        dst[..8].copy_from_slice(&m);
        m.iter()
            .enumerate()
            .fold(0, |bits, (i, &x)| bits | u32::from(x != 0) << i)
    }
}

/// Four `f64` lanes.
pub(crate) trait F64V: Arith {
    /// All lanes `x`.
    fn splat(x: f64) -> Self;
    /// Four `f32` values widened exactly to `f64`.
    fn from_f32(a: [f32; 4]) -> Self;
}

/// An instruction-set level: a pair of lane types.
pub(crate) trait Level {
    /// Eight `f32` lanes.
    type F: F32V;
    /// Four `f64` lanes.
    type D: F64V;
    /// Lanes 0..4 and 4..8 of `f`, widened exactly to `f64`.
    fn widen(f: Self::F) -> (Self::D, Self::D);
    /// `(x, y, z)` lanes of the points `pos[idx[i]]` (12-byte records).
    ///
    /// # Safety
    /// `idx` has at least 8 entries, each `< pos.len()`, and `pos.len() >= 2`.
    unsafe fn gather_vec3(pos: &[glam::Vec3], idx: &[u32]) -> [Self::F; 3];
    /// `(x, y, z)` lanes of the points `pos[idx[i]]` (`[x, y, z, pad]` records).
    ///
    /// # Safety
    /// `idx` has at least 8 entries, each `< pos.len()`.
    unsafe fn gather_records(pos: &[[f32; 4]], idx: &[u32]) -> [Self::F; 3];
    /// Orders this thread's earlier streaming stores ([`F32V::store_i32`]) before its later
    /// stores, as `_mm_sfence` does; a no-op where the level has no streaming stores.
    fn store_fence() {}
    /// The 8 triangles `tris` (vertex ids in winding order) in canonical order: column `k`,
    /// lane `i` is the `k`-th smallest id of triangle `i`.
    #[inline(always)]
    fn canon8(tris: &[[u32; 3]; 8]) -> [[u32; 8]; 3] {
        canon8_scalar(tris)
    }
}

/// [`Level::canon8`], one triangle at a time.
#[inline(always)]
pub(crate) fn canon8_scalar(tris: &[[u32; 3]]) -> [[u32; 8]; 3] {
    let mut c = [[0u32; 8]; 3];
    for (i, &[a, b, d]) in tris.iter().take(8).enumerate() {
        let (lo, hi) = (a.min(b), a.max(b));
        let (mid, top) = (hi.min(d), hi.max(d));
        let (bot, mid) = (lo.min(mid), lo.max(mid));
        (c[0][i], c[1][i], c[2][i]) = (bot, mid, top);
    }
    c
}

/// The `wide` crate at the compile-time target level.
pub(crate) struct Wide;

impl Level for Wide {
    type F = wide::f32x8;
    type D = wide::f64x4;
    #[inline(always)]
    fn widen(f: wide::f32x8) -> (wide::f64x4, wide::f64x4) {
        let a = f.to_array();
        (
            F64V::from_f32([a[0], a[1], a[2], a[3]]),
            F64V::from_f32([a[4], a[5], a[6], a[7]]),
        )
    }
    #[inline(always)]
    unsafe fn gather_records(pos: &[[f32; 4]], idx: &[u32]) -> [wide::f32x8; 3] {
        debug_assert!(idx.len() >= 8 && idx[..8].iter().all(|&i| (i as usize) < pos.len()));
        // SAFETY: the caller guarantees 8 indices, all in range.
        let p: [[f32; 4]; 8] =
            std::array::from_fn(|i| unsafe { *pos.get_unchecked(*idx.get_unchecked(i) as usize) });
        [0, 1, 2].map(|c| wide::f32x8::new(std::array::from_fn(|i| p[i][c])))
    }
    #[inline(always)]
    unsafe fn gather_vec3(pos: &[glam::Vec3], idx: &[u32]) -> [wide::f32x8; 3] {
        debug_assert!(idx.len() >= 8 && idx[..8].iter().all(|&i| (i as usize) < pos.len()));
        // SAFETY: the caller guarantees 8 indices, all in range.
        let p: [[f32; 3]; 8] = std::array::from_fn(|i| unsafe {
            pos.get_unchecked(*idx.get_unchecked(i) as usize).to_array()
        });
        [0, 1, 2].map(|c| wide::f32x8::new(std::array::from_fn(|i| p[i][c])))
    }
}

impl F32V for wide::f32x8 {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        wide::f32x8::splat(x)
    }
    #[cfg(test)]
    #[inline(always)]
    unsafe fn gather(base: &[f32], idx: &[u32]) -> Self {
        debug_assert!(idx.len() >= 8 && idx[..8].iter().all(|&i| (i as usize) < base.len()));
        // SAFETY: the caller guarantees 8 indices, all in range.
        wide::f32x8::new(std::array::from_fn(|i| unsafe {
            *base.get_unchecked(*idx.get_unchecked(i) as usize)
        }))
    }
    #[inline(always)]
    fn sign_bits(self) -> (u32, u32) {
        let z = wide::f32x8::ZERO;
        (self.simd_gt(z).to_bitmask(), self.simd_lt(z).to_bitmask())
    }
    #[inline(always)]
    fn signum0(self) -> Self {
        let z = wide::f32x8::ZERO;
        let one = wide::f32x8::ONE;
        (self.simd_gt(z) & one) - (self.simd_lt(z) & one)
    }
    #[inline(always)]
    fn to_i32(self) -> [i32; 8] {
        self.trunc_int().to_array()
    }
    #[inline(always)]
    fn out_of_range_bits(self, min: f32, max: f32) -> u32 {
        let m = wide::f32x8::abs(self);
        let ok = m.simd_eq(wide::f32x8::ZERO)
            | (m.simd_ge(wide::f32x8::splat(min)) & m.simd_le(wide::f32x8::splat(max)));
        !ok.to_bitmask() & 0xFF
    }
}

impl F64V for wide::f64x4 {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        wide::f64x4::splat(x)
    }
    #[inline(always)]
    fn from_f32(a: [f32; 4]) -> Self {
        wide::f64x4::new([
            f64::from(a[0]),
            f64::from(a[1]),
            f64::from(a[2]),
            f64::from(a[3]),
        ])
    }
}

/// [`Arith`] for a `wide` vector type.
macro_rules! wide_arith {
    ($t:ty) => {
        impl Arith for $t {
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn gt_bits(self, other: Self) -> u32 {
                self.simd_gt(other).to_bitmask()
            }
            #[inline(always)]
            fn zero_bits(self) -> u32 {
                self.simd_eq(<$t>::ZERO).to_bitmask()
            }
        }
    };
}
wide_arith!(wide::f32x8);
wide_arith!(wide::f64x4);

#[cfg(target_arch = "x86_64")]
pub(crate) use avx2::{stream_i32x8, Avx2};

#[cfg(target_arch = "x86_64")]
mod avx2 {
    //! 256-bit lanes with `std::arch` intrinsics.
    //!
    //! # Safety
    //! The intrinsics require AVX (and AVX2 for the integer conversion path's callers). Values of
    //! these types are only created inside `#[target_feature(enable = "avx2")]` functions that
    //! the backend enters after `is_x86_feature_detected!("avx2")` returned true, so every
    //! intrinsic here runs on a CPU that has it.
    use super::{Arith, Level, F32V, F64V};
    use std::arch::x86_64::*;
    use std::ops::{Add, Mul, Sub};

    /// AVX2 level (256-bit `f32` and `f64` lanes).
    pub(crate) struct Avx2;

    /// Stores 8 `i32` at `p` with a streaming (non-temporal) store where `p` is 32- or 16-byte
    /// aligned (large allocations are often only 16-byte aligned: then two 16-byte halves),
    /// otherwise with an ordinary unaligned store. The caller orders streaming stores with
    /// `_mm_sfence` before the data is read by another thread.
    ///
    /// # Safety
    /// `p` points to 32 writable bytes; AVX2 present (module docs).
    #[inline(always)]
    pub(crate) unsafe fn stream_i32x8(p: *mut __m256i, m: __m256i) {
        // SAFETY: forwarded from the caller; each streaming store only on an address aligned
        // as it requires.
        unsafe {
            if p.align_offset(32) == 0 {
                _mm256_stream_si256(p, m);
            } else if p.align_offset(16) == 0 {
                let q = p.cast::<__m128i>();
                _mm_stream_si128(q, _mm256_castsi256_si128(m));
                _mm_stream_si128(q.add(1), _mm256_extracti128_si256::<1>(m));
            } else {
                _mm256_storeu_si256(p, m);
            }
        }
    }

    /// `acc[i] |= bit k` where lane `i` of `pos` is all ones and `bit 4 + k` where lane `i` of
    /// `neg` is (the several-light sign byte of light `k`).
    ///
    /// # Safety
    /// AVX2 present (module docs).
    #[inline(always)]
    unsafe fn or_bits(acc: &mut [u32; 8], pos: __m256i, neg: __m256i, k: u32) {
        // SAFETY: `acc` is 32 readable and writable bytes; unaligned load and store.
        unsafe {
            let bits = _mm256_or_si256(
                _mm256_and_si256(pos, _mm256_set1_epi32(1 << k)),
                _mm256_and_si256(neg, _mm256_set1_epi32(16 << k)),
            );
            let p = acc.as_mut_ptr().cast::<__m256i>();
            _mm256_storeu_si256(p, _mm256_or_si256(_mm256_loadu_si256(p), bits));
        }
    }

    impl Level for Avx2 {
        type F = F8;
        type D = D4;
        #[inline(always)]
        fn canon8(tris: &[[u32; 3]; 8]) -> [[u32; 8]; 3] {
            // SAFETY: `tris` is 96 readable bytes (three unaligned 32-byte loads); `out` 96
            // writable ones; AVX2 present (module docs).
            unsafe {
                let p = tris.as_ptr().cast::<u32>();
                let a = _mm256_loadu_si256(p.cast());
                let b = _mm256_loadu_si256(p.add(8).cast());
                let c = _mm256_loadu_si256(p.add(16).cast());
                // Id `k` of triangle `i` is element `3 i + k` of a|b|c. Each column's eight
                // elements sit at distinct lanes of a, b and c: blend them into one vector,
                // then permute them into triangle order.
                let col = |m: __m256i, order: [i32; 8]| {
                    let idx = _mm256_loadu_si256(order.as_ptr().cast());
                    _mm256_permutevar8x32_epi32(m, idx)
                };
                let x =
                    _mm256_blend_epi32::<0b0010_0100>(_mm256_blend_epi32::<0b1001_0010>(a, b), c);
                let y =
                    _mm256_blend_epi32::<0b0100_1001>(_mm256_blend_epi32::<0b0010_0100>(a, b), c);
                let z =
                    _mm256_blend_epi32::<0b1001_0010>(_mm256_blend_epi32::<0b0100_1001>(a, b), c);
                let x = col(x, [0, 3, 6, 1, 4, 7, 2, 5]);
                let y = col(y, [1, 4, 7, 2, 5, 0, 3, 6]);
                let z = col(z, [2, 5, 0, 3, 6, 1, 4, 7]);
                // A three-element sorting network, per lane (unsigned).
                let (lo, hi) = (_mm256_min_epu32(x, y), _mm256_max_epu32(x, y));
                let (mid, top) = (_mm256_min_epu32(hi, z), _mm256_max_epu32(hi, z));
                let (bot, mid) = (_mm256_min_epu32(lo, mid), _mm256_max_epu32(lo, mid));
                let mut out = [[0u32; 8]; 3];
                for (o, v) in out.iter_mut().zip([bot, mid, top]) {
                    _mm256_storeu_si256(o.as_mut_ptr().cast(), v);
                }
                out
            }
        }
        #[inline(always)]
        fn store_fence() {
            // SAFETY: SSE is part of x86-64.
            unsafe { _mm_sfence() }
        }
        #[inline(always)]
        fn widen(f: F8) -> (D4, D4) {
            // SAFETY: see the module documentation. f32 -> f64 is exact.
            unsafe {
                (
                    D4(_mm256_cvtps_pd(_mm256_castps256_ps128(f.0))),
                    D4(_mm256_cvtps_pd(_mm256_extractf128_ps::<1>(f.0))),
                )
            }
        }
        #[inline(always)]
        unsafe fn gather_vec3(pos: &[glam::Vec3], idx: &[u32]) -> [F8; 3] {
            debug_assert!(idx.len() >= 8 && idx[..8].iter().all(|&i| (i as usize) < pos.len()));
            // SAFETY: 8 readable indices, each in range of `pos` (caller). Records are 12 bytes
            // (`Vec3` is `repr(C)` `[f32; 3]`): a 16-byte load at a record reads the next
            // record's x too, which exists for every record but the last; the last is loaded
            // from 4 bytes earlier (the previous record's z: `pos.len() >= 2`) and rotated.
            // AVX2 present (module docs).
            unsafe {
                let base = pos.as_ptr().cast::<f32>();
                let last = pos.len() - 1;
                transpose8(|i: usize| {
                    let v = *idx.get_unchecked(i) as usize;
                    if v < last {
                        _mm_loadu_ps(base.add(3 * v))
                    } else {
                        // [z', x, y, z] to [x, y, z, z'].
                        _mm_permute_ps::<0b00_11_10_01>(_mm_loadu_ps(base.add(3 * v - 1)))
                    }
                })
            }
        }
        #[inline(always)]
        unsafe fn gather_records(pos: &[[f32; 4]], idx: &[u32]) -> [F8; 3] {
            debug_assert!(idx.len() >= 8 && idx[..8].iter().all(|&i| (i as usize) < pos.len()));
            // SAFETY: 8 readable indices, each in range of `pos` (caller); each record is 16
            // readable bytes; AVX2 present (module docs).
            unsafe {
                transpose8(|i: usize| {
                    _mm_loadu_ps(
                        pos.as_ptr()
                            .add(*idx.get_unchecked(i) as usize)
                            .cast::<f32>(),
                    )
                })
            }
        }
    }

    /// The x, y and z lanes of the 8 points whose `[x, y, z, _]` rows `row(i)` loads.
    ///
    /// # Safety
    /// AVX2 present (module docs); `row` is safe to call for `0..8`.
    #[inline(always)]
    unsafe fn transpose8(row: impl Fn(usize) -> __m128) -> [F8; 3] {
        // SAFETY: AVX2 present (the caller's contract).
        unsafe {
            let pair =
                |i: usize| _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(row(i)), row(i + 4));
            // Rows [x y z w] of points i and i+4 in the two 128-bit halves; 4x4 transpose.
            let (r0, r1, r2, r3) = (pair(0), pair(1), pair(2), pair(3));
            let t0 = _mm256_unpacklo_ps(r0, r1); // x0 x1 y0 y1
            let t1 = _mm256_unpacklo_ps(r2, r3); // x2 x3 y2 y3
            let t2 = _mm256_unpackhi_ps(r0, r1); // z0 z1 w0 w1
            let t3 = _mm256_unpackhi_ps(r2, r3); // z2 z3 w2 w3
            [
                F8(_mm256_shuffle_ps::<0x44>(t0, t1)),
                F8(_mm256_shuffle_ps::<0xEE>(t0, t1)),
                F8(_mm256_shuffle_ps::<0x44>(t2, t3)),
            ]
        }
    }

    #[derive(Clone, Copy)]
    pub(crate) struct F8(__m256);

    #[derive(Clone, Copy)]
    pub(crate) struct D4(__m256d);

    macro_rules! binop {
        ($t:ident, $tr:ident, $m:ident, $intr:ident) => {
            impl $tr for $t {
                type Output = $t;
                #[inline(always)]
                fn $m(self, rhs: $t) -> $t {
                    // SAFETY: see the module documentation (only reached on AVX2 CPUs).
                    $t(unsafe { $intr(self.0, rhs.0) })
                }
            }
        };
    }
    binop!(F8, Add, add, _mm256_add_ps);
    binop!(F8, Sub, sub, _mm256_sub_ps);
    binop!(F8, Mul, mul, _mm256_mul_ps);
    binop!(D4, Add, add, _mm256_add_pd);
    binop!(D4, Sub, sub, _mm256_sub_pd);
    binop!(D4, Mul, mul, _mm256_mul_pd);

    impl F32V for F8 {
        #[inline(always)]
        fn splat(x: f32) -> Self {
            // SAFETY: see the module documentation.
            F8(unsafe { _mm256_set1_ps(x) })
        }
        #[cfg(test)]
        #[inline(always)]
        unsafe fn gather(base: &[f32], idx: &[u32]) -> Self {
            debug_assert!(idx.len() >= 8 && idx[..8].iter().all(|&i| (i as usize) < base.len()));
            // SAFETY: 8 readable indices, each in range of `base` and below 2^31 (caller);
            // AVX2 present (module docs).
            unsafe {
                let vi = _mm256_loadu_si256(idx.as_ptr().cast::<__m256i>());
                F8(_mm256_i32gather_ps::<4>(base.as_ptr(), vi))
            }
        }
        #[inline(always)]
        fn sign_bits(self) -> (u32, u32) {
            // SAFETY: see the module documentation.
            unsafe {
                let z = _mm256_setzero_ps();
                let gt = _mm256_cmp_ps::<_CMP_GT_OQ>(self.0, z);
                let lt = _mm256_cmp_ps::<_CMP_LT_OQ>(self.0, z);
                (_mm256_movemask_ps(gt) as u32, _mm256_movemask_ps(lt) as u32)
            }
        }
        #[inline(always)]
        fn signum0(self) -> Self {
            // SAFETY: see the module documentation.
            unsafe {
                let z = _mm256_setzero_ps();
                let one = _mm256_set1_ps(1.0);
                let gt = _mm256_and_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(self.0, z), one);
                let lt = _mm256_and_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(self.0, z), one);
                F8(_mm256_sub_ps(gt, lt))
            }
        }
        #[inline(always)]
        fn store_i32(self, dst: &mut [i32]) -> u32 {
            let dst = &mut dst[..8];
            // SAFETY: `dst` holds 8 i32 (checked above); streaming stores are used only on
            // addresses aligned as they require (32 or 16 bytes); AVX2 present (module docs).
            unsafe {
                let m = _mm256_cvttps_epi32(self.0);
                let p = dst.as_mut_ptr().cast::<__m256i>();
                stream_i32x8(p, m);
                let zero = _mm256_cmpeq_epi32(m, _mm256_setzero_si256());
                !(_mm256_movemask_ps(_mm256_castsi256_ps(zero)) as u32) & 0xFF
            }
        }
        #[inline(always)]
        fn or_sign_bits(self, acc: &mut [u32; 8], k: u32) {
            // SAFETY: `acc` is 32 readable and writable bytes; unaligned load and store; AVX2
            // present (module docs).
            unsafe {
                let z = _mm256_setzero_ps();
                let gt = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GT_OQ>(self.0, z));
                let lt = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(self.0, z));
                or_bits(acc, gt, lt, k);
            }
        }
        #[inline(always)]
        fn or_sign_bits3(self, b: Self, c: Self, acc: &mut [u32; 8], k: u32) {
            // SAFETY: as in `or_sign_bits`.
            unsafe {
                let z = _mm256_setzero_ps();
                let gt = |x: __m256| _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GT_OQ>(x, z));
                let lt = |x: __m256| _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(x, z));
                let all_gt = _mm256_and_si256(_mm256_and_si256(gt(self.0), gt(b.0)), gt(c.0));
                let all_lt = _mm256_and_si256(_mm256_and_si256(lt(self.0), lt(b.0)), lt(c.0));
                or_bits(acc, all_gt, all_lt, k);
            }
        }
        #[inline(always)]
        fn store_i32_cached(self, dst: &mut [i32]) -> u32 {
            let dst = &mut dst[..8];
            // SAFETY: `dst` holds 8 i32 (checked above); unaligned store; AVX2 present
            // (module docs).
            unsafe {
                let m = _mm256_cvttps_epi32(self.0);
                _mm256_storeu_si256(dst.as_mut_ptr().cast::<__m256i>(), m);
                let zero = _mm256_cmpeq_epi32(m, _mm256_setzero_si256());
                !(_mm256_movemask_ps(_mm256_castsi256_ps(zero)) as u32) & 0xFF
            }
        }
        #[inline(always)]
        fn to_i32(self) -> [i32; 8] {
            let mut out = [0i32; 8];
            // SAFETY: `out` has room for 8 i32; unaligned store; AVX present (module docs).
            unsafe {
                _mm256_storeu_si256(
                    out.as_mut_ptr().cast::<__m256i>(),
                    _mm256_cvttps_epi32(self.0),
                );
            }
            out
        }
        #[inline(always)]
        fn out_of_range_bits(self, min: f32, max: f32) -> u32 {
            // SAFETY: see the module documentation. Ordered comparisons: false for NaN.
            unsafe {
                let m = _mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0);
                let zero = _mm256_cmp_ps::<_CMP_EQ_OQ>(m, _mm256_setzero_ps());
                let ge = _mm256_cmp_ps::<_CMP_GE_OQ>(m, _mm256_set1_ps(min));
                let le = _mm256_cmp_ps::<_CMP_LE_OQ>(m, _mm256_set1_ps(max));
                let ok = _mm256_or_ps(zero, _mm256_and_ps(ge, le));
                !(_mm256_movemask_ps(ok) as u32) & 0xFF
            }
        }
    }

    impl F64V for D4 {
        #[inline(always)]
        fn splat(x: f64) -> Self {
            // SAFETY: see the module documentation.
            D4(unsafe { _mm256_set1_pd(x) })
        }
        #[inline(always)]
        fn from_f32(a: [f32; 4]) -> Self {
            // SAFETY: `a` is 4 readable f32; AVX present (module docs). f32 -> f64 is exact.
            D4(unsafe { _mm256_cvtps_pd(_mm_loadu_ps(a.as_ptr())) })
        }
    }

    /// [`Arith`] for a 256-bit lane type, from its intrinsics (`_ps` or `_pd`).
    macro_rules! arith {
        ($t:ident, $andnot:ident, $set1:ident, $cmp:ident, $movemask:ident, $setzero:ident) => {
            impl Arith for $t {
                #[inline(always)]
                fn abs(self) -> Self {
                    // SAFETY: see the module documentation. Clears the sign bit.
                    $t(unsafe { $andnot($set1(-0.0), self.0) })
                }
                #[inline(always)]
                fn gt_bits(self, other: Self) -> u32 {
                    // SAFETY: see the module documentation.
                    unsafe { $movemask($cmp::<_CMP_GT_OQ>(self.0, other.0)) as u32 }
                }
                #[inline(always)]
                fn zero_bits(self) -> u32 {
                    // SAFETY: see the module documentation.
                    unsafe { $movemask($cmp::<_CMP_EQ_OQ>(self.0, $setzero())) as u32 }
                }
            }
        };
    }
    arith!(
        F8,
        _mm256_andnot_ps,
        _mm256_set1_ps,
        _mm256_cmp_ps,
        _mm256_movemask_ps,
        _mm256_setzero_ps
    );
    arith!(
        D4,
        _mm256_andnot_pd,
        _mm256_set1_pd,
        _mm256_cmp_pd,
        _mm256_movemask_pd,
        _mm256_setzero_pd
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scalar definition of a several-light sign byte's bits for light `k`.
    fn bits(x: f32, k: u32) -> u32 {
        if x > 0.0 {
            1 << k
        } else if x < 0.0 {
            16 << k
        } else {
            0
        }
    }

    /// `or_sign_bits` and `or_sign_bits3` at level `Lv` against the scalar definitions, on
    /// lanes mixing signs, zeros of both signs, NaN and infinities.
    fn check_level<Lv: Level>() {
        let vals = [
            1.0f32,
            -2.0,
            0.0,
            -0.0,
            f32::NAN,
            f32::INFINITY,
            -f32::INFINITY,
            1e-45,
        ];
        let ld = |v: [f32; 8]| -> Lv::F {
            // SAFETY: 8 in-range indices into `v`.
            unsafe { Lv::F::gather(&v, &[0, 1, 2, 3, 4, 5, 6, 7]) }
        };
        let mut n = 0u32;
        for i in 0..vals.len() {
            for j in 0..vals.len() {
                // Lane q holds a rotation of the values, so every triple occurs.
                let a: [f32; 8] = std::array::from_fn(|q| vals[(i + q) % 8]);
                let b: [f32; 8] = std::array::from_fn(|q| vals[(j + 3 * q) % 8]);
                let c: [f32; 8] = std::array::from_fn(|q| vals[q]);
                for k in 0..4u32 {
                    // Bits of the other lights are kept.
                    let other = 0xFF & !(0x11 << k);
                    let mut three = [other; 8];
                    ld(a).or_sign_bits3(ld(b), ld(c), &mut three, k);
                    let mut one = [other; 8];
                    ld(a).or_sign_bits(&mut one, k);
                    for q in 0..8 {
                        let (x, y, z) = (bits(a[q], k), bits(b[q], k), bits(c[q], k));
                        let agree = if x == y && y == z { x } else { 0 };
                        assert_eq!(three[q], other | agree, "{:?} lane {q}", (a[q], b[q], c[q]));
                        assert_eq!(one[q], other | x, "{} lane {q}", a[q]);
                        n += u32::from(agree != 0);
                    }
                }
            }
        }
        assert!(n > 0, "some triples must agree");
    }
    /// `canon8` at level `Lv` sorts each triangle, against a sort of each triangle.
    fn check_canon8<Lv: Level>() {
        let mut x = 0x9E37_79B9u32;
        for _ in 0..200 {
            let tris: [[u32; 3]; 8] = std::array::from_fn(|_| {
                std::array::from_fn(|_| {
                    x ^= x << 13;
                    x ^= x >> 17;
                    x ^= x << 5;
                    // Ids on both sides of 2^31, so a signed comparison would fail.
                    x.rotate_left(x & 31) | (x & 1) << 31
                })
            });
            let got = Lv::canon8(&tris);
            for (i, t) in tris.iter().enumerate() {
                let mut want = *t;
                want.sort_unstable();
                assert_eq!([got[0][i], got[1][i], got[2][i]], want, "{tris:?} lane {i}");
            }
        }
    }

    #[test]
    fn canon8_of_every_level_sorts_each_triangle() {
        check_canon8::<Wide>();
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            #[target_feature(enable = "avx2")]
            unsafe fn run() {
                check_canon8::<Avx2>();
            }
            // SAFETY: AVX2 detected above.
            unsafe { run() }
        }
    }

    #[test]
    fn sign_bits_of_every_level_follow_the_scalar_definition() {
        check_level::<Wide>();
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            #[target_feature(enable = "avx2")]
            unsafe fn run() {
                check_level::<Avx2>();
            }
            // SAFETY: AVX2 detected above.
            unsafe { run() }
        }
    }
}
