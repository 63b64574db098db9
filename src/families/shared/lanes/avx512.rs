//! [`F64x8`]: eight f64 lanes in one AVX-512 register, for CPUs with AVX-512F and AVX-512DQ.
//! Twice the samples per instruction of [`super::avx2::F64x4`], with the same IEEE operations
//! lane by lane, so the same bits. AVX-512 compares give bit masks (`k` registers), not vectors;
//! the trait's all-ones mask vectors are made from them with `vpmovm2q` and read back with
//! `vpmovq2m`, which the compiler mostly folds away (the built kernel holds 2 `vpmovm2q` and 8
//! `vpmovq2m` beside 290 compares).
//!
//! As in `avx2`: every method is `#[inline(always)]` so that inside a
//! `#[target_feature(enable = "avx512f,avx512dq")]` caller each intrinsic is one instruction, and
//! a value of this type exists only after the CPU was found to have both ([`available`]): that
//! is what makes the `unsafe` blocks sound.

use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Sub};

use super::register::{register_lane_items, register_operators};
use super::vector::Lane;

/// Eight f64 lanes in an AVX-512 register (see the module's safety note).
#[derive(Clone, Copy)]
pub(crate) struct F64x8(__m512d);

/// Whether this CPU runs [`F64x8`].
pub(crate) fn available() -> bool {
    std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512dq")
}

register_operators!(F64x8 {
    arithmetic Add::add = _mm512_add_pd, Sub::sub = _mm512_sub_pd, Mul::mul = _mm512_mul_pd,
        Div::div = _mm512_div_pd;
    bits BitAnd::bitand = _mm512_and_pd, BitOr::bitor = _mm512_or_pd,
        BitXor::bitxor = _mm512_xor_pd;
});

impl F64x8 {
    /// The lanes set in `k` all ones, the others zero.
    #[inline(always)]
    fn from_mask(k: __mmask8) -> Self {
        // SAFETY: as in `splat`.
        F64x8(unsafe { _mm512_castsi512_pd(_mm512_movm_epi64(k)) })
    }

    /// The lanes whose sign bit is set (as `vblendvpd` and `movmskpd` read a mask).
    #[inline(always)]
    fn to_mask(self) -> __mmask8 {
        // SAFETY: as in `splat`.
        unsafe { _mm512_movepi64_mask(_mm512_castpd_si512(self.0)) }
    }
}

impl Lane for F64x8 {
    #[inline(always)]
    fn move_mask(self) -> i32 {
        i32::from(self.to_mask())
    }
    #[inline(always)]
    fn blend(self, t: Self, f: Self) -> Self {
        // SAFETY: as in `splat`.
        F64x8(unsafe { _mm512_mask_blend_pd(self.to_mask(), f.0, t.0) })
    }
    #[inline(always)]
    fn shl_bits<const N: i32>(self) -> Self {
        // SAFETY: as in `splat`. The count is a constant: the compiler emits the immediate form.
        F64x8(unsafe {
            let count = _mm512_set1_epi64(i64::from(N));
            _mm512_castsi512_pd(_mm512_sllv_epi64(_mm512_castpd_si512(self.0), count))
        })
    }
    // `vrndscalepd` with scale 0 rounds as `vroundpd` does; `min`/`max` give `o` where either is
    // NaN, as the AVX2 kernel's `vminpd`.
    register_lane_items! {
        F64x8(__m512d; 8), compare: Self::from_mask = _mm512_cmp_pd_mask,
        splat: _mm512_set1_pd, load: _mm512_loadu_pd, store: _mm512_storeu_pd,
        abs: _mm512_andnot_pd, sqrt: _mm512_sqrt_pd, round: _mm512_roundscale_pd,
        min: _mm512_min_pd, max: _mm512_max_pd
    }
}
