//! [`F64x4`]: four f64 lanes in one AVX register, for CPUs with AVX2. The default x86-64 build
//! has no AVX, so wide's vectors are two SSE2 halves; this type is chosen at run time
//! (`is_x86_feature_detected!`) and does the same IEEE operations on the whole register, so it
//! gives the same bits in about half the instructions. The AVX2 kernel runs two of them side by
//! side ([`super::vector::Pair`]).
//!
//! Every method is `#[inline(always)]`, so inside a `#[target_feature(enable = "avx2")]` caller
//! the intrinsics inline to single instructions (out of line, every intrinsic is a call). A value
//! of this type exists only after the CPU was found to have AVX2 ([`available`]): that is what
//! makes the `unsafe` blocks sound.

use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Sub};

use super::vector::{register_operators, Lane};

/// Four f64 lanes in an AVX register (see the module's safety note).
#[derive(Clone, Copy)]
pub(super) struct F64x4(__m256d);

/// Whether this CPU runs [`F64x4`].
pub(super) fn available() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

/// `f64`'s sign bit.
const SIGN: f64 = -0.0;

register_operators!(F64x4 {
    arithmetic Add::add = _mm256_add_pd;
    arithmetic Sub::sub = _mm256_sub_pd;
    arithmetic Mul::mul = _mm256_mul_pd;
    arithmetic Div::div = _mm256_div_pd;
    bits BitAnd::bitand = _mm256_and_pd;
    bits BitOr::bitor = _mm256_or_pd;
    bits BitXor::bitxor = _mm256_xor_pd;
});

macro_rules! compare {
    ($method:ident, $predicate:ident) => {
        #[inline(always)]
        fn $method(self, o: Self) -> Self {
            // SAFETY: as in `splat`.
            F64x4(unsafe { _mm256_cmp_pd::<$predicate>(self.0, o.0) })
        }
    };
}

impl Lane for F64x4 {
    const LANES: usize = 4;
    type Array = [f64; 4];
    // SAFETY (both): [f64; 4] and __m256d have the same size, and every bit pattern is valid.
    const ZERO: Self = F64x4(unsafe { std::mem::transmute::<[f64; 4], __m256d>([0.0; 4]) });
    const ONE: Self = F64x4(unsafe { std::mem::transmute::<[f64; 4], __m256d>([1.0; 4]) });

    #[inline(always)]
    fn splat(x: f64) -> Self {
        // SAFETY: values of this type exist only on CPUs with AVX2 (module note).
        F64x4(unsafe { _mm256_set1_pd(x) })
    }
    #[inline(always)]
    fn new(lanes: [f64; 4]) -> Self {
        // SAFETY: as in `splat`; the array holds four f64.
        F64x4(unsafe { _mm256_loadu_pd(lanes.as_ptr()) })
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 4] {
        let mut lanes = [0.0; 4];
        // SAFETY: as in `splat`; the array holds four f64.
        unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), self.0) };
        lanes
    }
    #[inline(always)]
    fn move_mask(self) -> i32 {
        // SAFETY: as in `splat`.
        unsafe { _mm256_movemask_pd(self.0) }
    }
    #[inline(always)]
    fn blend(self, t: Self, f: Self) -> Self {
        // SAFETY: as in `splat`.
        F64x4(unsafe { _mm256_blendv_pd(f.0, t.0, self.0) })
    }
    compare!(cmp_eq, _CMP_EQ_OQ);
    compare!(cmp_ne, _CMP_NEQ_UQ);
    compare!(cmp_lt, _CMP_LT_OQ);
    compare!(cmp_le, _CMP_LE_OQ);
    compare!(cmp_gt, _CMP_GT_OQ);
    compare!(cmp_ge, _CMP_GE_OQ);
    #[inline(always)]
    fn abs(self) -> Self {
        // SAFETY: as in `splat`.
        F64x4(unsafe { _mm256_andnot_pd(Self::splat(SIGN).0, self.0) })
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // SAFETY: as in `splat`.
        F64x4(unsafe { _mm256_sqrt_pd(self.0) })
    }
    #[inline(always)]
    fn round(self) -> Self {
        // SAFETY: as in `splat`.
        F64x4(unsafe {
            _mm256_round_pd::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(self.0)
        })
    }
    /// `o` where either is NaN (wide's picks the number: the same wherever `o` is not NaN,
    /// which is the trait's contract).
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        // SAFETY: as in `splat`.
        F64x4(unsafe { _mm256_min_pd(self.0, o.0) })
    }
    /// As `min`.
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        // SAFETY: as in `splat`.
        F64x4(unsafe { _mm256_max_pd(self.0, o.0) })
    }

    #[inline(always)]
    fn shl_bits<const N: i32>(self) -> Self {
        // SAFETY: as in `splat`.
        F64x4(unsafe { _mm256_castsi256_pd(_mm256_slli_epi64::<N>(_mm256_castpd_si256(self.0))) })
    }
}
