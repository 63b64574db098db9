//! Why a parameter is undetermined or poorly determined: the Jacobian's numerical null space,
//! and the data's geometry as the parameter sees it (samples near the glint, the spread of
//! θ_h and of cos 2φ_h), and which samples sit near the glints (evidence for the verdict's
//! suggestions). Words for fit.json's warnings; no numbers are changed here.

use std::f64::consts::PI;

use super::problem::FitData;
use crate::families::marschner::azimuthal::caustic_position;
use crate::families::marschner::bravais::bravais_indices;
use crate::families::marschner::{ParamName, Params, RootMode};
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

/// Per sample: within 2 w_c of the glint azimuth φ_c(θ_d) the model places (its caustic under
/// the fit's root mode, index η). Where the glint's shape, and so the root map, matters most.
pub fn near_glint(data: &FitData, mode: RootMode, eta: f64, w_c: f64) -> Vec<bool> {
    data.angles
        .iter()
        .map(|a| {
            let td = 0.5 * (a.theta_r - a.theta_i);
            let (s, c) = td.sin_cos();
            let eta_p = bravais_indices(&eta, s, c).eta_p;
            if !eta_p.is_finite() {
                return false;
            }
            let Some((phi_c, _)) = caustic_position(mode, eta_p) else {
                return false;
            };
            let phi = wrap(a.phi_r - a.phi_i).abs();
            (phi - phi_c).abs() < 2.0 * w_c
        })
        .collect()
}

/// Samples near the glint ([`near_glint`]) and the span of |φ| they cover.
fn samples_near_glint(data: &FitData, mode: RootMode, eta: f64, w_c: f64) -> (usize, f64) {
    let near: Vec<f64> = near_glint(data, mode, eta, w_c)
        .iter()
        .zip(&data.angles)
        .filter(|(n, _)| **n)
        .map(|(_, a)| wrap(a.phi_r - a.phi_i).abs())
        .collect();
    let span = near.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - near.iter().copied().fold(f64::INFINITY, f64::min);
    (near.len(), if near.is_empty() { 0.0 } else { span })
}

/// The why-undetermined text's ending naming the strongly correlated partners (empty if none).
pub fn correlated_tail(partners: &[String]) -> String {
    if partners.is_empty() {
        String::new()
    } else {
        format!("; strongly correlated with {}", partners.join(", "))
    }
}

/// Why the data cannot determine `p` (geometry first, else the correlated partners).
pub fn why_undetermined(
    p: ParamName,
    data: &FitData,
    mode: RootMode,
    params: &Params<f64>,
    partners: &[String],
) -> String {
    let tail = correlated_tail(partners);
    match p {
        ParamName::KG | ParamName::WC => {
            let (n, span) = samples_near_glint(data, mode, params.eta, params.w_c);
            if n == 0 {
                format!("no sample near the glint (|phi - phi_c| < 2 w_c){tail}")
            } else if span < params.w_c {
                format!(
                    "the {n} sample(s) near the glint span only {:.1} deg of |phi|: its width and height trade off{tail}",
                    span.to_degrees()
                )
            } else {
                format!("{n} sample(s) near the glint (|phi - phi_c| < 2 w_c){tail}")
            }
        }
        ParamName::Eccentricity => {
            let spread = crate::families::marschner::eccentricity::cos_2phi_h_spread(&data.angles);
            format!("the samples span cos(2 phi_h) by only {spread:.3}: eccentricity acts through phi_h{tail}")
        }
        ParamName::SigmaA(_) => {
            let n = tt_region_samples(data);
            format!(
                "absorption shows in TT/TRT; {n} sample(s) have |phi| > 135 deg (TT region){tail}"
            )
        }
        ParamName::AlphaR | ParamName::BetaR => {
            let spread = theta_h_span(data);
            format!(
                "the samples span theta_h by {:.1} deg only: the longitudinal lobe shape needs a scan across it{tail}",
                spread.to_degrees()
            )
        }
        _ => format!("the data do not constrain it{tail}"),
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
