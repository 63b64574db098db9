//! Every on-disk format hairfit writes and reads, one Serialize + Deserialize type each, so a
//! writer and its reader can never disagree: `fit.json` ([`FitJson`]), `curves.csv`
//! ([`CurveRow`]), `timing.json` ([`Timing`]), `truth.json` ([`Truth`]), the loader's report
//! ([`LoadReport`]); `params.json` is [`crate::params::ParamFile`]. Readers name file, line and
//! column on bad input; writers write atomically. This module depends on `model` and `params`
//! only, never on `fit` or `report` (both use it).

pub mod curves;
pub mod decimal;
pub mod fit_json;
pub mod load_report;
pub mod timing;
pub mod truth;

use std::path::Path;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::atomic::write_atomically;
use crate::error::{Error, Result};

pub use curves::{
    read_curves_csv, write_curves_csv, CurveRow, CurveValues, Curves, CurvesMode, CURVES_HEADER,
    DOWN_WEIGHT,
};
pub use fit_json::{
    ChannelCorrelation, ChannelResiduals, Correlation, DataInfo, DownWeighted, EffectsSource,
    FitJson, FitStatus, Floored, GofThresholds, GoodnessOfFit, Interval, OptionsRecord,
    ParamStatus, ParameterEntry, ResidualSummary, ScaleEntry, ScaleMethod, Suggestion, TraceStage,
    Verdict,
};
pub use load_report::{LineTally, LoadReport, RejectReason, FIRST_LINES};
pub use timing::{StageTiming, Timing};
pub use truth::Truth;

/// Read a JSON file as `T`; a syntax or schema error names line and column, followed by `hint`
/// (what the file is and how to regenerate it).
pub fn read_json<T: DeserializeOwned>(path: &Path, hint: &str) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    serde_json::from_str(&text).map_err(|e| json_error(path, e, hint))
}

/// Parse `text` (from `path`, for messages) as a JSON **object** of type `T`. serde would also
/// fill a struct from an array, by position; a parameter file written as an array is a
/// mistake, so anything but an object is refused where it starts.
pub fn parse_json_object<T: DeserializeOwned>(text: &str, path: &Path, hint: &str) -> Result<T> {
    if let Some((offset, c)) = text.char_indices().find(|(_, c)| !c.is_whitespace()) {
        if c != '{' {
            let line = text[..offset].matches('\n').count() as u64 + 1;
            let column = (offset - text[..offset].rfind('\n').map_or(0, |i| i + 1)) as u64 + 1;
            return Err(Error::input(
                path,
                line,
                column,
                format!("expected a JSON object `{{ … }}`, found `{c}`; {hint}"),
            ));
        }
    }
    serde_json::from_str(text).map_err(|e| json_error(path, e, hint))
}

/// A JSON parameter file: one object, checked after reading.
pub trait ParameterFile: DeserializeOwned {
    /// What the file holds, for error messages (its keys).
    fn hint() -> String;
    /// Check every value's domain.
    fn validate(&self) -> Result<()>;

    /// Read and validate `path`.
    fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::from_json_str(&text, path)
    }

    /// Parse and validate JSON text; `path` only names the source in error messages.
    fn from_json_str(text: &str, path: impl AsRef<Path>) -> Result<Self> {
        let file: Self = parse_json_object(text, path.as_ref(), &Self::hint())?;
        file.validate()?;
        Ok(file)
    }
}

/// Write `value` as pretty-printed JSON plus a final newline, atomically. serde_json writes
/// a non-finite `f64` as `null`; the types here say where that can happen.
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<()> {
    write_atomically(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value)
            .map_err(|e| json_error(path, e, "cannot serialise"))?;
        w.write_all(b"\n").map_err(|e| Error::io(path, e))
    })
}

/// The one JSON error converter: syntax/schema errors at their line and column, I/O as I/O.
fn json_error(path: &Path, e: serde_json::Error, hint: &str) -> Error {
    if e.is_io() {
        return Error::Other(format!("{}: {e}", path.display()));
    }
    Error::json(path, &e, Some(hint))
}

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
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    write_json(&dir.join("fit.json"), fit)?;
    write_json(&dir.join("params.json"), &fit.params)?;
    if let Some(curves) = curves {
        curves.write_csv(&dir.join("curves.csv"), None)?;
    }
    write_timing(dir, timing)
}

/// Write `timing.json` into `dir` (again after the report, with its `outputs_s`).
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
