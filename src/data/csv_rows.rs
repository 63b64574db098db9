//! The data rows of a header CSV: read in large blocks of whole lines, each block parsed in
//! parallel pieces and fed to [`Rows`] in file order (while the next block is parsed), so the
//! dataset, the report and the first error are exactly those of reading line by line. From the
//! first block holding a quote or a lone carriage return on, the csv crate reads the rest (see
//! [`super::records`]).

use std::io::Read;
use std::path::Path;

use rayon::prelude::*;

use super::lines::{csv_error, quote_across_lines_error, read_error, LineCounter};
use super::options::{LoadOptions, Role};
use super::records::{count_lines, for_each_line, needs_csv_parser, split_at_lines, Blocks};
use super::rows::{Cell, RowCells, Rows};
use crate::error::{Error, Result};

/// The columns of a CSV file, from its header.
#[derive(Debug)]
pub(super) struct Columns {
    pub roles: Vec<Role>,
    pub channels: Vec<String>,
    pub has_sigma: bool,
    pub has_weight: bool,
    pub ignored: Vec<String>,
}

/// Parse one cell: `None` when empty or the missing token, else a number (NaN/inf/1e999 parse
/// to non-finite values, which validation rejects). Anything else is an input error.
pub(crate) fn parse_cell(
    bytes: &[u8],
    missing: &str,
    path: &Path,
    line: u64,
    column: u64,
    name: &str,
) -> Result<Cell> {
    let trimmed = bytes.trim_ascii();
    if trimmed.is_empty() || trimmed == missing.as_bytes() {
        return Ok(None);
    }
    // The fast parser reads exactly what `str::parse` reads; the text is only decoded for the
    // error message.
    if let Some(value) = super::records::parse_f64(trimmed) {
        return Ok(Some(value));
    }
    let text = std::str::from_utf8(trimmed).map_err(|_| {
        Error::input(
            path,
            line,
            column,
            format!("column `{name}` is not UTF-8 text (binary data in the file?)"),
        )
    })?;
    Err(Error::input(
        path,
        line,
        column,
        format!(
            "column `{name}`: `{}` is not a number (write `{missing}` or leave the cell \
             empty for a value that was not measured){}",
            text.chars().take(40).collect::<String>(),
            super::records::decimal_comma_hint(text)
        ),
    ))
}

/// Where the data rows come from.
pub(super) struct Input<'a> {
    pub path: &'a Path,
    pub header: &'a csv::StringRecord,
    pub header_line: u64,
    pub file_len: u64,
    pub delimiter: u8,
}

/// Bytes read per block: large enough to keep both cores busy (32 pieces of 32 kB), small
/// enough that the block and its parsed cells are a small part of memory (a 212 MB file holds
/// 80 MB of numbers). The block buffer and the pieces are reused block after block, so only
/// one block's worth of their pages is ever faulted in: a 12 MB file (100k rows) took 3k more
/// page faults with 8 MB blocks.
const BLOCK_BYTES: usize = 1 << 20;

/// Pieces a block is split into for the parallel parse (more than cores, to balance the load).
const PIECES_PER_BLOCK: usize = 32;

/// Rows after which the bytes per row so far size the reservation for the rest of the file.
const SIZE_SAMPLE_ROWS: u64 = 4096;

/// Stream the data rows after the header (`prefix`: bytes already read past it) into `rows`.
pub(super) fn read_rows(
    reader: impl Read,
    prefix: &[u8],
    input: &Input,
    options: &LoadOptions,
    cols: &Columns,
    rows: &mut Rows,
) -> Result<()> {
    let path = input.path;
    let mut blocks = Blocks::new(reader, prefix, BLOCK_BYTES);
    // Lines of the file before the next piece to feed (pieces count their lines from 1).
    let mut lines_fed = input.header_line;
    // Block k is parsed (in parallel pieces) while block k-1, parsed, is fed to `rows` in file
    // order. The piece buffers are reused block after block: fresh ones cost a page fault per
    // page.
    let mut parsing: Vec<Piece> = Vec::new();
    let mut parsed: Vec<Piece> = Vec::new();
    let mut parsed_count = 0;
    let mut parsed_bytes = 0u64;
    let mut fed_bytes = 0u64;
    let mut reserved = false;
    let feed = |pieces: &mut [Piece], rows: &mut Rows, lines_fed: &mut u64| -> Result<()> {
        pieces.iter_mut().try_for_each(|piece| {
            piece.feed(cols, rows, *lines_fed)?;
            *lines_fed += piece.line_count;
            Ok(())
        })
    };
    loop {
        let Some(block) = blocks.next_block().map_err(|e| read_error(path, e))? else {
            return feed(&mut parsed[..parsed_count], rows, &mut lines_fed);
        };
        if needs_csv_parser(block) {
            feed(&mut parsed[..parsed_count], rows, &mut lines_fed)?;
            return read_rows_csv(
                blocks.rest_from_block(),
                lines_fed,
                input,
                options,
                cols,
                rows,
            );
        }
        let pieces = split_at_lines(block, PIECES_PER_BLOCK);
        if parsing.len() < pieces.len() {
            parsing.resize_with(pieces.len(), Piece::default);
        }
        let ((), fed) = rayon::join(
            || {
                pieces
                    .par_iter()
                    .zip(parsing.par_iter_mut())
                    .for_each(|(piece, out)| parse_piece(piece, input, options, cols, out))
            },
            || feed(&mut parsed[..parsed_count], rows, &mut lines_fed),
        );
        fed?;
        fed_bytes += parsed_bytes;
        std::mem::swap(&mut parsing, &mut parsed);
        parsed_count = pieces.len();
        parsed_bytes = block.len() as u64;
        if !reserved && rows.rows_read() >= SIZE_SAMPLE_ROWS {
            reserved = true;
            let per_row = fed_bytes / rows.rows_read() + 1;
            let rest = input.file_len.saturating_sub(fed_bytes) / per_row;
            // 10% headroom: row lengths vary a little through a file.
            rows.reserve((rest + rest / 10) as usize);
        }
    }
}

/// The rows of one piece of a block, parsed: the used cells of each row (columns in file order,
/// ignored ones left out), its line counted from 1 at the piece's start (pieces are parsed
/// before the lines ahead of them are counted), and the error that ended the piece early.
#[derive(Default)]
struct Piece {
    cells: Vec<Cell>,
    lines: Vec<u64>,
    error: Option<Error>,
    /// Lines in the piece.
    line_count: u64,
}

impl Piece {
    /// Hand the rows to `rows` in order, then the piece's error; `lines_before`: lines of the
    /// file before the piece.
    fn feed(&mut self, cols: &Columns, rows: &mut Rows, lines_before: u64) -> Result<()> {
        let nc = cols.channels.len();
        let mut radiance: Vec<Cell> = vec![None; nc];
        let mut sigma: Vec<Cell> = vec![None; if cols.has_sigma { nc } else { 0 }];
        let mut weight: Vec<Cell> = vec![None; if cols.has_weight { nc } else { 0 }];
        let used: Vec<Role> = cols
            .roles
            .iter()
            .copied()
            .filter(|r| *r != Role::Ignored)
            .collect();
        if !used.is_empty() {
            for (row, &line) in self.cells.chunks(used.len()).zip(&self.lines) {
                let mut angles: [Cell; 4] = [None; 4];
                let mut cells = RowCells {
                    angles: &mut angles,
                    radiance: &mut radiance,
                    sigma: &mut sigma,
                    weight: &mut weight,
                };
                for (&role, &cell) in used.iter().zip(row) {
                    cells.place(role, cell);
                }
                rows.row(lines_before + line, angles, &radiance, &sigma, &weight);
            }
        }
        match self.error.take() {
            None => Ok(()),
            Some(mut error) => {
                if let Error::Input { line, .. } = &mut error {
                    *line += lines_before;
                }
                Err(error)
            }
        }
    }
}

/// Parse the lines of `piece` into `out` (lines counted from 1 at the piece's start).
fn parse_piece(
    piece: &[u8],
    input: &Input,
    options: &LoadOptions,
    cols: &Columns,
    out: &mut Piece,
) {
    let n_fields = cols.roles.len();
    let used = cols.roles.iter().filter(|r| **r != Role::Ignored).count();
    out.line_count = count_lines(piece);
    out.cells.clear();
    out.lines.clear();
    out.error = None;
    out.cells.reserve(out.line_count as usize * used);
    out.lines.reserve(out.line_count as usize);
    let delimiter = input.delimiter;
    // Delimiter positions of the line: one pass finds the field count and the fields.
    let mut commas: Vec<usize> = Vec::with_capacity(n_fields);
    for_each_line(piece, |index, text| {
        let line = index + 1;
        commas.clear();
        commas.extend(memchr::memchr_iter(delimiter, text));
        let found = commas.len() + 1;
        if found != n_fields {
            // A line of spaces only is blank, not a row.
            if found == 1 && text.iter().all(u8::is_ascii_whitespace) {
                return true;
            }
            out.error = Some(field_count_error(input.path, line, found, n_fields));
            return false;
        }
        let mark = out.cells.len();
        let mut start = 0;
        for (k, role) in cols.roles.iter().enumerate() {
            let end = commas.get(k).copied().unwrap_or(text.len());
            let field = &text[start..end];
            start = end + 1;
            if *role == Role::Ignored {
                continue;
            }
            match parse_cell(
                field,
                &options.missing,
                input.path,
                line,
                k as u64 + 1,
                &input.header[k],
            ) {
                Ok(cell) => out.cells.push(cell),
                Err(e) => {
                    out.cells.truncate(mark);
                    out.error = Some(e);
                    return false;
                }
            }
        }
        out.lines.push(line);
        true
    });
}

/// A row whose field count differs from the header's.
fn field_count_error(path: &Path, line: u64, found: usize, n_fields: usize) -> Error {
    Error::input(
        path,
        line,
        (found.min(n_fields) + 1) as u64,
        format!(
            "expected {n_fields} fields as in the header, found {found} \
             (a truncated or mis-delimited row?)"
        ),
    )
}

/// The rows from `reader` on (after `line_base` lines of the file) through the csv crate, for
/// input with quotes or lone carriage returns.
fn read_rows_csv(
    reader: impl Read,
    line_base: u64,
    input: &Input,
    options: &LoadOptions,
    cols: &Columns,
    rows: &mut Rows,
) -> Result<()> {
    let Input {
        path,
        header,
        file_len,
        ..
    } = *input;
    let (reader, newlines) = LineCounter::wrap(reader);
    let mut csv = csv::ReaderBuilder::new()
        .delimiter(input.delimiter)
        .has_headers(false)
        .flexible(true)
        .comment(Some(b'#'))
        .buffer_capacity(1 << 16)
        .from_reader(reader);
    let nc = cols.channels.len();
    let mut record = csv::ByteRecord::new();
    let mut radiance: Vec<Cell> = vec![None; nc];
    let mut sigma: Vec<Cell> = vec![None; if cols.has_sigma { nc } else { 0 }];
    let mut weight: Vec<Cell> = vec![None; if cols.has_weight { nc } else { 0 }];
    let n_fields = cols.roles.len();
    let rows_before = rows.rows_read();
    loop {
        let more = csv.read_byte_record(&mut record).map_err(|e| {
            let byte = e.position().map_or(0, |p| p.byte());
            let line = line_base + 1 + newlines.borrow_mut().count_before(byte);
            csv_error(path, e, line)
        })?;
        if !more {
            return Ok(());
        }
        // The record ends just before csv's position; its last byte is on the record's line.
        let end = csv.position().byte();
        let line = line_base + 1 + newlines.borrow_mut().count_before(end.saturating_sub(1));
        if record.len() != n_fields {
            // A line of spaces only is blank, not a row.
            if record.len() == 1 && record[0].iter().all(u8::is_ascii_whitespace) {
                continue;
            }
            return Err(quote_across_lines_error(path, &record, line, n_fields)
                .unwrap_or_else(|| field_count_error(path, line, record.len(), n_fields)));
        }
        let mut angles: [Cell; 4] = [None; 4];
        for (k, (role, field)) in cols.roles.iter().zip(record.iter()).enumerate() {
            if *role == Role::Ignored {
                continue;
            }
            let cell = parse_cell(
                field,
                &options.missing,
                path,
                line,
                k as u64 + 1,
                &header[k],
            )?;
            let mut cells = RowCells {
                angles: &mut angles,
                radiance: &mut radiance,
                sigma: &mut sigma,
                weight: &mut weight,
            };
            cells.place(*role, cell);
        }
        rows.row(line, angles, &radiance, &sigma, &weight);
        if rows.rows_read() == rows_before + SIZE_SAMPLE_ROWS {
            let per_row = end / SIZE_SAMPLE_ROWS + 1;
            let rest = file_len.saturating_sub(end) / per_row;
            rows.reserve((rest + rest / 10) as usize);
        }
    }
}
