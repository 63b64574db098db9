//! The Marschner demo's true parameters (`hairfit demo`, the cost ledger, the tests' synthetic
//! data): mid-range MODEL.md values, brown-ish hair.

use super::params::ParamFile;
use super::{MarschnerFamily, Params};
use crate::families::{FamilyParams, OwnFamily};

/// The demo's true parameters (mid-range MODEL.md values, brown-ish hair).
pub fn demo_truth() -> Params<f64> {
    Params {
        eta: 1.55,
        sigma_a: vec![0.25, 0.45, 0.8],
        alpha_r: (-7f64).to_radians(),
        beta_r: 7.5f64.to_radians(),
        k_g: 2.0,
        w_c: 15f64.to_radians(),
        eccentricity: 0.9,
        delta_eta_prime: 0.3,
        delta_h_m: 0.5,
    }
}

impl OwnFamily for MarschnerFamily {
    fn demo_truth(&self) -> FamilyParams {
        ParamFile::from_params(&demo_truth()).into()
    }
}
