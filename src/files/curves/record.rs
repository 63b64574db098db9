//! One row of `curves.csv` as a value ([`CurveRow`], through serde the reference definition of
//! every cell's text), the numbers of a row ([`CurveValues`]), the header, and `--curves`
//! ([`CurvesMode`]).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::files::nan_if_missing;

/// One row of `curves.csv`: one sample in one channel, angles in degrees; `fit*` include the
/// fitted scale (and the measurement's factor); `residual` is normalised in the fit's space;
/// `weight` the final robust weight. Non-finite numbers are empty cells.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CurveRow {
    pub sample: u64,
    /// Line of the sample in the data file.
    pub line: u64,
    pub channel: String,
    #[serde(serialize_with = "shortest")]
    pub theta_i: f64,
    #[serde(serialize_with = "shortest")]
    pub phi_i: f64,
    #[serde(serialize_with = "shortest")]
    pub theta_r: f64,
    #[serde(serialize_with = "shortest")]
    pub phi_r: f64,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "exponent")]
    pub data: f64,
    /// Empty when unknown.
    #[serde(serialize_with = "exponent_opt")]
    pub sigma: Option<f64>,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "exponent")]
    pub fit: f64,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "exponent")]
    pub fit_r: f64,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "exponent")]
    pub fit_tt: f64,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "exponent")]
    pub fit_trt: f64,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "exponent")]
    pub residual: f64,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "exponent")]
    pub weight: f64,
}

impl CurveRow {
    /// The robust loss really discounted this value (weight below [`DOWN_WEIGHT`]): the one
    /// definition of an "outlier" that the fit counts and the report marks.
    pub fn down_weighted(&self) -> bool {
        self.weight < DOWN_WEIGHT
    }

    /// The four angles in degrees, `[θ_i, φ_i, θ_r, φ_r]`.
    pub fn angles_deg(&self) -> [f64; 4] {
        [self.theta_i, self.phi_i, self.theta_r, self.phi_r]
    }
}

/// A value whose robust-loss weight ρ′ is below this counts as down-weighted. Every robust loss
/// gives weights just below 1 to ordinary residuals (Cauchy: 0.8 at one loss scale's fifth); below
/// one half the loss has removed most of the value's pull (Cauchy: |r| > C, Huber: |r| > 2C).
pub const DOWN_WEIGHT: f64 = 0.5;

/// The header `curves.csv` has, in this order (the fields of [`CurveRow`]; a test checks).
pub const CURVES_HEADER: [&str; 15] = [
    "sample", "line", "channel", "theta_i", "phi_i", "theta_r", "phi_r", "data", "sigma", "fit",
    "fit_r", "fit_tt", "fit_trt", "residual", "weight",
];

/// Angles: Rust's shortest round-trip decimal (`-170`, `-29.999999999999996`).
fn shortest<S: serde::Serializer>(v: &f64, s: S) -> std::result::Result<S::Ok, S::Error> {
    if v.is_finite() {
        s.serialize_str(&v.to_string())
    } else {
        s.serialize_str("")
    }
}

/// Values: shortest round-trip digits in exponent form (`2.43e-7`, `1e0`); empty if not finite.
fn exponent<S: serde::Serializer>(v: &f64, s: S) -> std::result::Result<S::Ok, S::Error> {
    if v.is_finite() {
        s.serialize_str(&format!("{v:e}"))
    } else {
        s.serialize_str("")
    }
}

fn exponent_opt<S: serde::Serializer>(
    v: &Option<f64>,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    exponent(&v.unwrap_or(f64::NAN), s)
}

/// How much of the curves a fit writes (`--curves`, recorded in fit.json's options).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CurvesMode {
    /// Every sample and channel.
    #[default]
    Full,
    /// The samples the report draws, an even spread of the rest and every sample with a
    /// down-weighted value (all of its channels), at most a few thousand samples plus those.
    Summary,
    /// No curves.csv at all.
    None,
}

impl std::fmt::Display for CurvesMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            CurvesMode::Full => "full",
            CurvesMode::Summary => "summary",
            CurvesMode::None => "none",
        })
    }
}

impl std::str::FromStr for CurvesMode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "full" => Ok(CurvesMode::Full),
            "summary" => Ok(CurvesMode::Summary),
            "none" => Ok(CurvesMode::None),
            other => Err(Error::Other(format!(
                "unknown curves mode `{other}`: use full, summary or none"
            ))),
        }
    }
}

/// The numbers of one row of [`Curves`] (`sigma` NaN when unknown, an empty cell).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveValues {
    pub data: f64,
    pub sigma: f64,
    pub fit: f64,
    pub fit_r: f64,
    pub fit_tt: f64,
    pub fit_trt: f64,
    pub residual: f64,
    pub weight: f64,
}

impl CurveValues {
    /// Every number missing (empty cells), until a row is filled in.
    pub const MISSING: CurveValues = CurveValues {
        data: f64::NAN,
        sigma: f64::NAN,
        fit: f64::NAN,
        fit_r: f64::NAN,
        fit_tt: f64::NAN,
        fit_trt: f64::NAN,
        residual: f64::NAN,
        weight: f64::NAN,
    };
}
