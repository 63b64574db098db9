//! The fit's output files as typed data: `fit.json` ([`FitResult`]) and `curves.csv`
//! ([`CurveRow`]), field names exactly as in the contracts, with readers that name file, line and
//! column on bad input and atomic writers (the fit writes them with these same types).

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::model::ModelConfig;
use crate::params::ParamFile;

/// A number that may be missing (`null` in JSON, an empty CSV cell): read as NaN, so a
/// non-finite value the fit wrote as "missing" is carried as non-finite, never an error.
fn nan_if_missing<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// A non-finite number written as missing (`null` / an empty CSV cell), never `NaN` text.
fn missing_if_nan<S: serde::Serializer>(v: &f64, s: S) -> std::result::Result<S::Ok, S::Error> {
    v.is_finite().then_some(*v).serialize(s)
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

/// How the fit ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FitStatus {
    Converged,
    Interrupted,
    MaxIterations,
    Failed,
}

impl FitStatus {
    /// The JSON spelling.
    pub fn as_str(&self) -> &'static str {
        match self {
            FitStatus::Converged => "converged",
            FitStatus::Interrupted => "interrupted",
            FitStatus::MaxIterations => "max_iterations",
            FitStatus::Failed => "failed",
        }
    }
}

/// What the fit did with one parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ParamStatus {
    Free,
    Fixed,
    AtBound,
    Undetermined,
}

impl ParamStatus {
    /// The JSON spelling.
    pub fn as_str(&self) -> &'static str {
        match self {
            ParamStatus::Free => "free",
            ParamStatus::Fixed => "fixed",
            ParamStatus::AtBound => "at_bound",
            ParamStatus::Undetermined => "undetermined",
        }
    }
}

/// `fit.json` → `data`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DataInfo {
    pub file: String,
    pub channels: Vec<String>,
    pub n_samples: usize,
    /// The data loader's report, kept opaque here (the report prints it as JSON).
    #[serde(default)]
    pub load_report: serde_json::Value,
}

/// `fit.json` → `parameters[]`: one model parameter (its JSON name, e.g. `alpha_r_deg`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterEntry {
    pub name: String,
    /// `null` when not finite.
    pub value: Option<f64>,
    /// `null` when fixed or undetermined.
    pub std_error: Option<f64>,
    pub status: ParamStatus,
}

/// `fit.json` → `scale[]`: the fitted per-channel scale.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScaleEntry {
    pub channel: String,
    pub value: Option<f64>,
    pub std_error: Option<f64>,
}

/// `fit.json` → `correlation`: `matrix[i][j]` between `names[i]` and `names[j]` (`null` where
/// undefined, e.g. an undetermined direction).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Correlation {
    pub names: Vec<String>,
    pub matrix: Vec<Vec<Option<f64>>>,
}

/// `fit.json` → `residuals.per_channel[]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelResiduals {
    pub channel: String,
    pub rms: Option<f64>,
    pub reduced_chi2: Option<f64>,
}

/// `fit.json` → `residuals`: goodness of fit in the fit's space (`log` or `linear`) and loss.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResidualSummary {
    pub space: String,
    pub loss: String,
    pub rms: Option<f64>,
    pub reduced_chi2: Option<f64>,
    pub dof: Option<i64>,
    #[serde(default)]
    pub per_channel: Vec<ChannelResiduals>,
}

/// `fit.json` → `trace[]`: one solver stage and its cost per iteration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceStage {
    pub stage: String,
    pub iterations: u64,
    pub cost: Option<f64>,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "missing_if_nan")]
    pub wall_s: f64,
    /// Cost per iteration (`null` entries read as NaN and are not drawn).
    #[serde(default, deserialize_with = "nan_if_missing_vec")]
    pub history: Vec<f64>,
}

/// The whole of `fit.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitResult {
    pub hairfit_version: String,
    pub status: FitStatus,
    pub data: DataInfo,
    pub model: ModelConfig,
    /// Every option the fit used, kept opaque (printed verbatim by the report).
    #[serde(default)]
    pub options: serde_json::Map<String, serde_json::Value>,
    /// The fitted parameters, exactly a parameter file.
    pub params: ParamFile,
    pub parameters: Vec<ParameterEntry>,
    pub scale: Vec<ScaleEntry>,
    #[serde(default)]
    pub correlation: Correlation,
    #[serde(default)]
    pub warnings: Vec<String>,
    pub residuals: ResidualSummary,
    #[serde(default)]
    pub trace: Vec<TraceStage>,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "missing_if_nan")]
    pub wall_time_s: f64,
}

/// One row of `curves.csv`: one sample in one channel, angles in degrees; `fit*` include the
/// fitted scale; `residual` is normalised in the fit's space; `weight` the final robust weight.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CurveRow {
    pub sample: u64,
    pub line: u64,
    pub channel: String,
    pub theta_i: f64,
    pub phi_i: f64,
    pub theta_r: f64,
    pub phi_r: f64,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "missing_if_nan")]
    pub data: f64,
    /// Empty in the file when unknown.
    pub sigma: Option<f64>,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "missing_if_nan")]
    pub fit: f64,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "missing_if_nan")]
    pub fit_r: f64,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "missing_if_nan")]
    pub fit_tt: f64,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "missing_if_nan")]
    pub fit_trt: f64,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "missing_if_nan")]
    pub residual: f64,
    #[serde(deserialize_with = "nan_if_missing", serialize_with = "missing_if_nan")]
    pub weight: f64,
}

/// The header `curves.csv` must have, in this order.
pub const CURVES_HEADER: [&str; 15] = [
    "sample", "line", "channel", "theta_i", "phi_i", "theta_r", "phi_r", "data", "sigma", "fit",
    "fit_r", "fit_tt", "fit_trt", "residual", "weight",
];

/// Read `fit.json`; a syntax or schema error names line and column.
pub fn read_fit_json(path: &Path) -> Result<FitResult> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    serde_json::from_str(&text).map_err(|e| {
        Error::input(
            path,
            e.line() as u64,
            e.column() as u64,
            format!("{e}; fit.json is written by `hairfit fit` — re-run the fit to regenerate it"),
        )
    })
}

/// Write `fit.json` atomically (pretty-printed).
pub fn write_fit_json(path: &Path, fit: &FitResult) -> Result<()> {
    write_atomically(path, |w| {
        serde_json::to_writer_pretty(&mut *w, fit)
            .map_err(|e| Error::Other(format!("{}: {e}", path.display())))?;
        w.write_all(b"\n").map_err(|e| Error::io(path, e))
    })
}

/// Read every row of `curves.csv`, checking the header; errors name line and column.
pub fn read_curves_csv(path: &Path) -> Result<Vec<CurveRow>> {
    let mut reader = csv::Reader::from_path(path).map_err(|e| csv_error(path, e))?;
    let header = reader.headers().map_err(|e| csv_error(path, e))?.clone();
    for (col, expected) in CURVES_HEADER.iter().enumerate() {
        if header.get(col).map(str::trim) != Some(*expected) {
            return Err(Error::input(
                path,
                1,
                col as u64 + 1,
                format!(
                    "expected column `{expected}` here; curves.csv's header is `{}`",
                    CURVES_HEADER.join(",")
                ),
            ));
        }
    }
    let mut rows = Vec::new();
    for record in reader.deserialize::<CurveRow>() {
        rows.push(record.map_err(|e| csv_error(path, e))?);
    }
    Ok(rows)
}

/// Write `curves.csv` atomically.
pub fn write_curves_csv(path: &Path, rows: &[CurveRow]) -> Result<()> {
    write_atomically(path, |w| {
        let mut writer = csv::Writer::from_writer(w);
        for row in rows {
            writer.serialize(row).map_err(|e| csv_error(path, e))?;
        }
        writer.flush().map_err(|e| Error::io(path, e))
    })
}

/// A csv error as an input error at its 1-based line and column (field).
fn csv_error(path: &Path, e: csv::Error) -> Error {
    let (line, column) = match e.kind() {
        csv::ErrorKind::Deserialize { pos, err } => (
            pos.as_ref().map_or(0, |p| p.line()),
            err.field().map_or(0, |f| f + 1),
        ),
        _ => (e.position().map_or(0, |p| p.line()), 0),
    };
    match e.kind() {
        csv::ErrorKind::Io(_) => Error::Other(format!("{}: {e}", path.display())),
        _ => Error::input(
            path,
            line,
            column,
            format!("{e}; curves.csv is written by `hairfit fit` — re-run the fit"),
        ),
    }
}
