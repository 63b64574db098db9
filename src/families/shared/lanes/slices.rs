//! The lanes' functions over whole slices, for loops whose only vector work is one function of
//! an array (a width rule's node positions, a column's attenuations): `exp(a·x)`, `asin` and
//! `sin/cos` of every element, on the widest register this CPU has. Every register gives the
//! same bits (the functions are written once over [`Lane`]).

use super::functions::LaneFunctions;
use super::vector::Lane;

/// Defines `$name(args…)` dispatching to `$kernel::<V>` compiled for AVX-512, AVX2 or `wide`
/// (the kernel generic over [`Lane`], `#[inline(always)]`, so its lane operations are single
/// instructions in each copy). Used where it is defined, by the families' kernels too.
macro_rules! dispatch {
    ($(#[$doc:meta])* $vis:vis $name:ident, $kernel:ident, ($($arg:ident: $ty:ty),*)) => {
        $(#[$doc])*
        $vis fn $name($($arg: $ty),*) {
            #[cfg(target_arch = "x86_64")]
            {
                use $crate::families::shared::lanes::{avx2, avx512, vector::Pair};
                #[target_feature(enable = "avx2,avx512f,avx512dq")]
                unsafe fn on_avx512($($arg: $ty),*) {
                    $kernel::<avx512::F64x8>($($arg),*)
                }
                #[target_feature(enable = "avx2")]
                unsafe fn on_avx2($($arg: $ty),*) {
                    $kernel::<Pair<avx2::F64x4>>($($arg),*)
                }
                if avx512::available() {
                    // SAFETY: the CPU has AVX-512F and AVX-512DQ.
                    return unsafe { on_avx512($($arg),*) };
                }
                if avx2::available() {
                    // SAFETY: the CPU has AVX2.
                    return unsafe { on_avx2($($arg),*) };
                }
            }
            $kernel::<wide::f64x4>($($arg),*)
        }
    };
}
pub(crate) use dispatch;

dispatch!(
    /// `out[k] = exp(a·x[k])`.
    pub(crate) exp_scaled,
    exp_scaled_on,
    (a: f64, x: &[f64], out: &mut [f64])
);
dispatch!(
    /// `out[k] = asin(x[k])`.
    pub(crate) asin,
    asin_on,
    (x: &[f64], out: &mut [f64])
);
dispatch!(
    /// `sin[k], cos[k] = sin x[k], cos x[k]`.
    pub(crate) sin_cos,
    sin_cos_on,
    (x: &[f64], sin: &mut [f64], cos: &mut [f64])
);

/// Each register of `$x` (the last one padded with zeros) as `$v`, its results `$body` written to
/// `$out…`. A macro, not a function taking a closure: a closure is compiled without the
/// kernel's target features, so its lane operations would not inline.
macro_rules! each {
    ($V:ty, $x:expr, |$v:ident| $body:expr => $($out:expr),+) => {{
        let x: &[f64] = $x;
        $(assert_eq!($out.len(), x.len(), "one output per input");)+
        let mut start = 0;
        while start < x.len() {
            let n = <$V>::LANES.min(x.len() - start);
            let $v = <$V>::from_fn(|l| if l < n { x[start + l] } else { 0.0 });
            let results = $body;
            let mut k = 0;
            $(
                $out[start..start + n].copy_from_slice(&results[k].to_array().as_ref()[..n]);
                k += 1;
            )+
            let _ = k;
            start += n;
        }
    }};
}

#[inline(always)]
fn exp_scaled_on<V: Lane>(a: f64, x: &[f64], out: &mut [f64]) {
    each!(V, x, |v| [(v * a).exp()] => out);
}

#[inline(always)]
fn asin_on<V: Lane>(x: &[f64], out: &mut [f64]) {
    each!(V, x, |v| [v.asin()] => out);
}

#[inline(always)]
fn sin_cos_on<V: Lane>(x: &[f64], sin: &mut [f64], cos: &mut [f64]) {
    each!(V, x, |v| {
        let (s, c) = v.sin_cos();
        [s, c]
    } => sin, cos);
}

#[cfg(test)]
mod tests {
    use super::*;
    use wide::f64x4;

    /// Each slice function equals its lane function element by element on the portable
    /// register (bit for bit, partial registers included): the dispatch and the padding lose
    /// nothing, whichever register this CPU picks (the registers agree bit for bit:
    /// `functions`' tests). Through the trait: wide's inherent methods of the same names are
    /// its own functions.
    #[test]
    fn slices_are_their_lane_functions_element_by_element() {
        for len in [0, 1, 3, 4, 7, 8, 9, 17, 100] {
            let x: Vec<f64> = (0..len).map(|k| -0.99 + 1.98 * k as f64 / 100.0).collect();
            let one = |f: &dyn Fn(f64x4) -> f64x4, v: f64| f(f64x4::splat(v)).to_array()[0];
            let mut out = vec![0.0; len];
            exp_scaled(-1.7, &x, &mut out);
            for (o, v) in out.iter().zip(&x) {
                assert_eq!(
                    o.to_bits(),
                    one(&|w| LaneFunctions::exp(w * -1.7), *v).to_bits()
                );
            }
            asin(&x, &mut out);
            for (o, v) in out.iter().zip(&x) {
                assert_eq!(o.to_bits(), one(&|w| LaneFunctions::asin(w), *v).to_bits());
            }
            let mut cos = vec![0.0; len];
            sin_cos(&x, &mut out, &mut cos);
            for ((s, c), v) in out.iter().zip(&cos).zip(&x) {
                assert_eq!(
                    s.to_bits(),
                    one(&|w| LaneFunctions::sin_cos(w).0, *v).to_bits()
                );
                assert_eq!(
                    c.to_bits(),
                    one(&|w| LaneFunctions::sin_cos(w).1, *v).to_bits()
                );
            }
        }
    }
}
