//! The parameter file (`PARAMS.json`) with MODEL.md's names, degrees in the file, radians in
//! [`Params`]; loading, defaults, unknown-key rejection and domain validation.

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::families::marschner::parameters::{NAMES, TABLE};
use crate::families::marschner::{ParamName, Params};

/// The parameter table's default of `name` (file units), for serde's `default = ...`.
fn table_default(name: ParamName) -> f64 {
    name.fact()
        .default
        .expect("the parameter file omits only parameters with a default in the table")
}
fn default_eta() -> f64 {
    table_default(ParamName::Eta)
}
fn default_eccentricity() -> f64 {
    table_default(ParamName::Eccentricity)
}
fn default_delta_eta_prime() -> f64 {
    table_default(ParamName::DeltaEtaPrime)
}
fn default_delta_h_m() -> f64 {
    table_default(ParamName::DeltaHM)
}

pub use crate::geometry::SigmaA;

/// Reading, parsing and validating a parameter file (`load`, `from_json_str`, `validate`).
pub use crate::json_file::ParameterFile;

/// The JSON parameter file, angles in degrees.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamFile {
    #[serde(default = "default_eta")]
    pub eta: f64,
    pub sigma_a: SigmaA,
    pub alpha_r_deg: f64,
    pub beta_r_deg: f64,
    pub k_g: f64,
    pub w_c_deg: f64,
    #[serde(default = "default_eccentricity")]
    pub eccentricity: f64,
    #[serde(default = "default_delta_eta_prime")]
    pub delta_eta_prime: f64,
    #[serde(default = "default_delta_h_m")]
    pub delta_h_m: f64,
}

impl crate::json_file::ParameterFile for ParamFile {
    fn hint() -> String {
        format!(
            "a parameter file is a JSON object with keys {}",
            TABLE.map(|s| s.name).join(", ")
        )
    }

    /// Check every value against the parameter table's domain (see [`Params::validate`]).
    fn validate(&self) -> Result<()> {
        self.sigma_a.require_channels()?;
        self.to_params().validate()
    }
}

impl ParamFile {
    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        self.sigma_a.n_channels()
    }

    /// True when `sigma_a` was a single number (eval then writes one column `s`).
    pub fn sigma_a_is_scalar(&self) -> bool {
        matches!(self.sigma_a, SigmaA::Scalar(_))
    }

    /// The value of `name` as written in the file (degrees for angles).
    fn file_value(&self, name: ParamName) -> f64 {
        match name {
            ParamName::Eta => self.eta,
            ParamName::SigmaA(c) => match &self.sigma_a {
                SigmaA::Scalar(s) => *s,
                SigmaA::PerChannel(v) => v[c],
            },
            ParamName::AlphaR => self.alpha_r_deg,
            ParamName::BetaR => self.beta_r_deg,
            ParamName::KG => self.k_g,
            ParamName::WC => self.w_c_deg,
            ParamName::Eccentricity => self.eccentricity,
            ParamName::DeltaEtaPrime => self.delta_eta_prime,
            ParamName::DeltaHM => self.delta_h_m,
        }
    }

    /// Warnings for values that look like radians in a degrees key (S would come out near zero
    /// everywhere with no other sign), naming the key.
    pub fn radians_in_degrees_keys(&self) -> Vec<String> {
        NAMES
            .iter()
            .map(|&name| (name.fact(), self.file_value(name)))
            .filter(|(spec, v)| spec.looks_like_radians(*v))
            .map(|(spec, v)| {
                format!(
                    "{} = {v} is read as degrees but looks like radians (typical {}..{} \
                     degrees; S may be near zero everywhere): if you meant {v} rad, write {:.4}",
                    spec.name,
                    spec.typical.0,
                    spec.typical.1,
                    v.to_degrees()
                )
            })
            .collect()
    }

    /// Model parameters, converted to model units by the parameter table (degrees to radians).
    pub fn to_params(&self) -> Params<f64> {
        Params::from_fn(self.n_channels(), |name| {
            name.fact().unit.to_model(self.file_value(name))
        })
    }

    /// The file form of `params` (radians to degrees); one channel becomes a scalar `sigma_a`.
    pub fn from_params(params: &Params<f64>) -> ParamFile {
        let file = |name: ParamName| params.get(name) * name.fact().unit.file_factor();
        let sigma_a = if params.sigma_a.len() == 1 {
            SigmaA::Scalar(params.sigma_a[0])
        } else {
            SigmaA::PerChannel(params.sigma_a.clone())
        };
        ParamFile {
            eta: file(ParamName::Eta),
            sigma_a,
            alpha_r_deg: file(ParamName::AlphaR),
            beta_r_deg: file(ParamName::BetaR),
            k_g: file(ParamName::KG),
            w_c_deg: file(ParamName::WC),
            eccentricity: file(ParamName::Eccentricity),
            delta_eta_prime: file(ParamName::DeltaEtaPrime),
            delta_h_m: file(ParamName::DeltaHM),
        }
    }
}
