//! Shared helpers of the Chiang tests: CHIANG.md's parameter sets and a one-sample evaluator.
#![allow(dead_code)]

use hairfit::families::chiang::{scattering, ChiangEffects, ChiangModel, ChiangParams};
use hairfit::geometry::Angles;

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

/// S of channel 0 at (θ_i, φ_i, θ_r, φ_r) in degrees from the composite rule (broken at the
/// kinks) at `density` nodes per π, the residual over `residual_nodes` plain nodes: a reference
/// when both are large.
pub fn composite_s(
    params: &ChiangParams<f64>,
    density: usize,
    residual_nodes: usize,
    deg: [f64; 4],
) -> f64 {
    use hairfit::families::chiang::{scattering_from_table, AzimuthalTable, WidthRule, WidthSet};
    let a = Angles::from_degrees(deg[0], deg[1], deg[2], deg[3]);
    let phi = hairfit::geometry::angles::wrap(a.phi_r - a.phi_i).abs();
    let effects = ChiangEffects::default();
    let (mut breaks, mut nodes) = (Vec::new(), Vec::new());
    hairfit::families::chiang::width::split_nodes(
        &effects,
        density,
        params.eta,
        a.theta_r,
        phi,
        &mut breaks,
        &mut nodes,
    );
    let residual = WidthRule::cached(residual_nodes).unwrap();
    let mut table = AzimuthalTable::zeros(params.sigma_a.len());
    let set = WidthSet {
        lobes: &nodes,
        residual: &residual.nodes,
    };
    table.fill(params, &effects, set, a.theta_r, phi);
    let mut out = vec![0.0; params.sigma_a.len()];
    scattering_from_table(params, &effects, &table, a.theta_i, a.theta_r, &mut out);
    out[0]
}
