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

use super::register::{register_lane_items, register_operators};
use super::vector::Lane;

/// Four f64 lanes in an AVX register (see the module's safety note).
#[derive(Clone, Copy)]
pub(crate) struct F64x4(__m256d);

/// Whether this CPU runs [`F64x4`].
pub(crate) fn available() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

register_operators!(F64x4 {
    arithmetic Add::add = _mm256_add_pd, Sub::sub = _mm256_sub_pd, Mul::mul = _mm256_mul_pd,
        Div::div = _mm256_div_pd;
    bits BitAnd::bitand = _mm256_and_pd, BitOr::bitor = _mm256_or_pd,
        BitXor::bitxor = _mm256_xor_pd;
});

impl Lane for F64x4 {
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
    #[inline(always)]
    fn shl_bits<const N: i32>(self) -> Self {
        // SAFETY: as in `splat`.
        F64x4(unsafe { _mm256_castsi256_pd(_mm256_slli_epi64::<N>(_mm256_castpd_si256(self.0))) })
    }
    // `min`/`max` give `o` where either is NaN (wide's pick the number: the same wherever `o` is
    // not NaN, which is the trait's contract).
    register_lane_items! {
        F64x4(__m256d; 4), compare: F64x4 = _mm256_cmp_pd, splat: _mm256_set1_pd,
        load: _mm256_loadu_pd, store: _mm256_storeu_pd, abs: _mm256_andnot_pd,
        sqrt: _mm256_sqrt_pd, round: _mm256_round_pd, min: _mm256_min_pd, max: _mm256_max_pd
    }
}
