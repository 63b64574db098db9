//! The number types the model runs in, and the chain rule through one scalar input.
//!
//! Most of `S`'s work (Bravais indices, exit-angle roots, Fresnel factors, the caustic) depends on
//! the parameters only through one scalar: the lobe's index of refraction `η` (or `η*`). That work
//! runs in [`ModelNum::Scalar`], a dual number with ONE direction (`d/dη`), and is then mapped onto
//! the fit's directions by the chain rule `f(η) + f'(η)·dη` ([`ModelNum::chain`]): exact first
//! derivatives at a fraction of the cost of carrying every direction through every operation.
//! For `f64` both types are `f64` and nothing changes.

use nalgebra::{allocator::Allocator, DefaultAllocator, Dim};
use num_dual::{Derivative, Dual64, DualNum, DualVec64};

/// A number type the model is generic over: `f64`, or a first-order dual vector.
pub trait ModelNum: DualNum<f64> {
    /// Numbers carrying the derivative with respect to one scalar input only.
    type Scalar: DualNum<f64>;
    /// This value as the scalar input: its real part, seeded with derivative 1.
    fn seed(&self) -> Self::Scalar;
    /// `f(x)` in `Self` from `f` at `x` in [`ModelNum::Scalar`] (seeded by [`ModelNum::seed`]):
    /// the real part of `f`, derivative `f'·(derivative of x)`.
    fn chain(f: &Self::Scalar, x: &Self) -> Self;
    /// Real part `re`, derivative `Σ a·(derivative of x)` over `terms = [(a, x), ...]`: the chain
    /// rule through a few inputs whose partial derivatives `a` are known in f64.
    fn linear(re: f64, terms: &[(f64, &Self)]) -> Self;
}

impl ModelNum for f64 {
    type Scalar = f64;
    #[inline]
    fn seed(&self) -> f64 {
        *self
    }
    #[inline]
    fn chain(f: &f64, _x: &f64) -> f64 {
        *f
    }
    #[inline]
    fn linear(re: f64, _terms: &[(f64, &f64)]) -> f64 {
        re
    }
}

impl<D: Dim> ModelNum for DualVec64<D>
where
    DefaultAllocator: Allocator<D>,
    DualVec64<D>: DualNum<f64>,
{
    type Scalar = Dual64;
    #[inline]
    fn seed(&self) -> Dual64 {
        Dual64::new(self.re, 1.0)
    }
    #[inline]
    fn chain(f: &Dual64, x: &Self) -> Self {
        DualVec64::new(f.re, &x.eps * f.eps)
    }
    #[inline]
    fn linear(re: f64, terms: &[(f64, &Self)]) -> Self {
        let mut eps = Derivative::none();
        for (a, x) in terms {
            eps += &x.eps * *a;
        }
        DualVec64::new(re, eps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Const;
    use num_dual::DualSVec64;

    /// Same value bit for bit; each derivative to 1e-15 relative (the same products of
    /// derivatives in another order: an ulp or so).
    fn assert_agree<const N: usize>(full: &DualSVec64<N>, via: &DualSVec64<N>) {
        assert_eq!(full.re, via.re);
        let (a, b) = (
            full.eps.unwrap_generic(Const::<N>, Const::<1>),
            via.eps.unwrap_generic(Const::<N>, Const::<1>),
        );
        for j in 0..N {
            assert!((a[j] - b[j]).abs() <= 1e-15 * a[j].abs(), "{a} vs {b}");
        }
    }

    /// `chain` of `sin` through a seeded scalar equals `sin` carried in every direction, to
    /// rounding (one product of derivatives vs the same product in another order: 1 ulp).
    #[test]
    fn chain_matches_the_full_dual_computation() {
        let x = DualSVec64::<3>::new(
            0.7,
            Derivative::some(nalgebra::SVector::from([1.5, -2.0, 0.25])),
        );
        let full = x.sin() * x;
        let s = x.seed();
        let via = <DualSVec64<3> as ModelNum>::chain(&(s.sin() * s), &x);
        assert_agree(&full, &via);
    }

    /// `linear` with the partials of `x·exp(y)` gives that product's dual, to rounding.
    #[test]
    fn linear_matches_the_full_dual_computation() {
        let d = |v: [f64; 2]| Derivative::some(nalgebra::SVector::from(v));
        let x = DualSVec64::<2>::new(0.3, d([1.0, 0.5]));
        let y = DualSVec64::<2>::new(-1.2, d([-0.25, 2.0]));
        let full = x * y.exp();
        let e = y.re.exp();
        let via = DualSVec64::<2>::linear(x.re * e, &[(e, &x), (x.re * e, &y)]);
        assert_agree(&full, &via);
    }
}
