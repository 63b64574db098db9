//! `hairfit eval`: stream an angles CSV through the model and append the scattering values.
//!
//! The input is read and written in fixed-size chunks (evaluated in parallel with rayon), so memory
//! stays bounded whatever the row count. Output files are written atomically: an error on any row
//! leaves no output file behind.

use std::io::{Read, Write};
use std::path::Path;

use rayon::prelude::*;

use crate::atomic::write_atomically;
use crate::data::lines::{csv_error, LineCounter, TextGuard};
use crate::data::AngleUnit;
use crate::error::{Error, Result};
use crate::family::{FamilyModel, FamilyParams};
use crate::model::Angles;

/// Rows evaluated per parallel chunk: large enough to amortise the rayon fork, small enough that
/// memory does not grow with the file.
const CHUNK_ROWS: usize = 16_384;

/// Values (rows × channels) per chunk: with many channels the chunk has fewer rows, so memory
/// stays bounded by the channel count too (16k rows × 1M channels asked for 131 GB).
const CHUNK_VALUES: usize = 1 << 20;

/// Rows per parallel work item of a chunk (a batch shares work per exit direction).
const EVAL_BATCH: usize = 256;

pub use crate::data::ANGLE_COLUMNS;

/// What `hairfit eval` needs besides the files.
#[derive(Debug, Clone)]
pub struct EvalRequest {
    /// The model family with its parameters and configuration.
    pub model: FamilyModel,
    /// Column names for the appended values: `["s"]` or `["s_0", …]`.
    pub output_columns: Vec<String>,
    /// The parameters as read, for error messages.
    pub params: FamilyParams,
    /// `--angles`: the input's angle unit; the file's `# angles:` line decides when absent
    /// (degrees when neither says).
    pub angles: Option<AngleUnit>,
}

/// Summary of an evaluation run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EvalSummary {
    pub rows: u64,
}

/// Output column names: `s` for a scalar `sigma_a`, `s_0…s_{N−1}` for N channels.
pub fn output_columns(n_channels: usize, scalar: bool) -> Vec<String> {
    if scalar {
        vec!["s".to_string()]
    } else {
        (0..n_channels).map(|c| format!("s_{c}")).collect()
    }
}

/// Evaluate `input` and write to `output` (atomically), or to stdout when `output` is `None`.
pub fn eval_file(
    input: &Path,
    output: Option<&Path>,
    request: &EvalRequest,
) -> Result<EvalSummary> {
    let file = std::fs::File::open(input).map_err(|e| Error::io(input, e))?;
    if file.metadata().is_ok_and(|m| m.is_dir()) {
        return Err(Error::Other(format!(
            "--input {}: is a directory, not an angles CSV",
            input.display()
        )));
    }
    let file = TextGuard::new(file);
    // The unit line is read before the stream, so `eval_stream` sees the settled unit.
    let directive = crate::data::unit::file_directive(input, 1)?;
    let request = &EvalRequest {
        angles: Some(crate::data::unit::resolve(
            request.angles,
            directive,
            input,
        )?),
        ..request.clone()
    };
    match output {
        Some(out) => {
            let mut summary = EvalSummary { rows: 0 };
            write_atomically(out, |w| {
                summary = eval_stream(file, input, w, request)?;
                Ok(())
            })?;
            Ok(summary)
        }
        None => {
            let stdout = std::io::stdout();
            let mut lock = std::io::BufWriter::new(stdout.lock());
            let summary = eval_stream(file, input, &mut lock, request)?;
            lock.flush().map_err(|e| Error::io("<stdout>", e))?;
            Ok(summary)
        }
    }
}

/// Evaluate a CSV stream; `source` names the input in error messages.
pub fn eval_stream<R: Read, W: Write + ?Sized>(
    input: R,
    source: &Path,
    output: &mut W,
    request: &EvalRequest,
) -> Result<EvalSummary> {
    let (input, newlines) = LineCounter::wrap(input);
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(false)
        .comment(Some(b'#'))
        .from_reader(input);
    // The record just read ends before the reader's position; its last byte is on its line.
    let line_of_last_record = |reader: &csv::Reader<_>| {
        let end: u64 = csv::Reader::position(reader).byte();
        1 + newlines.borrow_mut().count_before(end.saturating_sub(1))
    };
    let headers = match reader.byte_headers() {
        Ok(h) => h.clone(),
        Err(e) => {
            let line = line_of_last_record(&reader);
            return Err(csv_error(source, e, line));
        }
    };
    let header_line = line_of_last_record(&reader);
    let header_names: Vec<String> = headers
        .iter()
        .enumerate()
        .map(|(i, h)| {
            let name = String::from_utf8_lossy(h);
            // A UTF-8 byte-order mark may precede the first header.
            let name = if i == 0 {
                name.trim_start_matches('\u{feff}')
            } else {
                &name
            };
            name.trim().to_string()
        })
        .collect();
    let angle_index = locate_angle_columns(source, header_line, &header_names)?;
    for name in &request.output_columns {
        if header_names.iter().any(|h| h == name) {
            return Err(Error::input(
                source,
                header_line,
                1 + header_names.iter().position(|h| h == name).unwrap() as u64,
                format!(
                    "the input already has a column `{name}`, which eval would append; rename it"
                ),
            ));
        }
    }

    let mut writer = csv::WriterBuilder::new().from_writer(output);
    let mut out_header: Vec<&str> = header_names.iter().map(String::as_str).collect();
    out_header.extend(request.output_columns.iter().map(String::as_str));
    writer
        .write_record(&out_header)
        .map_err(|e| write_error(&e))?;

    let n_channels = request.model.n_channels().max(1);
    let chunk_rows = (CHUNK_VALUES / n_channels).clamp(1, CHUNK_ROWS);
    // Records are reused chunk after chunk: a fresh record per row cost a malloc/free pair per
    // row, ~17% of eval's time.
    let mut pool: Vec<csv::ByteRecord> = Vec::with_capacity(chunk_rows);
    let mut angles: Vec<Angles> = Vec::with_capacity(chunk_rows);
    let mut values: Vec<f64> = Vec::with_capacity(chunk_rows * n_channels);
    let mut rows = 0u64;
    loop {
        angles.clear();
        let mut filled = 0;
        while filled < chunk_rows {
            if filled == pool.len() {
                pool.push(csv::ByteRecord::new());
            }
            match reader.read_byte_record(&mut pool[filled]) {
                Ok(true) => {}
                Ok(false) => break,
                Err(e) => {
                    let line = line_of_last_record(&reader);
                    return Err(csv_error(source, e, line));
                }
            }
            let line = line_of_last_record(&reader);
            angles.push(parse_angles(
                source,
                line,
                &pool[filled],
                &angle_index,
                &header_names,
                request.angles.unwrap_or(AngleUnit::Deg),
            )?);
            filled += 1;
        }
        let records = &pool[..filled];
        if records.is_empty() {
            break;
        }
        values.clear();
        values.resize(records.len() * n_channels, 0.0);
        // Chunks of rows share the Chiang width integral per exit direction.
        values
            .par_chunks_mut(n_channels * EVAL_BATCH)
            .zip(angles.par_chunks(EVAL_BATCH))
            .for_each(|(out, a)| request.model.eval_batch(a, out));
        if let Some(j) = values.iter().position(|v| !v.is_finite()) {
            return Err(non_finite_error(
                source,
                records,
                j / n_channels,
                values[j],
                request,
            ));
        }
        // Input fields pass through as bytes; values are appended with ryu's shortest round-trip
        // digits (no String per value, no record copy).
        let mut digits = ryu::Buffer::new();
        for (record, vals) in records.iter().zip(values.chunks(n_channels)) {
            for field in record.iter() {
                writer.write_field(field).map_err(|e| write_error(&e))?;
            }
            for &v in vals {
                writer
                    .write_field(digits.format_finite(v))
                    .map_err(|e| write_error(&e))?;
            }
            writer
                .write_record(None::<&[u8]>)
                .map_err(|e| write_error(&e))?;
        }
        rows += records.len() as u64;
    }
    writer.flush().map_err(|e| Error::io("<output>", e))?;
    Ok(EvalSummary { rows })
}

/// Indices of the four angle columns, or an error naming the missing ones.
fn locate_angle_columns(source: &Path, header_line: u64, headers: &[String]) -> Result<[usize; 4]> {
    let mut index = [0usize; 4];
    let mut missing = Vec::new();
    for (slot, name) in index.iter_mut().zip(ANGLE_COLUMNS) {
        match headers.iter().position(|h| h == name) {
            Some(i) => *slot = i,
            None => missing.push(name),
        }
    }
    if missing.is_empty() {
        Ok(index)
    } else {
        Err(Error::input(
            source,
            header_line,
            1,
            format!(
                "missing column(s) {}; the header must name theta_i,phi_i,theta_r,phi_r (degrees), found: {}",
                missing.join(", "),
                headers.join(",")
            ),
        ))
    }
}

/// Parse one row's angles (in `unit`) with errors naming line and column.
fn parse_angles(
    source: &Path,
    line: u64,
    record: &csv::ByteRecord,
    index: &[usize; 4],
    headers: &[String],
    unit: AngleUnit,
) -> Result<Angles> {
    let (theta_limit, unit_name) = match unit {
        AngleUnit::Deg => (90.0, "degrees"),
        AngleUnit::Rad => (std::f64::consts::FRAC_PI_2, "radians"),
    };
    let mut deg = [0.0f64; 4];
    for (k, &col) in index.iter().enumerate() {
        let field = record.get(col).unwrap_or_default();
        let text = std::str::from_utf8(field).map_err(|_| {
            Error::input(source, line, col as u64 + 1, "the field is not valid UTF-8")
        })?;
        let value: f64 = text.trim().parse().map_err(|_| {
            Error::input(
                source,
                line,
                col as u64 + 1,
                format!(
                    "`{}` is not a number (column `{}`, {unit_name})",
                    text.trim(),
                    headers[col]
                ),
            )
        })?;
        if !value.is_finite() {
            return Err(Error::input(
                source,
                line,
                col as u64 + 1,
                format!(
                    "`{}` is not finite (column `{}`)",
                    text.trim(),
                    headers[col]
                ),
            ));
        }
        let is_theta = k % 2 == 0;
        if is_theta && value.abs() >= theta_limit {
            return Err(Error::input(
                source,
                line,
                col as u64 + 1,
                format!(
                    "{} = {value} {unit_name} lies on the fiber axis or beyond; inclinations must satisfy |θ| < 90° (π/2)",
                    headers[col]
                ),
            ));
        }
        deg[k] = value;
    }
    Ok(match unit {
        AngleUnit::Deg => Angles::from_degrees(deg[0], deg[1], deg[2], deg[3]),
        AngleUnit::Rad => Angles {
            theta_i: deg[0],
            phi_i: deg[1],
            theta_r: deg[2],
            phi_r: deg[3],
        },
    })
}

/// A non-finite S is an error naming the row and the parameters, never a `NaN` in the output.
fn non_finite_error(
    source: &Path,
    records: &[csv::ByteRecord],
    row: usize,
    value: f64,
    request: &EvalRequest,
) -> Error {
    let fields: Vec<String> = records[row]
        .iter()
        .map(|f| String::from_utf8_lossy(f).into_owned())
        .collect();
    Error::Other(format!(
        "{}: the model gives S = {value} for the row `{}` with the parameters {}: use \
         parameters the model can evaluate",
        source.display(),
        fields.join(","),
        request.params.json_line()
    ))
}

fn write_error(err: &csv::Error) -> Error {
    Error::Other(format!("could not write the output: {err}"))
}
