//! Why a parameter is undetermined or poorly determined, the parts every family shares: the
//! Jacobian's numerical null space, the correlated partners' words, and the data's geometry as
//! any family's parameters see it (the TT region, the span of θ_h). A family's own words live
//! in its folder (Marschner's glint: `families::marschner::fit::diagnostics`). Words for
//! fit.json's warnings; no numbers are changed here.

use std::f64::consts::PI;

use super::problem::FitData;
use crate::geometry::angles::wrap;

/// A standard error above this fraction of the typical range earns a "poorly determined" warning.
pub const POORLY_DETERMINED: f64 = 0.2;

/// A parameter whose unit column-scaled direction has at least this weight (squared component)
/// in the numerical null space of the Jacobian moves along a direction the data do not see:
/// 1e-6 is a component of 1e-3, far above the rounding of an SVD (~1e-15) yet catching partners
/// of an undetermined parameter that would otherwise get a meaningless tiny standard error.
pub const NULL_WEIGHT: f64 = 1e-6;

/// Per column of the Jacobian, its weight in the numerical null space (the solver's one
/// computation, shared with the covariance).
pub use crate::lm::null_space_weights;

/// The why-undetermined text's ending naming the strongly correlated partners (empty if none).
pub fn correlated_tail(partners: &[String]) -> String {
    if partners.is_empty() {
        String::new()
    } else {
        format!("; strongly correlated with {}", partners.join(", "))
    }
}

/// Samples with |φ| > 135° (where TT, and so absorption, shows): any family's
/// why-undetermined text for σ_a.
pub fn tt_region_samples(data: &FitData) -> usize {
    data.angles
        .iter()
        .filter(|a| wrap(a.phi_r - a.phi_i).abs() > 0.75 * PI)
        .count()
}

/// The span of θ_h = (θ_i + θ_r)/2 over the samples (radians): a longitudinal lobe's shape needs it.
pub fn theta_h_span(data: &FitData) -> f64 {
    let th = data.angles.iter().map(|a| 0.5 * (a.theta_i + a.theta_r));
    th.clone().fold(f64::NEG_INFINITY, f64::max) - th.fold(f64::INFINITY, f64::min)
}
