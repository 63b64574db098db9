//! Loading measured or synthetic samples: owns the [`Dataset`] (struct of arrays, angles in
//! radians) that the fit and the synthesizer use, the three file formats (header CSV, headerless
//! fixed-angle goniometer scans, JSON), and the [`LoadReport`] that accounts for every row.
//!
//! A malformed file is an [`Error::Input`] naming file, line and column; a well-formed row with
//! a bad value is a rejection counted in the report, never silently dropped.

mod csv;
mod csv_rows;
mod dataset;
mod options;

mod expr;
mod json;
pub(crate) mod lines;
pub(crate) mod records;
mod report;
mod rows;
mod scan;
pub(crate) mod unit;

pub(crate) use self::csv::{repeated_column, repeated_column_message};

use std::path::Path;

use crate::error::{Error, Result};

pub use self::csv::{write_csv, write_csv_with};
pub use self::dataset::{round_trip_degrees, Dataset, ANGLE_COLUMNS};
pub use self::expr::Linear;
pub use self::json::write_json;
pub use self::options::{AngleUnit, Format, LoadOptions};
pub use self::report::{LineTally, LoadReport, RejectReason, FIRST_LINES};

/// The format of `path`: `--format`, else `--columns` means scan, else the extension.
pub fn detect_format(path: &Path, options: &LoadOptions) -> Format {
    if let Some(f) = options.format {
        return f;
    }
    if !options.columns.is_empty() {
        return Format::Scan;
    }
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("csv" | "tsv") => Format::Csv,
        Some("json") => Format::Json,
        _ => Format::Scan,
    }
}

/// Load samples from `path`, returning the accepted samples and a report on every row.
pub fn load(path: &Path, options: &LoadOptions) -> Result<(Dataset, LoadReport)> {
    // A missing file or a directory says so before any format-specific advice (a mistyped
    // `data.cvs` would otherwise be read as a scan and asked for --columns).
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(Error::Other(format!(
            "{}: is a directory, not a data file",
            path.display()
        )));
    }
    if !meta.is_file() {
        // Reading a pipe a second time would wait forever for a writer that is gone.
        return Err(Error::Other(format!(
            "{}: is a pipe or a device, not a file: a data file is read more than once (its \
             format, unit line and rows), so save the stream to a file first (e.g. \
             `… > data.csv`) and give that file",
            path.display()
        )));
    }
    let format = detect_format(path, options);
    check_options_fit_format(path, format, options)?;
    if let Some(t) = options.negative_tolerance {
        // NaN fails this too.
        if t.is_nan() || t < 0.0 {
            return Err(Error::Other(format!(
                "--negative-tolerance must be a number >= 0 (got {t})"
            )));
        }
    }
    let started = std::time::Instant::now();
    let (dataset, mut report) = match format {
        Format::Csv => csv::load_csv(path, options)?,
        Format::Scan => scan::load_scan(path, options)?,
        Format::Json => json::load_json(path, options)?,
    };
    report.file = path.display().to_string();
    report.format = format.name().into();
    report.settings = Some(format!("{options:?}"));
    report.seconds = Some(started.elapsed().as_secs_f64());
    debug_assert_eq!(report.rows_read, report.accepted + report.rejected_total());
    Ok((dataset, report))
}

/// The channel names of the data at `path` as far as they can be known without reading its
/// rows: a CSV file's header or a scan's `--columns`. `None` for a JSON dataset (its
/// `"channels"` can only be found by parsing the whole file) and for a file or header that
/// cannot be read (loading it says why). For checks made before anything runs (`hairfit
/// batch`'s manifest): the header is one line, however large the file.
pub fn channels_without_loading(path: &Path, options: &LoadOptions) -> Option<Vec<String>> {
    if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
        return None;
    }
    match detect_format(path, options) {
        Format::Csv => csv::header_channels(path, options),
        Format::Scan => scan::column_channels(options),
        Format::Json => None,
    }
}

/// Scan-only options on another format are a mistake worth an error, not a silent no-op.
fn check_options_fit_format(path: &Path, format: Format, options: &LoadOptions) -> Result<()> {
    let scan_only = [
        ("--columns", !options.columns.is_empty()),
        ("--fixed", !options.fixed.is_empty()),
        ("--map", !options.maps.is_empty()),
    ];
    if format != Format::Csv && options.delimiter.is_some() {
        return Err(Error::Other(format!(
            "{}: --delimiter applies to CSV files with a header; this file is read as {}",
            path.display(),
            format.name()
        )));
    }
    if format != Format::Scan {
        if let Some((name, _)) = scan_only.iter().find(|(_, given)| *given) {
            return Err(Error::Other(format!(
                "{}: {name} applies to headerless scan files only; this file is read as {} \
                 (use --format scan to read it as a scan)",
                path.display(),
                format.name()
            )));
        }
    }
    if format == Format::Json && options.angles == Some(AngleUnit::Rad) {
        return Err(Error::Other(format!(
            "{}: JSON datasets are always in degrees; drop --angles rad",
            path.display()
        )));
    }
    Ok(())
}

/// `hairfit load`: load `path` and return the report as text (a summary, or JSON when `json`).
pub fn load_command(path: &Path, options: &LoadOptions, json: bool) -> Result<String> {
    let (_, report) = load(path, options)?;
    if json {
        let mut text = serde_json::to_string_pretty(&report)
            .map_err(|e| Error::Other(format!("cannot serialize the report: {e}")))?;
        text.push('\n');
        Ok(text)
    } else {
        Ok(report.to_string())
    }
}
