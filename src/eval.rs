//! `hairfit eval`: stream an angles CSV through the model and append the scattering values.
//!
//! The input is read and written in fixed-size chunks (evaluated in parallel with rayon, or on the
//! calling thread when the pool has one thread), so memory stays bounded whatever the row count.
//! Output files are written atomically: an error on any row leaves no output file behind.

use std::io::{Read, Write};
use std::ops::Range;
use std::path::Path;

use rayon::prelude::*;

use crate::atomic::write_atomically;
use crate::data::lines::{csv_error, quote_across_lines_error, read_error, LineCounter, TextGuard};
use crate::data::records::{needs_csv_parser, Blocks};
use crate::data::unit::{RadiansEvidence, UnitLine};
use crate::data::{repeated_column, repeated_column_message, AngleUnit};
use crate::error::{Error, Result};
use crate::families::{FamilyModel, FamilyParams};
use crate::geometry::Angles;

mod angles;
mod plain_row;
mod shortest;
use angles::{locate_angle_columns, parse_angles, to_angles};
use plain_row::PlainRow;
use shortest::push_shortest;

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
    /// `--angles`: the input's angle unit; the file's `# angles:` line decides when absent.
    /// When neither says, degrees are assumed and the summary warns if the angles look like
    /// radians (the loader's rule, applied to every row read).
    pub angles: Option<AngleUnit>,
}

/// Summary of an evaluation run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EvalSummary {
    pub rows: u64,
    /// Things that may make the output wrong (e.g. angles that look like radians read as
    /// degrees); known only once every row is read, so they come after the output.
    pub warnings: Vec<String>,
}

/// Output column names: `s` for a scalar `sigma_a`, `s_0…s_{N−1}` for N channels.
pub fn output_columns(n_channels: usize, scalar: bool) -> Vec<String> {
    if scalar {
        vec!["s".to_string()]
    } else {
        (0..n_channels).map(|c| format!("s_{c}")).collect()
    }
}

/// `--input -` reads standard input, `--output -` writes standard output.
pub const STDIO_NAME: &str = "-";

/// The file `--output` names: `None` for standard output (absent, or `-`).
pub fn output_file(output: Option<&Path>) -> Option<&Path> {
    output.filter(|out| *out != Path::new(STDIO_NAME))
}

/// Evaluate `input` and write to `output` (atomically), or to stdout when `output` is `None` or
/// `-`; an `input` of `-` is standard input.
pub fn eval_file(
    input: &Path,
    output: Option<&Path>,
    request: &EvalRequest,
) -> Result<EvalSummary> {
    // `-` is standard input, named `<stdin>` in messages.
    let stdin = input == Path::new(STDIO_NAME);
    let (source, is_file): (Box<dyn Read>, bool) = if stdin {
        (Box::new(std::io::stdin().lock()), false)
    } else {
        let file = std::fs::File::open(input).map_err(|e| Error::io(input, e))?;
        let meta = file.metadata().map_err(|e| Error::io(input, e))?;
        if meta.is_dir() {
            return Err(Error::Other(format!(
                "--input {}: is a directory, not an angles CSV",
                input.display()
            )));
        }
        (Box::new(file), meta.is_file())
    };
    let input = if stdin { Path::new("<stdin>") } else { input };
    let output = output_file(output);
    if let Some(out) = output {
        crate::atomic::refuse_directory_output("--output", out, "eval.csv")?;
    }
    // The unit line is read before the stream, so `eval_stream` sees the settled unit (`None`
    // when neither the line nor `--angles` states one). A file is read again from its start; a
    // pipe or device can be read only once, so the lines read for the unit are kept and read
    // again in front of the rest.
    let mut file = std::io::BufReader::with_capacity(1 << 16, TextGuard::new(source));
    let mut preamble = Vec::new();
    let directive = if is_file {
        crate::data::unit::file_directive(input, 1)?
    } else {
        let limit = crate::data::unit::STREAM_PREAMBLE_LIMIT as u64 + 1;
        let mut bounded = (&mut file).take(limit);
        crate::data::unit::directive_in(&mut bounded, input, 1, Some(&mut preamble))?
    };
    let file = std::io::Cursor::new(preamble).chain(file);
    crate::data::unit::resolve(request.angles, directive, input)?;
    let request = &EvalRequest {
        angles: request.angles.or(directive.map(|(unit, _)| unit)),
        ..request.clone()
    };
    match output {
        Some(out) => {
            let mut summary = EvalSummary {
                rows: 0,
                warnings: Vec::new(),
            };
            write_atomically(out, |w| {
                summary = eval_stream(file, input, w, request).map_err(|e| name_output(e, out))?;
                Ok(())
            })?;
            Ok(summary)
        }
        None => {
            let stdout = std::io::stdout();
            let mut lock = std::io::BufWriter::new(stdout.lock());
            let stdout = Path::new("<stdout>");
            let summary =
                eval_stream(file, input, &mut lock, request).map_err(|e| name_output(e, stdout))?;
            lock.flush().map_err(|e| Error::io(stdout, e))?;
            Ok(summary)
        }
    }
}

/// The stream names a failed write `OUTPUT_NAME`; the file knows its name.
const OUTPUT_NAME: &str = "<output>";

fn name_output(e: Error, name: &Path) -> Error {
    match e {
        Error::Io { path, source } if path == Path::new(OUTPUT_NAME) => Error::io(name, source),
        e => e,
    }
}

/// Evaluate a CSV stream; `source` names the input in error messages.
///
/// Quote-free input is read by hand in large blocks and copied through verbatim (plain data lines
/// parsed in place by [`PlainRow`], any other line split at its commas); from the first block
/// with a quote or a lone carriage return on, the csv crate reads the rest (the output is the
/// same either way).
pub fn eval_stream<R: Read, W: Write + ?Sized>(
    input: R,
    source: &Path,
    output: &mut W,
    request: &EvalRequest,
) -> Result<EvalSummary> {
    let model = |angles: &[Angles], out: &mut [f64]| request.model.eval_batch_fast(angles, out);
    eval_stream_with(input, source, output, request, &model)
}

/// [`eval_stream`] with `model` in place of the request's model (`model(angles, out)` fills
/// `out` row-major, one value per row and channel): benchmarks time the reading and writing
/// alone with a trivial one.
pub fn eval_stream_with<R: Read, W: Write + ?Sized>(
    input: R,
    source: &Path,
    output: &mut W,
    request: &EvalRequest,
    model: &(dyn Fn(&[Angles], &mut [f64]) + Sync),
) -> Result<EvalSummary> {
    let mut blocks = Blocks::new(input, &[], BLOCK_BYTES);
    let mut eval = Evaluation::new(source, output, request, model);
    let mut line_base = 0u64;
    let mut first_block = true;
    let mut starts: Vec<usize> = Vec::new();
    while let Some(mut block) = blocks.next_block().map_err(|e| read_error(source, e))? {
        if needs_csv_parser(block) {
            eval_csv_rest(blocks.rest_from_block(), line_base, &mut eval)?;
            return eval.finish();
        }
        if first_block {
            // The csv crate drops a byte-order mark at the start of the input.
            block = block.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(block);
            first_block = false;
        }
        // Lines as `for_each_line` hands them out, counted from 1 in the block.
        let mut pos = 0;
        let mut index = 0u64;
        while pos < block.len() {
            index += 1;
            if let Some(row) = eval.header.as_ref().and_then(|h| h.plain.read(block, pos)) {
                eval.data_row(row.values, pos..row.end);
                pos = row.next;
                eval.flush_if_full(Some(block))?;
                continue;
            }
            let end = memchr::memchr(b'\n', &block[pos..]).map_or(block.len(), |i| pos + i);
            let text_end = if block[pos..end].ends_with(b"\r") {
                end - 1
            } else {
                end
            };
            let line = &block[pos..text_end];
            if !line.is_empty() && line[0] != b'#' {
                let split = SplitLine::new(line, &mut starts);
                eval.record(line_base + index, &split, Some(pos..text_end))?;
                eval.flush_if_full(Some(block))?;
            }
            pos = end + 1;
        }
        // The rows' text stays in the block: they are written before the next block is read.
        eval.flush_chunk(Some(block))?;
        line_base += index;
    }
    if eval.header.is_none() {
        // No header at all: the error names the missing columns at the last line.
        eval.record(line_base.max(1), &csv::ByteRecord::new(), None)?;
    }
    eval.finish()
}

/// Read the rest of the input (after `line_base` lines) with the csv crate.
fn eval_csv_rest<R: Read, W: Write + ?Sized>(
    rest: R,
    line_base: u64,
    eval: &mut Evaluation<'_, W>,
) -> Result<()> {
    let source = eval.source;
    let (input, newlines) = LineCounter::wrap(rest);
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .comment(Some(b'#'))
        .from_reader(input);
    let mut record = csv::ByteRecord::new();
    loop {
        let more = reader.read_byte_record(&mut record);
        // The record just read ends before the reader's position; its last byte is on its line.
        let end: u64 = reader.position().byte();
        let line = line_base + 1 + newlines.borrow_mut().count_before(end.saturating_sub(1));
        match more {
            Ok(true) => {
                let expected = eval.header.as_ref().map(|h| h.names.len());
                if let Some(expected) = expected.filter(|&n| n != record.len()) {
                    if let Some(e) = quote_across_lines_error(source, &record, line, expected) {
                        return Err(e);
                    }
                }
                eval.record(line, &record, None)?;
                eval.flush_if_full(None)?;
            }
            Ok(false) => {
                if eval.header.is_none() {
                    eval.record(line, &csv::ByteRecord::new(), None)?;
                }
                return Ok(());
            }
            Err(e) => return Err(csv_error(source, e, line)),
        }
    }
}

/// Input bytes per block read.
const BLOCK_BYTES: usize = 1 << 20;

/// The fields of a record, from a quote-free line or from the csv crate.
trait Fields {
    fn count(&self) -> usize;
    fn field(&self, i: usize) -> &[u8];
}

impl Fields for csv::ByteRecord {
    fn count(&self) -> usize {
        self.len()
    }
    fn field(&self, i: usize) -> &[u8] {
        self.get(i).unwrap_or_default()
    }
}

/// A quote-free line split at its commas.
struct SplitLine<'a> {
    text: &'a [u8],
    /// Start of each field; the field runs to the next start minus the comma.
    starts: &'a [usize],
}

impl<'a> SplitLine<'a> {
    /// Split `text`, keeping the field starts in `starts` (reused line after line).
    fn new(text: &'a [u8], starts: &'a mut Vec<usize>) -> Self {
        starts.clear();
        starts.push(0);
        starts.extend(memchr::memchr_iter(b',', text).map(|i| i + 1));
        SplitLine { text, starts }
    }
}

impl Fields for SplitLine<'_> {
    fn count(&self) -> usize {
        self.starts.len()
    }
    fn field(&self, i: usize) -> &[u8] {
        let end = self
            .starts
            .get(i + 1)
            .map_or(self.text.len(), |next| next - 1);
        &self.text[self.starts[i]..end]
    }
}

/// The header, once read.
struct Header {
    names: Vec<String>,
    angle_index: [usize; 4],
    /// The fast path for its data lines.
    plain: PlainRow,
}

/// An evaluation in progress: rows gathered into chunks, each evaluated in parallel and written
/// as one large write.
struct Evaluation<'a, W: ?Sized> {
    source: &'a Path,
    output: &'a mut W,
    request: &'a EvalRequest,
    model: &'a (dyn Fn(&[Angles], &mut [f64]) + Sync),
    unit: AngleUnit,
    /// What the rows say about their unit, when degrees were assumed (`--angles` absent, no
    /// unit line).
    radians: Option<RadiansEvidence>,
    header: Option<Header>,
    n_channels: usize,
    chunk_rows: usize,
    angles: Vec<Angles>,
    /// Each row's input text as written out: where it lies in the block being read, or, for
    /// rows the csv crate read, in `joined` (fields comma-joined, quoted where needed).
    spans: Vec<Range<usize>>,
    joined: Vec<u8>,
    values: Vec<f64>,
    out: Vec<u8>,
    rows: u64,
}

impl<'a, W: Write + ?Sized> Evaluation<'a, W> {
    fn new(
        source: &'a Path,
        output: &'a mut W,
        request: &'a EvalRequest,
        model: &'a (dyn Fn(&[Angles], &mut [f64]) + Sync),
    ) -> Self {
        let n_channels = request.model.n_channels().max(1);
        let chunk_rows = (CHUNK_VALUES / n_channels).clamp(1, CHUNK_ROWS);
        Evaluation {
            source,
            output,
            request,
            model,
            unit: request.angles.unwrap_or(AngleUnit::Deg),
            radians: request.angles.is_none().then(RadiansEvidence::default),
            header: None,
            n_channels,
            chunk_rows,
            angles: Vec::with_capacity(chunk_rows),
            spans: Vec::with_capacity(chunk_rows),
            joined: Vec::new(),
            values: Vec::with_capacity(chunk_rows * n_channels),
            out: Vec::new(),
            rows: 0,
        }
    }

    /// Take one record at `line`: the header first, then data rows. `raw` is where the line
    /// lies in the block being read when it can be copied to the output as it is.
    fn record(&mut self, line: u64, fields: &impl Fields, raw: Option<Range<usize>>) -> Result<()> {
        let Some(header) = &self.header else {
            return self.header(line, fields);
        };
        let expected = header.names.len();
        if fields.count() != expected {
            return Err(Error::input(
                self.source,
                line,
                fields.count() as u64 + 1,
                format!(
                    "this row has {} fields but the header has {expected}",
                    fields.count()
                ),
            ));
        }
        let values = parse_angles(
            self.source,
            line,
            fields,
            &header.angle_index,
            &header.names,
            self.unit,
        )?;
        self.angles.push(to_angles(values, self.unit));
        let span = raw.unwrap_or_else(|| {
            let start = self.joined.len();
            for i in 0..fields.count() {
                if i > 0 {
                    self.joined.push(b',');
                }
                push_csv_field(&mut self.joined, fields.field(i));
            }
            start..self.joined.len()
        });
        self.spans.push(span);
        Ok(())
    }

    /// Take a data row the fast path read: its angles (in the file's unit) and where its text
    /// lies in the block.
    fn data_row(&mut self, values: [f64; 4], raw: Range<usize>) {
        self.angles.push(to_angles(values, self.unit));
        self.spans.push(raw);
    }

    /// Evaluate and write the rows taken once they fill a chunk (`block`: see
    /// [`Self::flush_chunk`]).
    fn flush_if_full(&mut self, block: Option<&[u8]>) -> Result<()> {
        if self.angles.len() < self.chunk_rows {
            return Ok(());
        }
        self.flush_chunk(block)
    }

    /// Read the header at `line`, check it and write the output's header.
    fn header(&mut self, line: u64, fields: &impl Fields) -> Result<()> {
        let names: Vec<String> = (0..fields.count())
            .map(|i| {
                let name = String::from_utf8_lossy(fields.field(i));
                // A UTF-8 byte-order mark may precede the first header.
                let name = if i == 0 {
                    name.trim_start_matches('\u{feff}')
                } else {
                    &name
                };
                name.trim().to_string()
            })
            .collect();
        if let Some(k) = repeated_column(names.iter().map(String::as_str)) {
            return Err(Error::input(
                self.source,
                line,
                1 + k as u64,
                repeated_column_message(&names[k]),
            ));
        }
        let angle_index = locate_angle_columns(self.source, line, &names)?;
        for name in &self.request.output_columns {
            if let Some(k) = names.iter().position(|h| h == name) {
                return Err(Error::input(
                    self.source,
                    line,
                    1 + k as u64,
                    format!(
                        "the input already has a column `{name}`, which eval would append; rename it"
                    ),
                ));
            }
        }
        // Radians say so in the output too, or it would read back as degrees.
        if self.unit == AngleUnit::Rad {
            self.out
                .extend_from_slice(format!("{}\n", UnitLine(AngleUnit::Rad)).as_bytes());
        }
        let all = names
            .iter()
            .map(String::as_str)
            .chain(self.request.output_columns.iter().map(String::as_str));
        for (i, name) in all.enumerate() {
            if i > 0 {
                self.out.push(b',');
            }
            push_csv_field(&mut self.out, name.as_bytes());
        }
        self.out.push(b'\n');
        let plain = PlainRow::new(names.len(), &angle_index, self.unit);
        self.header = Some(Header {
            names,
            angle_index,
            plain,
        });
        Ok(())
    }

    /// Evaluate the gathered rows and write them: rows read from a block have their text in
    /// `block`, rows the csv crate read (`block` is `None`) in `joined`.
    fn flush_chunk(&mut self, block: Option<&[u8]>) -> Result<()> {
        if self.angles.is_empty() {
            return Ok(());
        }
        if let Some(evidence) = &mut self.radians {
            // Degrees beyond ±π settle it at the first such row: the rest costs one test a chunk.
            for a in &self.angles {
                if evidence.settled() {
                    break;
                }
                evidence.add([a.theta_i, a.phi_i, a.theta_r, a.phi_r]);
            }
        }
        let n_channels = self.n_channels;
        let model = self.model;
        self.values.clear();
        self.values.resize(self.angles.len() * n_channels, 0.0);
        // Chunks of rows share the Chiang width integral per exit direction. With one thread
        // the batches run here, not on the pool's only worker while this thread sleeps (two
        // wake-ups a chunk); the batches are the same, so are the values.
        let batch = |(out, a): (&mut [f64], &[Angles])| model(a, out);
        let (values, angles) = (&mut self.values, &self.angles);
        let width = n_channels * EVAL_BATCH;
        if rayon::current_num_threads() == 1 {
            let batches = values.chunks_mut(width).zip(angles.chunks(EVAL_BATCH));
            batches.for_each(batch);
        } else {
            let batches = values
                .par_chunks_mut(width)
                .zip(angles.par_chunks(EVAL_BATCH));
            batches.for_each(batch);
        }
        let text = block.unwrap_or(&self.joined);
        if let Some(j) = self.values.iter().position(|v| !v.is_finite()) {
            let row = &text[self.spans[j / n_channels].clone()];
            return Err(non_finite_error(
                self.source,
                row,
                self.values[j],
                self.request,
            ));
        }
        // Values are appended as shortest round-trip text, all into one buffer.
        let mut digits = zmij::Buffer::new();
        // The longest value is 24 bytes.
        let text_bytes: usize = self.spans.iter().map(|s| s.len()).sum();
        self.out
            .reserve(text_bytes + self.values.len() * 25 + self.angles.len());
        for (span, vals) in self.spans.iter().zip(self.values.chunks(n_channels)) {
            self.out.extend_from_slice(&text[span.clone()]);
            for &v in vals {
                self.out.push(b',');
                push_shortest(&mut self.out, &mut digits, v);
            }
            self.out.push(b'\n');
        }
        self.rows += self.angles.len() as u64;
        self.angles.clear();
        self.spans.clear();
        self.joined.clear();
        self.write_out()
    }

    fn write_out(&mut self) -> Result<()> {
        self.output
            .write_all(&self.out)
            .map_err(|e| Error::io(OUTPUT_NAME, e))?;
        self.out.clear();
        Ok(())
    }

    /// Evaluate and write what is left; the summary.
    fn finish(mut self) -> Result<EvalSummary> {
        // Rows read from blocks were written at each block's end.
        self.flush_chunk(None)?;
        self.write_out()?;
        self.output.flush().map_err(|e| Error::io(OUTPUT_NAME, e))?;
        let warnings = self.radians.and_then(|e| e.warning()).into_iter().collect();
        Ok(EvalSummary {
            rows: self.rows,
            warnings,
        })
    }
}

/// Append `field` as the csv crate writes it: in quotes (inner quotes doubled) when it holds a
/// comma, a quote or a line break, else as it is.
fn push_csv_field(out: &mut Vec<u8>, field: &[u8]) {
    if field
        .iter()
        .any(|&b| matches!(b, b',' | b'"' | b'\n' | b'\r'))
    {
        out.push(b'"');
        for &b in field {
            if b == b'"' {
                out.push(b'"');
            }
            out.push(b);
        }
        out.push(b'"');
    } else {
        out.extend_from_slice(field);
    }
}

/// A non-finite S is an error naming the row (its fields as written out) and the parameters,
/// never a `NaN` in the output.
fn non_finite_error(source: &Path, row: &[u8], value: f64, request: &EvalRequest) -> Error {
    Error::Other(format!(
        "{}: the model gives S = {value} for the row `{}` with the parameters {}: use \
         parameters the model can evaluate",
        source.display(),
        String::from_utf8_lossy(row),
        request.params.json_line()
    ))
}
