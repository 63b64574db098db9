//! `curves.csv`: the fit at every sample, one row per sample and channel ([`CurveRow`]),
//! written and read with the csv crate (cells quoted when they need it).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::nan_if_missing;
use crate::atomic::write_atomically;
use crate::error::{Error, Result};

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

/// Write `curves.csv` atomically: [`CURVES_HEADER`], then one record per row.
pub fn write_curves_csv(path: &Path, rows: &[CurveRow]) -> Result<()> {
    write_atomically(path, |w| {
        let mut writer = csv::WriterBuilder::new().has_headers(false).from_writer(w);
        writer
            .write_record(CURVES_HEADER)
            .map_err(|e| csv_error(path, e))?;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The header written is the header serde derives from the type: one definition.
    #[test]
    fn header_matches_the_type() {
        let row = CurveRow {
            sample: 0,
            line: 2,
            channel: "r,g".into(),
            theta_i: 0.0,
            phi_i: -170.0,
            theta_r: 1.5,
            phi_r: 2.0,
            data: 1.0,
            sigma: None,
            fit: f64::NAN,
            fit_r: 0.5,
            fit_tt: 0.25,
            fit_trt: 0.25,
            residual: -0.1,
            weight: 1.0,
        };
        let mut w = csv::Writer::from_writer(Vec::new());
        w.serialize(&row).unwrap();
        let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next().unwrap(), CURVES_HEADER.join(","));
        // Number formats are the file's; a channel name with a comma is quoted.
        assert_eq!(
            lines.next().unwrap(),
            "0,2,\"r,g\",0,-170,1.5,2,1e0,,,5e-1,2.5e-1,2.5e-1,-1e-1,1e0"
        );
    }
}
