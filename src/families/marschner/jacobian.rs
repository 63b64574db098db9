//! Exact Jacobians of S by forward-mode AD, one dual direction per chosen parameter.
//!
//! Derivatives are per unit of [`Params`], i.e. per RADIAN for α_R, β_R and w_c (multiply by
//! π/180 for per degree). Two entry points:
//! - [`scattering_jacobian`]: any parameter list, `DualDVec64` (heap per call; simple).
//! - [`StaticJacobian`]: `N` parameters fixed at compile time, `DualSVec64<N>`; build it once per
//!   parameter vector and call [`StaticJacobian::eval`] per sample with no allocation (fast path
//!   for a fit).

use nalgebra::{allocator::Allocator, Const, DefaultAllocator, Dim, Dyn, U1};
use num_dual::{Derivative, DualDVec64, DualNum, DualSVec64, DualVec64};

use super::{scattering, Angles, ModelConfig, ParamName, Params};

/// `params` as dual numbers with `dim` derivative directions, parameter `which[j]` seeded as
/// direction j (the one seeding of the crate: this module's Jacobians and the fit's gradients).
/// Panics if `which` names a channel `SigmaA(c)` that `params` does not have.
pub(crate) fn seeded<D: Dim>(
    params: &Params<f64>,
    which: &[ParamName],
    dim: D,
) -> Params<DualVec64<D>>
where
    DefaultAllocator: Allocator<D>,
    DualVec64<D>: DualNum<f64>,
{
    for w in which {
        if let ParamName::SigmaA(c) = w {
            assert!(*c < params.sigma_a.len(), "sigma_a[{c}] does not exist");
        }
    }
    let mut dual = params.map(|&v| DualVec64::from_re(v));
    for (j, &name) in which.iter().enumerate() {
        let direction = Derivative::derivative_generic(dim, U1, j);
        dual.set(name, DualVec64::new(params.get(name), direction));
    }
    dual
}

/// Jacobian of S for `N` parameters known at compile time, reusable across samples.
#[derive(Debug, Clone)]
pub struct StaticJacobian<const N: usize> {
    params: Params<DualSVec64<N>>,
    out: Vec<DualSVec64<N>>,
}

impl<const N: usize> StaticJacobian<N> {
    /// Seed `params` with one direction per entry of `which`.
    /// Panics if `which` names a channel `SigmaA(c)` that `params` does not have.
    pub fn new(params: &Params<f64>, which: &[ParamName; N]) -> Self {
        let dual = seeded(params, which, Const::<N>);
        let out = vec![DualSVec64::<N>::from_re(0.0); params.sigma_a.len()];
        StaticJacobian { params: dual, out }
    }

    /// S per channel into `values` and `jac[c][j] = ∂S_c/∂which[j]`; both have one entry per
    /// channel (panics otherwise).
    pub fn eval(
        &mut self,
        config: &ModelConfig,
        angles: &Angles,
        values: &mut [f64],
        jac: &mut [[f64; N]],
    ) {
        scattering(&self.params, config, angles, &mut self.out);
        for ((d, v), j) in self.out.iter().zip(values.iter_mut()).zip(jac.iter_mut()) {
            *v = d.re;
            let eps = d.eps.unwrap_generic(Const::<N>, U1);
            j.copy_from_slice(eps.as_slice());
        }
    }
}

/// S per channel and `jac[c][j] = ∂S_c/∂which[j]` (per radian for angular parameters).
/// Panics if `which` names a channel `SigmaA(c)` that `params` does not have.
pub fn scattering_jacobian(
    params: &Params<f64>,
    config: &ModelConfig,
    angles: &Angles,
    which: &[ParamName],
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let n = which.len();
    let dual = seeded(params, which, Dyn(n));
    let mut out = vec![DualDVec64::from_re(0.0); params.sigma_a.len()];
    scattering(&dual, config, angles, &mut out);
    let values = out.iter().map(|d| d.re).collect();
    let jac = out
        .into_iter()
        .map(|d| d.eps.unwrap_generic(Dyn(n), U1).iter().copied().collect())
        .collect();
    (values, jac)
}
