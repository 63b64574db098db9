//! The exponentially scaled modified Bessel function `i0e(x) = e^{−|x|} I₀(x)`, generic over the
//! number type so that `M_p` differentiates exactly under forward-mode AD.
//!
//! Cephes' Chebyshev expansions (Moshier): 30 terms in `x/2 − 2` on [0, 8], 25 terms in
//! `32/x − 2` times `1/√x` above. Relative error ≲ 1e-15 over the whole axis (checked against the
//! power series and the asymptotic series in the tests below). Evaluating the expansion with dual
//! numbers gives the derivative of the approximation, which agrees with `i1e − i0e` to the same
//! order. pbrt's 10-term series is deliberately not used (CHIANG.md "pbrt numerics").

use num_dual::DualNum;

/// Chebyshev coefficients of `e^{−x} I₀(x)` on [0, 8] (Cephes `i0.c`, table A).
#[allow(clippy::excessive_precision)]
const I0E_SMALL: [f64; 30] = [
    -4.415_341_646_479_339_379_50e-18,
    3.330_794_518_822_238_097_83e-17,
    -2.431_279_846_547_954_693_59e-16,
    1.715_391_285_555_133_030_61e-15,
    -1.168_533_287_799_345_168_08e-14,
    7.676_185_498_604_935_616_88e-14,
    -4.856_446_783_111_929_460_90e-13,
    2.955_052_663_129_639_834_61e-12,
    -1.726_826_291_441_555_707_23e-11,
    9.675_809_035_373_236_912_24e-11,
    -5.189_795_601_635_262_906_66e-10,
    2.659_823_724_682_386_650_35e-9,
    -1.300_025_009_986_248_042_12e-8,
    6.046_995_022_541_918_949_32e-8,
    -2.670_793_853_940_611_733_91e-7,
    1.117_387_539_120_103_718_15e-6,
    -4.416_738_358_458_750_563_59e-6,
    1.644_844_807_072_889_708_93e-5,
    -5.754_195_010_082_103_703_98e-5,
    1.885_028_850_958_416_557_29e-4,
    -5.763_755_745_385_823_658_85e-4,
    1.639_475_616_941_335_798_42e-3,
    -4.324_309_995_050_575_944_30e-3,
    1.054_646_039_459_499_831_83e-2,
    -2.373_741_480_589_946_881_56e-2,
    4.930_528_423_967_070_848_78e-2,
    -9.490_109_704_804_764_442_10e-2,
    1.716_209_015_222_087_753_49e-1,
    -3.046_826_723_431_983_986_83e-1,
    6.767_952_744_094_760_849_95e-1,
];

/// Chebyshev coefficients of `e^{−x} √x I₀(x)` in `32/x − 2` for x > 8 (Cephes `i0.c`, table B).
#[allow(clippy::excessive_precision)]
const I0E_LARGE: [f64; 25] = [
    -7.233_180_487_874_753_954_56e-18,
    -4.830_504_485_944_182_071_26e-18,
    4.465_621_420_296_759_999_01e-17,
    3.461_222_867_697_461_093_10e-17,
    -2.827_623_980_516_583_484_94e-16,
    -3.425_485_619_677_219_134_62e-16,
    1.772_560_133_056_526_383_60e-15,
    3.811_680_669_352_622_420_75e-15,
    -9.554_846_698_828_307_648_70e-15,
    -4.150_569_347_287_222_086_63e-14,
    1.540_086_217_521_409_826_91e-14,
    3.852_778_382_742_142_701_14e-13,
    7.180_124_451_383_666_233_67e-13,
    -1.794_178_531_506_806_117_78e-12,
    -1.321_581_184_044_771_311_88e-11,
    -3.149_916_527_963_241_364_54e-11,
    1.188_914_710_784_643_834_24e-11,
    4.940_602_388_224_969_589_10e-10,
    3.396_232_025_708_386_345_15e-9,
    2.266_668_990_498_178_064_59e-8,
    2.048_918_589_469_063_741_83e-7,
    2.891_370_520_834_756_482_97e-6,
    6.889_758_346_916_823_984_26e-5,
    3.369_116_478_255_694_089_90e-3,
    8.044_904_110_141_088_316_08e-1,
];

/// Clenshaw sum `½(b₀ − b₂)` of a Chebyshev series in Cephes' order (highest degree first).
#[inline]
fn chebyshev<T: DualNum<f64>>(x: &T, coefficients: &[f64]) -> T {
    let mut b0 = T::from(coefficients[0]);
    let mut b1 = T::from(0.0);
    let mut b2 = T::from(0.0);
    for &c in &coefficients[1..] {
        b2 = b1;
        b1 = b0;
        b0 = x.clone() * b1.clone() - b2.clone() + c;
    }
    (b0 - b2) * 0.5
}

/// `i0e(x) = e^{−|x|} I₀(x)`, finite for every finite x (→ 1/√(2πx) as x → ∞).
pub fn i0e<T: DualNum<f64>>(x: &T) -> T {
    let a = if x.re() < 0.0 { -x.clone() } else { x.clone() };
    if a.re() <= 8.0 {
        chebyshev(&(a * 0.5 - 2.0), &I0E_SMALL)
    } else {
        chebyshev(&(a.recip() * 32.0 - 2.0), &I0E_LARGE) / a.sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::Dual64;

    /// `e^{−x} Σ (x²/4)^k / (k!)²`, summed in f64: all terms positive, so relative error ~1e-15.
    fn series(x: f64) -> f64 {
        let q = x * x / 4.0;
        let (mut term, mut sum, mut k) = ((-x).exp(), 0.0, 0.0);
        while term > sum * 1e-18 || k < 5.0 {
            sum += term;
            k += 1.0;
            term *= q / (k * k);
        }
        sum
    }

    /// Hankel's asymptotic series `(2πx)^{-1/2} Σ ((2k−1)!!)² / (k! (8x)^k)`, truncated while terms fall.
    fn asymptotic(x: f64) -> f64 {
        let (mut term, mut sum, mut k) = (1.0, 0.0, 0.0_f64);
        loop {
            sum += term;
            k += 1.0;
            let next = term * (2.0 * k - 1.0) * (2.0 * k - 1.0) / (k * 8.0 * x);
            if next.abs() >= term.abs() || next.abs() < 1e-20 * sum {
                break;
            }
            term = next;
        }
        sum / (2.0 * std::f64::consts::PI * x).sqrt()
    }

    #[test]
    fn matches_power_series_and_asymptote() {
        // Power series up to x = 40 (its own rounding grows with the ~40 terms summed: 1e-14);
        // above, Hankel's series (a few terms, 2e-15). Both are independent of the Chebyshev tables.
        for i in 0..=400 {
            let x = i as f64 * 0.1;
            let rel = (i0e(&x) - series(x)).abs() / series(x);
            assert!(rel < 1e-14, "x = {x}: rel {rel:e}");
        }
        for x in [40.0, 55.5, 100.0, 1e3, 1e5, 1e8] {
            let rel = (i0e(&x) - asymptotic(x)).abs() / asymptotic(x);
            assert!(rel < 2e-15, "x = {x}: rel {rel:e}");
        }
        assert_eq!(i0e(&0.0), 1.0);
        assert_eq!(i0e(&-3.0), i0e(&3.0));
    }

    /// `e^{−x} I₁(x) = e^{−x} Σ (x/2)^{2k+1} / (k!(k+1)!)`, same summation as [`series`].
    fn series_i1e(x: f64) -> f64 {
        let q = x * x / 4.0;
        let (mut term, mut sum, mut k) = ((-x).exp() * x / 2.0, 0.0, 0.0);
        while term > sum * 1e-18 || k < 5.0 {
            sum += term;
            k += 1.0;
            term *= q / (k * (k + 1.0));
        }
        sum
    }

    #[test]
    fn dual_derivative_is_i1e_minus_i0e() {
        // d/dx[e^{−x} I₀(x)] = e^{−x}(I₁(x) − I₀(x)) exactly; both from their power series. The
        // difference cancels to ~1/(2x) of i0e, so compare against i0e's scale (1e-13: the series'
        // rounding, ~40 terms, amplified by that cancellation).
        for x in [0.3, 2.0, 7.9, 8.1, 15.0, 39.0] {
            let d = i0e(&Dual64::from_re(x).derivative()).eps;
            let exact = series_i1e(x) - series(x);
            assert!(
                (d - exact).abs() < 1e-13 * series(x),
                "x = {x}: {d} vs {exact}"
            );
        }
    }
}
