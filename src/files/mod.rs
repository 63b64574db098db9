//! Every on-disk format hairfit writes and reads, one Serialize + Deserialize type each, so a
//! writer and its reader can never disagree: `fit.json` ([`FitJson`]), `curves.csv`
//! ([`CurveRow`]), `timing.json` ([`Timing`]), `truth.json` ([`Truth`]), the loader's report
//! ([`LoadReport`]); `params.json` is [`crate::families::marschner::params::ParamFile`]. Readers name file, line and
//! column on bad input; writers write atomically. This module sits below `fit` and `report`
//! (both use it) and above the model families whose parameters its records hold; the fit's
//! settings and test statistics it records are defined here (`settings`, `statistics`).

pub mod curves;
pub mod decimal;
pub mod fit_json;
pub mod load_report;
pub mod settings;
pub mod statistics;
pub mod timing;
pub mod truth;

use std::path::Path;

use serde::Deserialize;

use crate::error::{Error, Result};

pub use crate::json_file::{parse_json_object, read_json, write_json, ParameterFile};

pub use curves::{
    read_curves_csv, write_curves_csv, CurveRow, CurveValues, Curves, CurvesMode, CURVES_HEADER,
    DOWN_WEIGHT,
};
pub use fit_json::{
    ChannelCorrelation, ChannelResiduals, Correlation, DataInfo, DownWeighted, EffectsSource,
    FitJson, FitStatus, Floored, GofThresholds, GoodnessOfFit, Interval, OptionsRecord,
    ParamStatus, ParameterEntry, ProfileMethod, ResidualSummary, ScaleEntry, ScaleMethod,
    Suggestion, TraceStage, Verdict,
};
pub use load_report::{LineTally, LoadReport, RejectReason, FIRST_LINES};
pub use timing::{StageTiming, Timing};
pub use truth::Truth;

/// Write the fit's files into `dir` (each atomically): `fit.json`, `params.json` (the fitted
/// parameters as a parameter file), `curves.csv` (unless `curves` is `None`: `--curves none`),
/// and the run's wall-clock `timing.json` (kept apart so rerunning a fit leaves the other
/// files byte-identical).
pub fn write_fit_dir(
    dir: &Path,
    fit: &FitJson,
    curves: Option<&Curves>,
    timing: &Timing,
) -> Result<()> {
    write_fit_files(dir, fit, curves)?;
    write_timing(dir, timing)
}

/// [`write_fit_dir`] without `timing.json`, for a caller that writes it once its own outputs'
/// time is known (a file written and replaced at once costs its first write-back on ext4).
pub fn write_fit_files(dir: &Path, fit: &FitJson, curves: Option<&Curves>) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    write_json(&dir.join("fit.json"), fit)?;
    write_json(&dir.join("params.json"), &fit.params)?;
    if let Some(curves) = curves {
        curves.write_csv(&dir.join("curves.csv"), None)?;
    }
    Ok(())
}

/// Write `timing.json` into `dir`.
pub fn write_timing(dir: &Path, timing: &Timing) -> Result<()> {
    write_json(&dir.join(timing::TIMING_FILE), timing)
}

/// A number that may be missing (`null` in JSON, an empty CSV cell): read as NaN, so a
/// non-finite value the fit wrote as "missing" is carried as non-finite, never an error.
fn nan_if_missing<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// [`nan_if_missing`] for every element of a list.
fn nan_if_missing_vec<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> std::result::Result<Vec<f64>, D::Error> {
    Ok(Vec::<Option<f64>>::deserialize(d)?
        .into_iter()
        .map(|v| v.unwrap_or(f64::NAN))
        .collect())
}

/// `Some(x)` when finite: how a number that may be non-finite enters a file (as `null`).
pub fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}
