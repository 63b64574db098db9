//! Reading text input line by line, safely: line numbers of CSV records as a person counts them
//! (the csv crate's record positions point before skipped blank and comment lines and drift with
//! CRLF, so readers count newlines here), and a guard that refuses input with no line breaks.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::io::Read;
use std::path::Path;
use std::rc::Rc;

use crate::error::{Error, Result};

/// Offsets of the newlines a reader has passed, so a byte offset can be turned into a line.
/// csv's own record positions point before skipped blank/comment lines (and drift with CRLF),
/// so lines are counted here; the queue only holds newlines still in csv's read-ahead buffer.
#[derive(Default)]
pub(crate) struct Newlines {
    read: u64,
    pending: VecDeque<u64>,
    before: u64,
}

impl Newlines {
    /// Number of newlines strictly before byte offset `byte` (offsets must not decrease).
    pub(crate) fn count_before(&mut self, byte: u64) -> u64 {
        while self.pending.front().is_some_and(|&nl| nl < byte) {
            self.pending.pop_front();
            self.before += 1;
        }
        self.before
    }
}

/// A reader that records where its newlines are.
pub(crate) struct LineCounter<R> {
    inner: R,
    lines: Rc<RefCell<Newlines>>,
}

impl<R: Read> Read for LineCounter<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        let mut lines = self.lines.borrow_mut();
        let start = lines.read;
        for (i, _) in buf[..n].iter().enumerate().filter(|(_, &b)| b == b'\n') {
            lines.pending.push_back(start + i as u64);
        }
        lines.read += n as u64;
        Ok(n)
    }
}

impl<R: Read> LineCounter<R> {
    /// Wrap `inner`; the shared [`Newlines`] answers which line a byte offset is on.
    pub(crate) fn wrap(inner: R) -> (Self, Rc<RefCell<Newlines>>) {
        let lines = Rc::new(RefCell::new(Newlines::default()));
        (
            LineCounter {
                inner,
                lines: Rc::clone(&lines),
            },
            lines,
        )
    }
}

/// Longest line a text input may have. A hairfit table's longest line is its header (about 20
/// bytes per column, so 64 MiB is over three million columns); input with no line break at all
/// (`/dev/zero`, a binary file) is refused here instead of being read into memory whole.
pub(crate) const MAX_LINE_BYTES: u64 = 64 << 20;

/// Why a reader stopped: the input is not line-structured text. Carried inside an
/// `io::Error` so that every reader (csv, scan, JSON, eval) reports it through [`read_error`].
#[derive(Debug)]
pub(crate) struct NotText {
    line: u64,
    message: String,
}

impl std::fmt::Display for NotText {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for NotText {}

/// A reader that refuses input no text table can be: a line longer than [`MAX_LINE_BYTES`], a
/// first line ended by a lone carriage return (a file whose line breaks are CR only, which
/// would otherwise read as one long line: "a header but no samples"), or UTF-16 text or NUL
/// bytes in the first line.
pub(crate) struct TextGuard<R> {
    inner: R,
    /// Line feeds seen so far (the current line is `lf + 1`).
    lf: u64,
    /// Bytes of the current line seen so far.
    in_line: u64,
    /// The previous chunk ended with a carriage return.
    pending_cr: bool,
}

impl<R> TextGuard<R> {
    pub(crate) fn new(inner: R) -> Self {
        TextGuard {
            inner,
            lf: 0,
            in_line: 0,
            pending_cr: false,
        }
    }

    /// The wrapped reader.
    pub(crate) fn get_ref(&self) -> &R {
        &self.inner
    }

    fn refuse(&self, message: String) -> std::io::Error {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            NotText {
                line: self.lf + 1,
                message,
            },
        )
    }

    /// Check the next chunk of input.
    fn check(&mut self, chunk: &[u8]) -> std::io::Result<()> {
        // memchr: this sees every byte of every input, so a byte loop here was 5% of a load.
        let first_newline = memchr::memchr(b'\n', chunk);
        if self.lf == 0 {
            // UTF-16 (Excel's "Unicode text") is refused by name rather than read as a header
            // of NUL-separated letters; NUL bytes anywhere in line 1 (a binary file) alike.
            let line_1 = first_newline.map_or(chunk, |end| &chunk[..end]);
            let at_start = self.in_line == 0;
            let utf16 = chunk.starts_with(b"\xFF\xFE") || chunk.starts_with(b"\xFE\xFF");
            if (at_start && utf16) || memchr::memchr(0, line_1).is_some() {
                return Err(self.refuse(
                    "the file is UTF-16 text (or binary: its first line holds NUL bytes); save \
                     it as UTF-8, e.g. `iconv -f UTF-16 -t UTF-8 IN > OUT`"
                        .into(),
                ));
            }
        }
        if self.lf == 0 {
            // Only the first line is checked for CR-only breaks: later lone CRs are harmless.
            let first_line = first_newline.map_or(chunk, |end| &chunk[..end]);
            let lone_cr = (self.pending_cr && chunk.first().is_some_and(|&b| b != b'\n'))
                || first_line
                    .windows(2)
                    .any(|w| w[0] == b'\r' && w[1] != b'\n');
            if lone_cr {
                return Err(self.refuse(
                    "the line breaks are carriage returns only (an old Mac text file?): \
                     convert them to line feeds, e.g. `tr '\\r' '\\n' < IN > OUT`"
                        .into(),
                ));
            }
            self.pending_cr = chunk.last() == Some(&b'\r');
        }
        let (newlines, tail) = match memchr::memrchr(b'\n', chunk) {
            Some(last) => (
                memchr::memchr_iter(b'\n', chunk).count() as u64,
                (chunk.len() - last - 1) as u64,
            ),
            None => (0, self.in_line + chunk.len() as u64),
        };
        // A line inside one chunk is shorter than the chunk; only the run up to the first
        // newline can continue a long line from earlier chunks.
        let head = first_newline.unwrap_or(chunk.len()) as u64;
        if self.in_line + head > MAX_LINE_BYTES || tail > MAX_LINE_BYTES {
            return Err(self.refuse(format!(
                "line {} is longer than {} with no line break: not a text table \
                 (a binary file or a device?)",
                self.lf + 1,
                crate::error::readable_bytes(MAX_LINE_BYTES)
            )));
        }
        self.lf += newlines;
        self.in_line = tail;
        Ok(())
    }
}

impl<R: Read> Read for TextGuard<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.check(&buf[..n])?;
        Ok(n)
    }
}

/// A read error on `path` as the library's error: input that is not text is an input error at
/// its line, anything else an I/O error on the file.
/// Read the next line (with its `\n`) into `buf`, replacing what it held; `false` at the end.
pub(crate) fn next_line(
    reader: &mut impl std::io::BufRead,
    buf: &mut Vec<u8>,
    path: &Path,
) -> crate::error::Result<bool> {
    buf.clear();
    let n = reader
        .read_until(b'\n', buf)
        .map_err(|e| read_error(path, e))?;
    Ok(n > 0)
}

pub(crate) fn read_error(path: &Path, err: std::io::Error) -> Error {
    if let Some(not_text) = err.get_ref().and_then(|e| e.downcast_ref::<NotText>()) {
        return Error::input(path, not_text.line, 1, not_text.message.clone());
    }
    Error::io(path, err)
}

/// The error for a record read by the csv crate whose field count is wrong because a quoted
/// field runs across line breaks (most often a quote that is never closed, which swallows the
/// rest of the file): it names the line and column where that field starts. `None` when no
/// field holds a line break (the plain field-count error applies). `end_line` is the line the
/// record ends on; the line breaks inside its fields say where it starts (csv's own record
/// position counts the comment lines before it).
pub(crate) fn quote_across_lines_error(
    path: &Path,
    record: &csv::ByteRecord,
    end_line: u64,
    expected: usize,
) -> Option<Error> {
    let field = record.iter().position(|f| f.contains(&b'\n'))?;
    let breaks: usize = record
        .iter()
        .map(|f| memchr::memchr_iter(b'\n', f).count())
        .sum();
    // A quote still open at the end of the input holds the last line's own `\n` too.
    let at_end = record
        .iter()
        .next_back()
        .is_some_and(|f| f.ends_with(b"\n"));
    let start_line = end_line
        .saturating_sub(breaks as u64 - u64::from(at_end))
        .max(1);
    Some(Error::input(
        path,
        start_line,
        field as u64 + 1,
        format!(
            "the quoted field that starts here runs on to line {end_line}, so this row has {} \
             fields where the header has {expected}: a quote that is never closed takes in the \
             lines after it; close the quote on this line (or write the field without it)",
            record.len()
        ),
    ))
}

/// A csv read error at `line` (where the reader stopped) as the library's error, with the column
/// when the csv crate knows it: one conversion for every csv reader (dataset loader and eval).
pub(crate) fn csv_error(path: &Path, err: csv::Error, line: u64) -> Error {
    let column = match err.kind() {
        csv::ErrorKind::UnequalLengths { len, .. } => *len + 1,
        csv::ErrorKind::Utf8 { err, .. } => err.field() as u64 + 1,
        _ => 1,
    };
    let message = match err.kind() {
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => format!("this row has {len} fields but the header has {expected_len}"),
        _ => format!("unreadable CSV: {err}"),
    };
    match err.into_kind() {
        csv::ErrorKind::Io(io) => read_error(path, io),
        _ => Error::input(path, line, column, message),
    }
}

/// Open `path` for buffered reading of text (see [`TextGuard`]).
pub(crate) fn open(path: &Path) -> Result<std::io::BufReader<TextGuard<std::fs::File>>> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    if file.metadata().is_ok_and(|m| m.is_dir()) {
        return Err(Error::Other(format!(
            "{}: is a directory, not a data file",
            path.display()
        )));
    }
    Ok(std::io::BufReader::with_capacity(
        1 << 16,
        TextGuard::new(file),
    ))
}
