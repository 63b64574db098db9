//! The parameter file (`PARAMS.json`) with MODEL.md's names, degrees in the file, radians in
//! [`Params`]; loading, defaults, unknown-key rejection and domain validation.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::model::Params;

/// MODEL.md default for η.
pub const DEFAULT_ETA: f64 = 1.55;
/// MODEL.md default for the eccentricity a.
pub const DEFAULT_ECCENTRICITY: f64 = 1.0;
/// MODEL.md default for Δη'.
pub const DEFAULT_DELTA_ETA_PRIME: f64 = 0.3;
/// MODEL.md default for Δh_M.
pub const DEFAULT_DELTA_H_M: f64 = 0.5;

fn default_eta() -> f64 {
    DEFAULT_ETA
}
fn default_eccentricity() -> f64 {
    DEFAULT_ECCENTRICITY
}
fn default_delta_eta_prime() -> f64 {
    DEFAULT_DELTA_ETA_PRIME
}
fn default_delta_h_m() -> f64 {
    DEFAULT_DELTA_H_M
}

/// `sigma_a` as written: one number (one channel) or an array (one per channel).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum SigmaA {
    Scalar(f64),
    PerChannel(Vec<f64>),
}

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

impl ParamFile {
    /// Read and validate a parameter file.
    pub fn load(path: impl AsRef<Path>) -> Result<ParamFile> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::from_json_str(&text, path)
    }

    /// Parse and validate JSON text; `path` only names the source in error messages.
    pub fn from_json_str(s: &str, path: impl AsRef<Path>) -> Result<ParamFile> {
        let file: ParamFile = serde_json::from_str(s).map_err(|e| {
            Error::input(
                path.as_ref(),
                e.line() as u64,
                e.column() as u64,
                format!(
                    "{e}; a parameter file is a JSON object with keys eta, sigma_a, alpha_r_deg, \
                     beta_r_deg, k_g, w_c_deg, eccentricity, delta_eta_prime, delta_h_m"
                ),
            )
        })?;
        file.validate()?;
        Ok(file)
    }

    /// Check MODEL.md's domain (see [`Params::validate`]).
    pub fn validate(&self) -> Result<()> {
        if let SigmaA::PerChannel(v) = &self.sigma_a {
            if v.is_empty() {
                return Err(Error::Parameter {
                    name: "sigma_a".into(),
                    value: f64::NAN,
                    message: "the array is empty: give one value per colour channel".into(),
                });
            }
        }
        self.to_params().validate()
    }

    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        match &self.sigma_a {
            SigmaA::Scalar(_) => 1,
            SigmaA::PerChannel(v) => v.len(),
        }
    }

    /// True when `sigma_a` was a single number (eval then writes one column `s`).
    pub fn sigma_a_is_scalar(&self) -> bool {
        matches!(self.sigma_a, SigmaA::Scalar(_))
    }

    /// Model parameters, degrees converted to radians.
    pub fn to_params(&self) -> Params<f64> {
        let sigma_a = match &self.sigma_a {
            SigmaA::Scalar(s) => vec![*s],
            SigmaA::PerChannel(v) => v.clone(),
        };
        Params {
            eta: self.eta,
            sigma_a,
            alpha_r: self.alpha_r_deg.to_radians(),
            beta_r: self.beta_r_deg.to_radians(),
            k_g: self.k_g,
            w_c: self.w_c_deg.to_radians(),
            eccentricity: self.eccentricity,
            delta_eta_prime: self.delta_eta_prime,
            delta_h_m: self.delta_h_m,
        }
    }

    /// The file form of `params` (radians to degrees); one channel becomes a scalar `sigma_a`.
    pub fn from_params(params: &Params<f64>) -> ParamFile {
        let sigma_a = if params.sigma_a.len() == 1 {
            SigmaA::Scalar(params.sigma_a[0])
        } else {
            SigmaA::PerChannel(params.sigma_a.clone())
        };
        ParamFile {
            eta: params.eta,
            sigma_a,
            alpha_r_deg: params.alpha_r.to_degrees(),
            beta_r_deg: params.beta_r.to_degrees(),
            k_g: params.k_g,
            w_c_deg: params.w_c.to_degrees(),
            eccentricity: params.eccentricity,
            delta_eta_prime: params.delta_eta_prime,
            delta_h_m: params.delta_h_m,
        }
    }
}
