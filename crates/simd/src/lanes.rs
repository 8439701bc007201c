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

/// Eight `f32` lanes.
pub(crate) trait F32V:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self>
{
    /// All lanes `x`.
    fn splat(x: f32) -> Self;
    /// Lanes from an array.
    fn load(a: [f32; 8]) -> Self;
    /// `(positive, negative)`: bit `i` set when lane `i` is `> 0` / `< 0`.
    fn sign_bits(self) -> (u32, u32);
    /// Per lane `+1.0`, `-1.0` or `0.0` for positive, negative and zero (or NaN) lanes.
    fn signum0(self) -> Self;
    /// Truncates to integers (the lanes are small exact integers here).
    fn to_i32(self) -> [i32; 8];
}

/// Four `f64` lanes.
pub(crate) trait F64V:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self>
{
    /// All lanes `x`.
    fn splat(x: f64) -> Self;
    /// Four `f32` values widened exactly to `f64`.
    fn widen(a: [f32; 4]) -> Self;
    /// Lane-wise absolute value.
    fn abs(self) -> Self;
    /// Bit `i` set when `self[i] > other[i]`.
    fn gt_bits(self, other: Self) -> u32;
    /// Bit `i` set when lane `i` equals `0.0`.
    fn zero_bits(self) -> u32;
}

/// An instruction-set level: a pair of lane types.
pub(crate) trait Level {
    /// Eight `f32` lanes.
    type F: F32V;
    /// Four `f64` lanes.
    type D: F64V;
}

/// The `wide` crate at the compile-time target level.
pub(crate) struct Wide;

impl Level for Wide {
    type F = wide::f32x8;
    type D = wide::f64x4;
}

impl F32V for wide::f32x8 {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        wide::f32x8::splat(x)
    }
    #[inline(always)]
    fn load(a: [f32; 8]) -> Self {
        wide::f32x8::new(a)
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
}

impl F64V for wide::f64x4 {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        wide::f64x4::splat(x)
    }
    #[inline(always)]
    fn widen(a: [f32; 4]) -> Self {
        wide::f64x4::new([
            f64::from(a[0]),
            f64::from(a[1]),
            f64::from(a[2]),
            f64::from(a[3]),
        ])
    }
    #[inline(always)]
    fn abs(self) -> Self {
        wide::f64x4::abs(self)
    }
    #[inline(always)]
    fn gt_bits(self, other: Self) -> u32 {
        self.simd_gt(other).to_bitmask()
    }
    #[inline(always)]
    fn zero_bits(self) -> u32 {
        self.simd_eq(wide::f64x4::ZERO).to_bitmask()
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use avx2::Avx2;

#[cfg(target_arch = "x86_64")]
mod avx2 {
    //! 256-bit lanes with `std::arch` intrinsics.
    //!
    //! # Safety
    //! The intrinsics require AVX (and AVX2 for the integer conversion path's callers). Values of
    //! these types are only created inside `#[target_feature(enable = "avx2")]` functions that
    //! the backend enters after `is_x86_feature_detected!("avx2")` returned true, so every
    //! intrinsic here runs on a CPU that has it.
    use super::{Level, F32V, F64V};
    use std::arch::x86_64::*;
    use std::ops::{Add, Mul, Sub};

    /// AVX2 level (256-bit `f32` and `f64` lanes).
    pub(crate) struct Avx2;

    impl Level for Avx2 {
        type F = F8;
        type D = D4;
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
        #[inline(always)]
        fn load(a: [f32; 8]) -> Self {
            // SAFETY: `a` is 8 readable f32; unaligned load; AVX present (module docs).
            F8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
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
    }

    impl F64V for D4 {
        #[inline(always)]
        fn splat(x: f64) -> Self {
            // SAFETY: see the module documentation.
            D4(unsafe { _mm256_set1_pd(x) })
        }
        #[inline(always)]
        fn widen(a: [f32; 4]) -> Self {
            // SAFETY: `a` is 4 readable f32; AVX present (module docs). f32 -> f64 is exact.
            D4(unsafe { _mm256_cvtps_pd(_mm_loadu_ps(a.as_ptr())) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            // SAFETY: see the module documentation. Clears the sign bit.
            D4(unsafe { _mm256_andnot_pd(_mm256_set1_pd(-0.0), self.0) })
        }
        #[inline(always)]
        fn gt_bits(self, other: Self) -> u32 {
            // SAFETY: see the module documentation.
            unsafe { _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(self.0, other.0)) as u32 }
        }
        #[inline(always)]
        fn zero_bits(self) -> u32 {
            // SAFETY: see the module documentation.
            unsafe {
                _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_EQ_OQ>(self.0, _mm256_setzero_pd())) as u32
            }
        }
    }
}
