//! Reading `curves.csv`'s records: each record's numbers, and errors at their line and column
//! that say how to regenerate the file.

use std::path::Path;

use super::record::{CurveValues, CURVES_HEADER};
use crate::error::{Error, Result};

/// The numbers of one record of `curves.csv`.
pub(super) struct ParsedRow {
    pub id: u64,
    pub line: u64,
    pub angles: [f64; 4],
    pub values: CurveValues,
}

/// An input error at `record`'s line, column `col` (0-based) not being `what`.
pub(super) fn field_error(path: &Path, record: &csv::ByteRecord, col: usize, what: &str) -> Error {
    Error::input(
        path,
        record.position().map_or(0, |p| p.line()),
        col as u64 + 1,
        format!(
            "`{}` in column `{}` is not {what}; curves.csv is written by `hairfit fit` — re-run the fit",
            String::from_utf8_lossy(record.get(col).unwrap_or_default()),
            CURVES_HEADER[col]
        ),
    )
}

/// Parse the numbers of one record (angles required; empty value cells are NaN).
pub(super) fn parse_record(path: &Path, record: &csv::ByteRecord) -> Result<ParsedRow> {
    let text = |col: usize| std::str::from_utf8(record.get(col).unwrap_or_default()).ok();
    let int = |col: usize| {
        text(col)
            .and_then(|t| t.parse::<u64>().ok())
            .ok_or_else(|| field_error(path, record, col, "an unsigned integer"))
    };
    let number = |col: usize| {
        text(col)
            .and_then(|t| t.parse::<f64>().ok())
            .ok_or_else(|| field_error(path, record, col, "a number"))
    };
    // Empty cells are numbers the fit could not compute.
    let optional = |col: usize| match record.get(col) {
        Some(b"") | None => Ok(f64::NAN),
        _ => number(col),
    };
    Ok(ParsedRow {
        id: int(0)?,
        line: int(1)?,
        angles: [number(3)?, number(4)?, number(5)?, number(6)?],
        values: CurveValues {
            data: optional(7)?,
            sigma: optional(8)?,
            fit: optional(9)?,
            fit_r: optional(10)?,
            fit_tt: optional(11)?,
            fit_trt: optional(12)?,
            residual: optional(13)?,
            weight: optional(14)?,
        },
    })
}

/// `text` as the csv writer writes it inside a record (quoted only when it must be).
pub(super) fn csv_field(text: &str) -> Vec<u8> {
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    // A second field: a lone empty field would be quoted to tell it from an empty record.
    w.write_record([text, "x"]).expect("writing to memory");
    let mut bytes = w.into_inner().expect("writing to memory");
    bytes.truncate(bytes.len() - ",x\n".len());
    bytes
}

/// A csv error as an input error at its 1-based line and column (field).
pub(super) fn csv_error(path: &Path, e: csv::Error) -> Error {
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
