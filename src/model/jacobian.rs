//! Exact Jacobians of S by forward-mode AD, one dual direction per chosen parameter.
//!
//! Derivatives are per unit of [`Params`], i.e. per RADIAN for α_R, β_R and w_c (multiply by
//! π/180 for per degree). Two entry points:
//! - [`scattering_jacobian`]: any parameter list, `DualDVec64` (heap per call; simple).
//! - [`StaticJacobian`]: `N` parameters fixed at compile time, `DualSVec64<N>`; build it once per
//!   parameter vector and call [`StaticJacobian::eval`] per sample with no allocation (fast path
//!   for a fit).

use nalgebra::{Const, Dyn, U1};
use num_dual::{DualDVec64, DualNum, DualSVec64};

use super::{scattering, Angles, ModelConfig, ParamName, Params};

/// `params` as dual numbers, parameter `which[j]` seeded as direction j.
fn seeded<D: DualNum<f64>>(
    params: &Params<f64>,
    which: &[ParamName],
    seed: impl Fn(f64, Option<usize>) -> D,
) -> Params<D> {
    for w in which {
        if let ParamName::SigmaA(c) = w {
            assert!(*c < params.sigma_a.len(), "sigma_a[{c}] does not exist");
        }
    }
    let mut dual = params.map(|&v| seed(v, None));
    for (j, &name) in which.iter().enumerate() {
        dual.set(name, seed(params.get(name), Some(j)));
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
        let dual = seeded(params, which, |v, j| match j {
            Some(j) => DualSVec64::<N>::from_re(v).derivative(j),
            None => DualSVec64::<N>::from_re(v),
        });
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
    let dual = seeded(params, which, |v, j| match j {
        Some(j) => DualDVec64::from_re(v).derivative(n, j),
        None => DualDVec64::from_re(v),
    });
    let mut out = vec![DualDVec64::from_re(0.0); params.sigma_a.len()];
    scattering(&dual, config, angles, &mut out);
    let values = out.iter().map(|d| d.re).collect();
    let jac = out
        .into_iter()
        .map(|d| d.eps.unwrap_generic(Dyn(n), U1).iter().copied().collect())
        .collect();
    (values, jac)
}
