//! `timing.json`: the wall-clock times of one fit run. They change on every run, so they live
//! apart from `fit.json` (which stays byte-identical for the same data, options and seed) and
//! are not committed (`.gitignore`).

use serde::{Deserialize, Serialize};

use super::nan_if_missing;

/// The file name inside a fit's directory.
pub const TIMING_FILE: &str = "timing.json";

/// Wall time of one solver stage (same `stage` names as `fit.json`'s `trace`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageTiming {
    pub stage: String,
    #[serde(deserialize_with = "nan_if_missing")]
    pub wall_s: f64,
}

/// The whole of `timing.json`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Timing {
    /// The whole fit, from its start to the outcome being ready.
    #[serde(deserialize_with = "nan_if_missing")]
    pub wall_time_s: f64,
    pub stages: Vec<StageTiming>,
    /// Reading and checking the data file (`hairfit fit`; absent when the data came otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load_s: Option<f64>,
    /// Writing the fit's files and drawing its report, after the fit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outputs_s: Option<f64>,
}

impl Timing {
    /// The wall time of `stage` (NaN if it was not run).
    pub fn stage(&self, stage: &str) -> f64 {
        self.stages
            .iter()
            .find(|s| s.stage == stage)
            .map_or(f64::NAN, |s| s.wall_s)
    }
}
