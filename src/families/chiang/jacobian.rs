//! Exact Jacobians of the Chiang `S` by forward-mode AD, one dual direction per chosen parameter.
//! Derivatives are per unit of [`ChiangParams`], i.e. per RADIAN for α (× π/180 for per degree).
//! The batch forms share the width integral per exit direction exactly as the values do.

use nalgebra::{Const, Dyn, U1};
use num_dual::{DualDVec64, DualNum, DualSVec64};

use super::evaluator::scattering_batch;
use super::{ChiangModel, ChiangParamName, ChiangParams};
use crate::geometry::Angles;

/// `params` as dual numbers, parameter `which[j]` seeded as direction j.
/// Panics if `which` names a channel that `params` does not have.
pub fn seeded<D: DualNum<f64>>(
    params: &ChiangParams<f64>,
    which: &[ChiangParamName],
    seed: impl Fn(f64, Option<usize>) -> D,
) -> ChiangParams<D> {
    let mut dual = params.map(|&v| seed(v, None));
    for (j, &name) in which.iter().enumerate() {
        if let ChiangParamName::SigmaA(c) = name {
            assert!(c < params.sigma_a.len(), "sigma_a[{c}] does not exist");
        }
        dual.set(name, seed(params.get(name), Some(j)));
    }
    dual
}

/// Values `v[k·n + c]` and Jacobian rows `jac[k·n + c][j] = ∂S/∂which[j]` for a batch
/// (heap-allocated duals: any parameter list).
pub fn batch_jacobian(
    params: &ChiangParams<f64>,
    model: &ChiangModel,
    angles: &[Angles],
    which: &[ChiangParamName],
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let k = which.len();
    let dual = seeded(params, which, |v, j| match j {
        Some(j) => DualDVec64::from_re(v).derivative(k, j),
        None => DualDVec64::from_re(v),
    });
    let mut out = vec![DualDVec64::from_re(0.0); angles.len() * params.sigma_a.len()];
    scattering_batch(&dual, model, angles, &mut out);
    split_duals(out, k)
}

/// Values and derivative rows of `k`-variable heap duals.
pub fn split_duals(out: Vec<DualDVec64>, k: usize) -> (Vec<f64>, Vec<Vec<f64>>) {
    let values = out.iter().map(|d| d.re).collect();
    let jac = out
        .into_iter()
        .map(|d| d.eps.unwrap_generic(Dyn(k), U1).iter().copied().collect())
        .collect();
    (values, jac)
}

/// The same for `N` parameters known at compile time (stack duals, the fast path for a fit):
/// `values` and `jac` have one entry per sample and channel.
pub fn batch_jacobian_static<const N: usize>(
    params: &ChiangParams<f64>,
    model: &ChiangModel,
    angles: &[Angles],
    which: &[ChiangParamName; N],
    values: &mut [f64],
    jac: &mut [[f64; N]],
) {
    let dual = seeded(params, which, |v, j| match j {
        Some(j) => DualSVec64::<N>::from_re(v).derivative(j),
        None => DualSVec64::<N>::from_re(v),
    });
    let mut out = vec![DualSVec64::<N>::from_re(0.0); values.len()];
    scattering_batch(&dual, model, angles, &mut out);
    for ((d, v), row) in out.iter().zip(values.iter_mut()).zip(jac.iter_mut()) {
        *v = d.re;
        row.copy_from_slice(d.eps.unwrap_generic(Const::<N>, U1).as_slice());
    }
}
