//! Exact Jacobians of S by forward-mode AD (`DualDVec64`, one dual direction per chosen parameter).
//!
//! Derivatives are per unit of [`Params`], i.e. per RADIAN for α_R, β_R and w_c (multiply by
//! π/180 for per degree). For a fixed, small parameter count `scattering` with `DualSVec64<N>`
//! avoids the heap and is faster; this helper trades that for a simple interface.

use nalgebra::{Dyn, U1};
use num_dual::DualDVec64;

use super::{scattering, Angles, ModelConfig, ParamName, Params};

/// The value of one parameter in `params` (radians for angles).
pub fn param_value(params: &Params<f64>, name: ParamName) -> f64 {
    match name {
        ParamName::Eta => params.eta,
        ParamName::SigmaA(c) => params.sigma_a[c],
        ParamName::AlphaR => params.alpha_r,
        ParamName::BetaR => params.beta_r,
        ParamName::KG => params.k_g,
        ParamName::WC => params.w_c,
        ParamName::Eccentricity => params.eccentricity,
        ParamName::DeltaEtaPrime => params.delta_eta_prime,
        ParamName::DeltaHM => params.delta_h_m,
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
    let seed = |name: ParamName, v: f64| -> DualDVec64 {
        match which.iter().position(|w| *w == name) {
            Some(j) => DualDVec64::from_re(v).derivative(n, j),
            None => DualDVec64::from_re(v),
        }
    };
    let dual = Params {
        eta: seed(ParamName::Eta, params.eta),
        sigma_a: params
            .sigma_a
            .iter()
            .enumerate()
            .map(|(c, &s)| seed(ParamName::SigmaA(c), s))
            .collect(),
        alpha_r: seed(ParamName::AlphaR, params.alpha_r),
        beta_r: seed(ParamName::BetaR, params.beta_r),
        k_g: seed(ParamName::KG, params.k_g),
        w_c: seed(ParamName::WC, params.w_c),
        eccentricity: seed(ParamName::Eccentricity, params.eccentricity),
        delta_eta_prime: seed(ParamName::DeltaEtaPrime, params.delta_eta_prime),
        delta_h_m: seed(ParamName::DeltaHM, params.delta_h_m),
    };
    for w in which {
        if let ParamName::SigmaA(c) = w {
            assert!(*c < params.sigma_a.len(), "sigma_a[{c}] does not exist");
        }
    }
    let mut out = vec![DualDVec64::from_re(0.0); params.sigma_a.len()];
    scattering(&dual, config, angles, &mut out);
    let values = out.iter().map(|d| d.re).collect();
    let jac = out
        .into_iter()
        .map(|d| d.eps.unwrap_generic(Dyn(n), U1).iter().copied().collect())
        .collect();
    (values, jac)
}
