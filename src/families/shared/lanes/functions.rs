//! exp, sin/cos, asin and acos on the lanes, written once over [`Lane`]'s basic operations, so
//! every kernel (wide's SSE2 halves, AVX registers, one AVX-512 register) runs the same
//! operations and gives the same bits on any CPU. Nothing is fused (`Lane::mul_add` rounds
//! twice): a fused multiply-add would change the last bits on CPUs that have it. Their domain is the model's: arguments of
//! moderate size (|x| ≲ 10⁵ for sin/cos), where a three-part reduction stays exact enough. Each
//! is within 1 ulp of libm (tests below).

use std::f64::consts::{FRAC_2_PI, LOG2_E};

use super::vector::Lane;

// π/2 in three parts, the first two of 33 significant bits: `n · part` is exact for |n| < 2²⁰
// and `x − n·PIO2_1` exact (Sterbenz), so the reduction loses nothing for the model's angles.
const PIO2_1: f64 = 1.570_796_326_734_125_6;
const PIO2_2: f64 = 6.077_100_506_303_966e-11;
const PIO2_3: f64 = 2.022_266_248_795_950_6e-21;
// ln 2 in two parts, the first of 32 bits: `n · LN2_HI` is exact for the exponents exp reaches.
const LN2_HI: f64 = 0.693_147_180_369_123_8;
const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
// π/2 as the f64 nearest it plus the rest, for asin/acos's `π/2 − …`.
const PIO2_HI: f64 = std::f64::consts::FRAC_PI_2;
const PIO2_LO: f64 = 6.123_233_995_736_766e-17;
const PIO4_HI: f64 = std::f64::consts::FRAC_PI_4;
/// 2⁵² + 2⁵¹: added to an integer-valued f64 below 2⁵¹ in magnitude, it leaves the integer in
/// the low bits of the sum.
const INTEGER_BITS: f64 = 6_755_399_441_055_744.0;
/// f64's sign bit.
const SIGN: f64 = -0.0;

/// Near-minimax coefficients (highest degree first) of `P` in `asin(√z) = √z + z√z·P(z)` on
/// `z ∈ [0, 1/4]`: a Chebyshev fit of degree 12, 5e-18 relative in asin after rounding the
/// coefficients to f64.
const ASIN_P: [f64; 13] = [
    0.028_757_851_367_421_566,
    -0.014_851_887_071_247_204,
    0.017_400_879_442_694_02,
    0.005_457_506_718_640_358,
    0.010_322_814_350_185_78,
    0.011_479_177_415_184_906,
    0.013_971_212_973_552_933,
    0.017_352_392_720_869_973,
    0.022_372_172_942_149_89,
    0.030_381_944_138_531_247,
    0.044_642_857_146_355_43,
    0.074_999_999_999_984_33,
    0.166_666_666_666_666_69,
];

/// `e^r`'s Taylor coefficients `1/k!`, k = 13 down to 0.
const EXP_TAYLOR: [f64; 14] = taylor(0, 1, 1.0, false);

/// `S` in `sin r = r + r³·S(r²)`: `(−1)^(m+1)/(2m+3)!` for m = 7 down to 0.
const SIN_TAYLOR: [f64; 8] = taylor(3, 2, -1.0, true);

/// `C` in `cos r = 1 − r²/2 + r⁴·C(r²)`: `(−1)^m/(2m+4)!` for m = 6 down to 0.
const COS_TAYLOR: [f64; 7] = taylor(4, 2, 1.0, true);

/// Coefficients `sign_m/(lowest + step·m)!` for m = N−1 down to 0 (highest degree first), with
/// `sign_m = first_sign·(−1)^m` when `alternate`, else `first_sign`.
const fn taylor<const N: usize>(
    lowest: usize,
    step: usize,
    first_sign: f64,
    alternate: bool,
) -> [f64; N] {
    let mut c = [0.0; N];
    let mut i = 0;
    while i < N {
        let m = N - 1 - i;
        let sign = if alternate && m % 2 == 1 {
            -first_sign
        } else {
            first_sign
        };
        c[i] = sign / factorial(lowest + step * m);
        i += 1;
    }
    c
}

/// `k!` as f64 (exact up to 18!, which is all the series use).
const fn factorial(k: usize) -> f64 {
    let mut f = 1.0;
    let mut i = 2;
    while i <= k {
        f *= i as f64;
        i += 1;
    }
    f
}

/// Horner's rule at `x` over `coefficients`, highest degree first.
#[inline(always)]
fn polynomial<V: Lane>(x: V, coefficients: &[f64]) -> V {
    let (first, rest) = coefficients.split_first().expect("a coefficient");
    let mut p = V::splat(*first);
    for &c in rest {
        p = p.mul_add(x, V::splat(c));
    }
    p
}

/// `2^k` for integer-valued `k` in the normal exponents' range: `k + 1023` into the exponent.
#[inline(always)]
fn two_to<V: Lane>(k: V) -> V {
    (k + (INTEGER_BITS + 1023.0)).shl_bits::<52>()
}

/// Largest integer ≤ x, for |x| < 2⁵¹.
#[inline(always)]
pub(crate) fn floor<V: Lane>(x: V) -> V {
    let r = x.round();
    r - (r.cmp_gt(x) & V::ONE)
}

/// `exp(x)`: `x = n ln 2 + r` with `|r| ≤ ln 2 / 2`, `e^r` by its Taylor series to r¹³
/// (truncation 6e-18 relative), scaled by `2^n` in two halves so that subnormal results come
/// out as libm's. Below −746 it is 0, above 710 ∞; NaN stays NaN.
#[inline(always)]
pub(crate) fn exp<V: Lane>(x: V) -> V {
    // Comparisons with NaN are false, so NaN passes the clamp.
    let x = x.cmp_lt(V::splat(-746.0)).blend(V::splat(-746.0), x);
    let x = x.cmp_gt(V::splat(710.0)).blend(V::splat(710.0), x);
    let n = (x * LOG2_E).round();
    let r = (x - n * LN2_HI) - n * LN2_LO;
    let e_r = polynomial(r, &EXP_TAYLOR);
    let half = floor(n * 0.5);
    e_r * two_to(half) * two_to(n - half)
}

/// `(sin x, cos x)`: `x = n π/2 + r` with `|r| ≤ π/4`, both Taylor series (to r¹⁷ and r¹⁶:
/// truncation below 1e-17), then the quadrant `n mod 4` swaps and signs them.
#[inline(always)]
pub(crate) fn sin_cos<V: Lane>(x: V) -> (V, V) {
    let n = (x * FRAC_2_PI).round();
    let r = ((x - n * PIO2_1) - n * PIO2_2) - n * PIO2_3;
    let z = r * r;
    let sin_r = (r * z).mul_add(polynomial(z, &SIN_TAYLOR), r);
    let cos_r = z.mul_add(
        z.mul_add(polynomial(z, &COS_TAYLOR), V::splat(-0.5)),
        V::ONE,
    );
    // n mod 4: 1 and 3 swap sin and cos; 2 and 3 negate sin, 1 and 2 negate cos.
    let q = n - floor(n * 0.25) * 4.0;
    let (one, two, three) = (V::ONE, V::splat(2.0), V::splat(3.0));
    let swap = q.cmp_eq(one) | q.cmp_eq(three);
    let sin_sign = q.cmp_ge(two) & V::splat(SIGN);
    let cos_sign = (q.cmp_eq(one) | q.cmp_eq(two)) & V::splat(SIGN);
    (
        swap.blend(cos_r, sin_r) ^ sin_sign,
        swap.blend(sin_r, cos_r) ^ cos_sign,
    )
}

/// The halves of asin for `a ∈ [0, 1]`: `(s, z, r, big)` with `asin = s + s·r` below 1/2
/// (`s = a`, `r = a²P(a²)`), and above it (`big`) `asin(√z) = s + s·r` for `z = (1−a)/2`,
/// `s = √z`, from which `asin a = π/2 − 2(s + s·r)` keeps its accuracy up to `a = 1`.
#[inline(always)]
fn asin_halves<V: Lane>(a: V) -> (V, V, V, V) {
    let big = a.cmp_gt(V::splat(0.5));
    let z = big.blend((-a + 1.0) * 0.5, a * a);
    let s = big.blend(z.sqrt(), a);
    (s, z, z * polynomial(z, &ASIN_P), big)
}

/// `asin x`. Above 1/2, `π/2 − 2(s + s·r)`: the rounding of `s` alone would cost an ulp of the
/// result, so `s` is split into `w` (its high 21 bits) and `c = (z − w²)/(s + w)` (`w²` and
/// `z − w²` are exact), and `π/2 − 2w` is formed from two halves of π/4. That keeps it within
/// 1 ulp, where `π/2 − 2p` directly was 2: the glint's φ_c depends on it, and a narrow glint
/// amplifies φ_c's error by 1/w_c.
#[inline(always)]
pub(crate) fn asin<V: Lane>(x: V) -> V {
    let (s, z, r, big) = asin_halves(x.abs());
    let w = s & V::splat(f64::from_bits(0xFFFF_FFFF_0000_0000));
    // At |x| = 1, s = w = 0: c is 0 (and NaN stays NaN through z).
    let c = (z - w * w) / (s + w).max(V::splat(f64::MIN_POSITIVE));
    let low = (s * 2.0) * r - (V::splat(PIO2_LO) - c * 2.0);
    let high = V::splat(PIO4_HI) - w * 2.0;
    let folded = V::splat(PIO4_HI) - (low - high);
    big.blend(folded, s.mul_add(r, s)).copysign(x)
}

#[inline(always)]
pub(crate) fn acos<V: Lane>(x: V) -> V {
    let (s, _, r, big) = asin_halves(x.abs());
    let p = s.mul_add(r, s);
    let negative = x.cmp_lt(V::ZERO);
    // |x| ≤ 1/2: π/2 − asin x; x > 1/2: 2 asin(√((1−x)/2)); x < −1/2: π minus that.
    let small = V::splat(PIO2_HI) - (p.copysign(x) - PIO2_LO);
    let from_pi = V::splat(2.0 * PIO2_HI) - (p * 2.0 - 2.0 * PIO2_LO);
    big.blend(negative.blend(from_pi, p * 2.0), small)
}

/// The functions above as methods of every [`Lane`] (`x.exp()`, `x.sin_cos()`, …), as the
/// kernel's formulas write them.
pub(crate) trait LaneFunctions: Lane {
    #[inline(always)]
    fn exp(self) -> Self {
        exp(self)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        sin_cos(self)
    }
    #[inline(always)]
    fn cos(self) -> Self {
        sin_cos(self).1
    }
    #[inline(always)]
    fn asin(self) -> Self {
        asin(self)
    }
    #[inline(always)]
    fn acos(self) -> Self {
        acos(self)
    }
}

impl<V: Lane> LaneFunctions for V {}

#[cfg(test)]
mod tests {
    use super::*;
    use wide::f64x4;

    /// Distance in units in the last place between `a` and libm's `b` (0 when both are NaN).
    fn ulps(a: f64, b: f64) -> f64 {
        if a.is_nan() && b.is_nan() || a == b {
            return 0.0;
        }
        let tiny = f64::MIN_POSITIVE * f64::EPSILON;
        let ulp = if b == 0.0 || !b.is_finite() {
            tiny
        } else {
            2f64.powf(b.abs().log2().floor() - 52.0).max(tiny)
        };
        (a - b).abs() / ulp
    }

    /// The vector of `xs`, repeated to fill the lanes.
    fn load<V: Lane>(xs: &[f64]) -> V {
        V::from_fn(|l| xs[l % xs.len()])
    }

    /// The first `n` lanes of `v`.
    fn first<V: Lane>(v: V, n: usize) -> Vec<f64> {
        v.to_array().as_ref()[..n].to_vec()
    }

    /// The worst ulp distance from libm over `inputs`, a vector at a time.
    fn worst<V: Lane>(inputs: &[f64], ours: impl Fn(V) -> V, libm: impl Fn(f64) -> f64) -> f64 {
        let mut worst = 0.0f64;
        for c in inputs.chunks(V::LANES) {
            let out = first(ours(load(c)), c.len());
            for (&x, y) in c.iter().zip(out) {
                let u = ulps(y, libm(x));
                assert!(u.is_finite(), "{x:e}: {y:e} against {:e}", libm(x));
                worst = worst.max(u);
            }
        }
        worst
    }

    /// `n` points over `[lo, hi]`, ends included.
    fn grid(lo: f64, hi: f64, n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
            .collect()
    }

    /// The inputs of each function: its domain in the model, and the edges of its reductions.
    fn inputs() -> [Vec<f64>; 3] {
        let mut exp = grid(-745.0, 709.0, 200_000);
        exp.extend(grid(-1.0, 1.0, 50_000));
        exp.extend([
            -0.0,
            0.0,
            1e-300,
            -1e-300,
            0.5 * LN2_HI,
            -0.5 * LN2_HI,
            708.0,
            -708.5,
        ]);
        exp.extend([-709.5, -720.0, -740.0, -744.4, 1e-17, -3.0e-9, 0.346_573_59]);
        let mut trig = grid(-30.0, 30.0, 200_000);
        trig.extend(grid(-1e-3, 1e-3, 20_000));
        // At and next to multiples of π/4, where the reduction and the quadrant switch.
        for k in -40..40 {
            let x = k as f64 * std::f64::consts::FRAC_PI_4;
            trig.extend([x, x.next_up(), x.next_down(), x + 1e-9, x - 1e-9]);
        }
        let mut inverse = grid(-1.0, 1.0, 200_000);
        inverse.extend(grid(0.499, 0.501, 4_000));
        inverse.extend(grid(-0.501, -0.499, 4_000));
        inverse.extend(grid(1.0 - 1e-6, 1.0, 4_000));
        inverse.extend(grid(-1.0, -1.0 + 1e-6, 4_000));
        inverse.extend(grid(-1e-6, 1e-6, 4_000));
        [exp, trig, inverse]
    }

    /// Each function is within 1 ulp of libm (glibc's own are within 1 ulp of the truth), as
    /// measured; 1 ulp is 2e-16 relative, against the lanes' 1e-11 tolerance to the scalar
    /// model, and a second ulp anywhere fails. Every vector type gives the same bits (the same
    /// operations, none fused).
    fn check<V: Lane>() -> [Vec<u64>; 5] {
        let [exp_in, trig_in, inverse_in] = inputs();
        let worst_of = [
            ("exp", worst::<V>(&exp_in, |x| x.exp(), f64::exp)),
            ("sin", worst::<V>(&trig_in, |x| x.sin_cos().0, f64::sin)),
            ("cos", worst::<V>(&trig_in, |x| x.sin_cos().1, f64::cos)),
            ("asin", worst::<V>(&inverse_in, |x| x.asin(), f64::asin)),
            ("acos", worst::<V>(&inverse_in, |x| x.acos(), f64::acos)),
        ];
        eprintln!("worst ulp: {worst_of:?}");
        for (name, u) in worst_of {
            assert!(u <= 1.0, "{name}: {u} ulp from libm");
        }
        let bits = |inputs: &[f64], f: &dyn Fn(V) -> V| -> Vec<u64> {
            inputs
                .chunks(V::LANES)
                .flat_map(|c| first(f(load(c)), c.len()))
                .map(f64::to_bits)
                .collect()
        };
        [
            bits(&exp_in, &|x| x.exp()),
            bits(&trig_in, &|x| x.sin_cos().0),
            bits(&trig_in, &|x| x.sin_cos().1),
            bits(&inverse_in, &|x| x.asin()),
            bits(&inverse_in, &|x| x.acos()),
        ]
    }

    #[test]
    fn the_functions_are_within_one_ulp_of_libm_and_alike_on_every_kernel() {
        let wide = check::<f64x4>();
        #[cfg(target_arch = "x86_64")]
        if super::super::avx2::available() {
            let avx = check::<super::super::avx2::F64x4>();
            assert!(wide == avx, "the AVX2 vector differs from wide's");
            let pair = check::<super::super::vector::Pair<super::super::avx2::F64x4>>();
            assert!(
                wide == pair,
                "the AVX2 kernel (a pair of vectors) differs from wide's"
            );
        } else {
            eprintln!("this CPU has no AVX2: its kernel is not tested here");
        }
        #[cfg(target_arch = "x86_64")]
        if super::super::avx512::available() {
            let avx512 = check::<super::super::avx512::F64x8>();
            assert!(wide == avx512, "the AVX-512 kernel differs from wide's");
        } else {
            eprintln!("this CPU has no AVX-512: its kernel is not tested here");
        }
    }

    /// Outside the domains: exp underflows to subnormals and 0 and overflows to ∞ as libm;
    /// NaN stays NaN everywhere; asin/acos beyond ±1 are NaN; the ends of asin/acos are exact.
    /// (Through the functions, not method syntax: wide's own inherent methods would win.)
    fn edges<V: Lane>() {
        let one = |f: fn(V) -> V, x: f64| f(V::splat(x)).to_array().as_ref()[0];
        for x in [-745.2, -800.0, f64::NEG_INFINITY, 709.8, 1e3, f64::INFINITY] {
            assert_eq!(one(exp, x), x.exp(), "exp({x})");
        }
        for x in [-709.5, -720.0, -740.0, -744.0] {
            assert!(
                ulps(one(exp, x), x.exp()) <= 2.0,
                "exp({x}) = {:e}",
                one(exp, x)
            );
        }
        let nan = V::splat(f64::NAN);
        assert!(first(exp(nan), V::LANES).iter().all(|v| v.is_nan()));
        let (s, c) = sin_cos(nan);
        assert!(first(s, 1)[0].is_nan() && first(c, 1)[0].is_nan());
        assert!(first(asin(nan), 1)[0].is_nan() && first(acos(nan), 1)[0].is_nan());
        let beyond: V = load(&[1.0 + 1e-15, -1.0 - 1e-15, 2.0, -3.0]);
        assert!(first(asin(beyond), V::LANES).iter().all(|v| v.is_nan()));
        assert!(first(acos(beyond), V::LANES).iter().all(|v| v.is_nan()));
        let ends: V = load(&[1.0, -1.0, 0.0, -0.0]);
        assert_eq!(
            first(acos(ends), 4),
            [0.0, std::f64::consts::PI, PIO2_HI, PIO2_HI]
        );
        let expected = [PIO2_HI, -PIO2_HI, 0.0, -0.0].map(f64::to_bits);
        let asin_bits: Vec<u64> = first(asin(ends), 4).into_iter().map(f64::to_bits).collect();
        assert_eq!(asin_bits, expected);
    }

    #[test]
    fn the_edges_are_libms() {
        edges::<f64x4>();
        #[cfg(target_arch = "x86_64")]
        if super::super::avx2::available() {
            edges::<super::super::avx2::F64x4>();
            edges::<super::super::vector::Pair<super::super::avx2::F64x4>>();
        }
        #[cfg(target_arch = "x86_64")]
        if super::super::avx512::available() {
            edges::<super::super::avx512::F64x8>();
        }
    }
}
