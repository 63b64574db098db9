//! Marschner's words for a parameter the data do not determine: which samples sit near the
//! glint the model places (evidence for the verdict's suggestions), the spread of cos 2φ_h, and
//! the shared geometry of `crate::fit::diagnostics`.

use crate::families::marschner::azimuthal::caustic_position;
use crate::families::marschner::bravais::bravais_indices;
use crate::families::marschner::{ParamName, Params, RootMode};
use crate::fit::diagnostics::{correlated_tail, theta_h_span, tt_region_samples};
use crate::fit::problem::FitData;
use crate::geometry::angles::wrap;

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
