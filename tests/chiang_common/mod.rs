//! Shared helpers of the Chiang tests: CHIANG.md's parameter sets and a one-sample evaluator.
#![allow(dead_code)]

use hairfit::chiang::{scattering, ChiangEffects, ChiangModel, ChiangParams};
use hairfit::model::Angles;

/// CHIANG.md known-values set A: eta 1.55, sigma_a 0.4, beta_m 0.3, beta_n 0.3, alpha_deg 2.
pub fn set_a() -> ChiangParams<f64> {
    params(1.55, 0.4, 0.3, 0.3, 2.0)
}

/// CHIANG.md known-values set B: eta 1.55, sigma_a 1.2, beta_m 0.1, beta_n 0.5, alpha_deg −3.
pub fn set_b() -> ChiangParams<f64> {
    params(1.55, 1.2, 0.1, 0.5, -3.0)
}

/// One-channel parameters, α in degrees.
pub fn params(
    eta: f64,
    sigma_a: f64,
    beta_m: f64,
    beta_n: f64,
    alpha_deg: f64,
) -> ChiangParams<f64> {
    ChiangParams {
        eta,
        sigma_a: vec![sigma_a],
        beta_m,
        beta_n,
        alpha: alpha_deg.to_radians(),
    }
}

/// All terms on, `nodes` width nodes.
pub fn model(nodes: usize) -> ChiangModel {
    ChiangModel::new(ChiangEffects::default(), nodes).unwrap()
}

/// S of channel 0 at (θ_i, φ_i, θ_r, φ_r) in degrees.
pub fn s(params: &ChiangParams<f64>, model: &ChiangModel, deg: [f64; 4]) -> f64 {
    let mut out = vec![0.0; params.sigma_a.len()];
    scattering(
        params,
        model,
        &Angles::from_degrees(deg[0], deg[1], deg[2], deg[3]),
        &mut out,
    );
    out[0]
}
