//! The Chiang parameter file: CHIANG.md's JSON names (`eta`, `sigma_a` as a number or one value
//! per channel, `beta_m`, `beta_n`, `alpha_deg`), an optional `"model": "chiang"` tag, unknown
//! keys rejected, domains checked against [`super::PARAMETERS`].

use serde::{Deserialize, Serialize};

use super::ChiangParams;
use crate::error::{Error, Result};
use crate::geometry::SigmaA;
pub use crate::json_file::ParameterFile;

/// The model tag a Chiang file may carry.
pub const MODEL_TAG: &str = "chiang";

fn default_eta() -> f64 {
    super::PARAMETERS[0].default.expect("eta has a default")
}

/// The JSON parameter file of the Chiang model, α in degrees.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChiangParamFile {
    /// `"chiang"` when present (a fit writes it); any other value is an error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    #[serde(default = "default_eta")]
    pub eta: f64,
    pub sigma_a: SigmaA,
    pub beta_m: f64,
    pub beta_n: f64,
    pub alpha_deg: f64,
}

impl crate::json_file::ParameterFile for ChiangParamFile {
    fn hint() -> String {
        "a Chiang parameter file is a JSON object with keys model (optional, \"chiang\"), eta \
         (optional, 1.55), sigma_a (number or array), beta_m, beta_n, alpha_deg"
            .into()
    }

    /// Check the model tag, a non-empty `sigma_a` and every domain.
    fn validate(&self) -> Result<()> {
        if let Some(tag) = &self.model {
            if tag != MODEL_TAG {
                return Err(Error::Parameter {
                    name: "model".into(),
                    value: f64::NAN,
                    message: format!(
                        "this file is tagged \"{tag}\" but is read as a Chiang parameter file: \
                         use \"model\": \"{MODEL_TAG}\" or drop the key"
                    ),
                });
            }
        }
        self.sigma_a.require_channels()?;
        self.to_params().validate()
    }
}

impl ChiangParamFile {
    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        self.sigma_a.n_channels()
    }

    /// Model parameters, α converted to radians.
    pub fn to_params(&self) -> ChiangParams<f64> {
        ChiangParams {
            eta: self.eta,
            sigma_a: match &self.sigma_a {
                SigmaA::Scalar(s) => vec![*s],
                SigmaA::PerChannel(v) => v.clone(),
            },
            beta_m: self.beta_m,
            beta_n: self.beta_n,
            alpha: self.alpha_deg.to_radians(),
        }
    }

    /// The file form of `params`, tagged `"model": "chiang"`; one channel becomes a scalar.
    pub fn from_params(params: &ChiangParams<f64>) -> ChiangParamFile {
        ChiangParamFile {
            model: Some(MODEL_TAG.into()),
            eta: params.eta,
            sigma_a: if params.sigma_a.len() == 1 {
                SigmaA::Scalar(params.sigma_a[0])
            } else {
                SigmaA::PerChannel(params.sigma_a.clone())
            },
            beta_m: params.beta_m,
            beta_n: params.beta_n,
            alpha_deg: params.alpha.to_degrees(),
        }
    }
}
