//! `truth.json` ([`Truth`]): the exact inputs of a synthetic dataset (`hairfit synth`'s
//! `FILE.truth.json` sidecar, `hairfit demo`'s `truth.json`), everything needed to check a fit.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::fit_json::ScaleEntry;
use crate::error::Result;
use crate::families::effects::ModelConfig;
use crate::families::{FamilyParams, FamilyRecord};
use crate::geometry::Measurement;

/// The sidecar `FILE.truth.json`: the exact inputs of a synthetic dataset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    pub hairfit_version: String,
    /// The exact parameters (a parameter file of the model's family: degrees, MODEL.md's or
    /// CHIANG.md's names).
    pub params: FamilyParams,
    pub channels: Vec<String>,
    /// Measured value = scale × S (× cos θ_i for `radiance`, see `measurement`), per channel.
    pub scale: Vec<ScaleEntry>,
    /// `s` (values are scale × S) or `radiance` (scale × S × cos θ_i); files written before
    /// the option existed hold S, hence the default.
    #[serde(default)]
    pub measurement: Measurement,
    /// Canonical rig spec with every option spelled out.
    pub rig: String,
    /// Canonical noise spec.
    pub noise: String,
    /// True when the CSV has `sigma` columns (photon, relative or floor noise).
    pub sigma_written: bool,
    pub seed: u64,
    pub rng: String,
    pub model: ModelConfig,
    pub n_samples: usize,
    /// 0-based sample indices multiplied by an outlier factor (empty without outlier noise).
    pub outliers: Vec<usize>,
    /// Choices made on the user's behalf (e.g. a scalar sigma_a replicated over channels).
    pub notes: Vec<String>,
    /// The command that made the files (absent when made through the library).
    pub command_line: Option<String>,
    /// What the family that made the data records of its configuration beside `model`, when it
    /// records anything ([`crate::families::OwnTypes::Record`]; Chiang's is the file's key).
    #[serde(rename = "chiang", default, skip_serializing_if = "Option::is_none")]
    pub family_record: Option<FamilyRecord>,
    /// Data made by a table family: the terms that were on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub terms: Option<Vec<String>>,
}

impl Truth {
    /// Read a truth file.
    pub fn load(path: &Path) -> Result<Truth> {
        super::read_json(path, "not a hairfit truth file")
    }

    /// Write a truth file atomically (pretty-printed).
    pub fn save(&self, path: &Path) -> Result<()> {
        super::write_json(path, self)
    }
}
