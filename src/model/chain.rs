//! The number types the model runs in, and the chain rule through one scalar input.
//!
//! Most of `S`'s work (Bravais indices, exit-angle roots, Fresnel factors, the caustic) depends on
//! the parameters only through one scalar: the lobe's index of refraction `η` (or `η*`). That work
//! runs in [`ModelNum::Scalar`], a dual number with ONE direction (`d/dη`), and is then mapped onto
//! the fit's directions by the chain rule `f(η) + f'(η)·dη` ([`ModelNum::chain`]): exact first
//! derivatives at a fraction of the cost of carrying every direction through every operation.
//! For `f64` both types are `f64` and nothing changes.

use nalgebra::{allocator::Allocator, DefaultAllocator, Dim};
use num_dual::{Dual64, DualNum, DualVec64};

/// A number type the model is generic over: `f64`, or a first-order dual vector.
pub trait ModelNum: DualNum<f64> {
    /// Numbers carrying the derivative with respect to one scalar input only.
    type Scalar: DualNum<f64>;
    /// This value as the scalar input: its real part, seeded with derivative 1.
    fn seed(&self) -> Self::Scalar;
    /// `f(x)` in `Self` from `f` at `x` in [`ModelNum::Scalar`] (seeded by [`ModelNum::seed`]):
    /// the real part of `f`, derivative `f'·(derivative of x)`.
    fn chain(f: &Self::Scalar, x: &Self) -> Self;
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Const;
    use num_dual::{Derivative, DualSVec64};

    /// `chain` of `sin` through a seeded scalar equals `sin` carried in every direction, to
    /// rounding (one product of derivatives vs the same product in another order: 1 ulp).
    #[test]
    fn chain_matches_the_full_dual_computation() {
        let x = DualSVec64::<3>::new(
            0.7,
            Derivative::some(nalgebra::SVector::from([1.5, -2.0, 0.25])),
        );
        let full = x.sin() * x.clone();
        let s = x.seed();
        let via = <DualSVec64<3> as ModelNum>::chain(&(s.sin() * s), &x);
        assert_eq!(full.re, via.re);
        let (a, b) = (
            full.eps.unwrap_generic(Const::<3>, Const::<1>),
            via.eps.unwrap_generic(Const::<3>, Const::<1>),
        );
        for j in 0..3 {
            assert!((a[j] - b[j]).abs() <= 1e-15 * a[j].abs(), "{a} vs {b}");
        }
    }
}
