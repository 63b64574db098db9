//! The fast path for reading delimited text: whole-line blocks read in large pieces, lines split
//! at the delimiter by hand, numbers parsed from bytes. It owns the rule for when that path gives
//! exactly what the csv crate would: no quote character and no lone carriage return in the block.
//! Readers switch to the csv crate for the rest of the input at the first block that breaks it.

use std::io::Read;

/// Whether `block` (whole lines) holds something only the csv crate reads right: a quote (quoted
/// fields may hold delimiters and line breaks) or a carriage return not followed by a line feed
/// (csv ends a record there; here it would be part of a field).
pub(crate) fn needs_csv_parser(block: &[u8]) -> bool {
    // One pass for both bytes: with `\n` line ends neither occurs, and the block is read once.
    memchr::memchr2_iter(b'"', b'\r', block)
        .any(|i| block[i] == b'"' || block.get(i + 1) != Some(&b'\n'))
}

/// A field's number from its bytes, exactly as `str::parse::<f64>` would read them (the same
/// grammar, correctly rounded, so bit-for-bit the same value; tested below on hard cases);
/// `None` where `parse` fails.
pub(crate) fn parse_f64(bytes: &[u8]) -> Option<f64> {
    fast_float2::parse::<f64, _>(bytes).ok()
}

/// The number at the start of `bytes` and how many bytes it takes; `None` when `bytes` does not
/// start with one. [`parse_f64`] is this parse plus the check that it took every byte, so when
/// the number ends where its field does, the value is the field's `parse_f64` value.
pub(crate) fn parse_f64_prefix(bytes: &[u8]) -> Option<(f64, usize)> {
    fast_float2::parse_partial::<f64, _>(bytes).ok()
}

/// For a cell that is not a number: when it reads as one with its single comma taken for a
/// decimal point (`1,5` from a semicolon table saved in a German or French locale), the hint
/// that says so, to append to the error.
pub(crate) fn decimal_comma_hint(text: &str) -> String {
    let fixed = text.replacen(',', ".", 1);
    let one_comma = text.matches(',').count() == 1;
    if one_comma && parse_f64(fixed.as_bytes()).is_some() {
        format!(
            "; `{text}` looks like a decimal comma: write `{fixed}` (save the table with a \
             decimal point)"
        )
    } else {
        String::new()
    }
}

/// The lines of `block` as csv reads records from quote-free text: `f(line index, line)` for
/// every line that is neither empty nor a `#` comment, the line without its `\n` or `\r\n`; the
/// index counts every line of the block from 0. Returns false as soon as `f` does.
pub(crate) fn for_each_line(block: &[u8], mut f: impl FnMut(u64, &[u8]) -> bool) -> bool {
    let mut start = 0;
    let mut index = 0u64;
    let mut visit = |line: &[u8], index: u64| {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        line.is_empty() || line[0] == b'#' || f(index, line)
    };
    for end in memchr::memchr_iter(b'\n', block) {
        if !visit(&block[start..end], index) {
            return false;
        }
        start = end + 1;
        index += 1;
    }
    start == block.len() || visit(&block[start..], index)
}

/// Number of lines in `block` (a last line without its `\n` counts).
pub(crate) fn count_lines(block: &[u8]) -> u64 {
    let newlines = memchr::memchr_iter(b'\n', block).count() as u64;
    newlines + u64::from(block.last().is_some_and(|&b| b != b'\n'))
}

/// Split `block` (whole lines) into about `pieces` parts, each ending at a line end.
pub(crate) fn split_at_lines(block: &[u8], pieces: usize) -> Vec<&[u8]> {
    let target = block.len() / pieces.max(1) + 1;
    let mut parts = Vec::with_capacity(pieces + 1);
    let mut rest = block;
    while !rest.is_empty() {
        let cut = if rest.len() <= target {
            rest.len()
        } else {
            memchr::memchr(b'\n', &rest[target..]).map_or(rest.len(), |i| target + i + 1)
        };
        let (part, tail) = rest.split_at(cut);
        parts.push(part);
        rest = tail;
    }
    parts
}

/// A reader handing out its input in blocks of whole lines (the last block may end without a
/// line break), so lines can be split without the csv crate's byte-by-byte state machine.
pub(crate) struct Blocks<R> {
    inner: R,
    /// Read bytes are `buf[..filled]`; the buffer keeps its length (zeroed once, not per block).
    buf: Vec<u8>,
    filled: usize,
    /// `buf[..block_end]` is the current block; the rest is the start of the next line.
    block_end: usize,
    /// Bytes read per block (more when one line is longer).
    size: usize,
    eof: bool,
    /// A read error met after complete lines: reported once those lines are handed out, as a
    /// reader going line by line would.
    pending: Option<std::io::Error>,
}

impl<R: Read> Blocks<R> {
    /// Blocks of about `size` bytes from `inner`, after `prefix` (bytes already read from it).
    pub(crate) fn new(inner: R, prefix: &[u8], size: usize) -> Self {
        Blocks {
            inner,
            buf: prefix.to_vec(),
            filled: prefix.len(),
            block_end: 0,
            size: size.max(1),
            eof: false,
            pending: None,
        }
    }

    /// Read until `want` bytes are held or the input ends.
    fn fill_to(&mut self, want: usize) -> std::io::Result<()> {
        if self.buf.len() < want {
            self.buf.resize(want, 0);
        }
        while !self.eof && self.filled < want {
            match self.inner.read(&mut self.buf[self.filled..want]) {
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
                Ok(n) => {
                    self.filled += n;
                    self.eof = n == 0;
                }
            }
        }
        Ok(())
    }

    /// Read the next block; `None` at the end of the input.
    pub(crate) fn next_block(&mut self) -> std::io::Result<Option<&[u8]>> {
        self.buf.copy_within(self.block_end..self.filled, 0);
        self.filled -= self.block_end;
        self.block_end = 0;
        if let Some(e) = self.pending.take() {
            return Err(e);
        }
        let mut want = self.size;
        loop {
            if let Err(e) = self.fill_to(want) {
                match memchr::memrchr(b'\n', &self.buf[..self.filled]) {
                    Some(last) => {
                        self.pending = Some(e);
                        self.block_end = last + 1;
                        break;
                    }
                    None => return Err(e),
                }
            }
            if self.eof {
                self.block_end = self.filled;
                break;
            }
            match memchr::memrchr(b'\n', &self.buf[..self.filled]) {
                Some(last) => {
                    self.block_end = last + 1;
                    break;
                }
                // A line longer than the block: read on (the TextGuard bounds line length).
                None => want = self.filled + self.size,
            }
        }
        Ok((self.block_end > 0).then(|| &self.buf[..self.block_end]))
    }

    /// The input from the start of the current block on (its bytes already read, then the rest
    /// of the stream, or the read error met after them), for reading on with the csv crate.
    pub(crate) fn rest_from_block(mut self) -> Rest<R> {
        self.buf.truncate(self.filled);
        Rest {
            read: std::io::Cursor::new(self.buf),
            pending: self.pending,
            inner: self.inner,
        }
    }
}

/// What [`Blocks::rest_from_block`] gives: bytes already read, then the rest of the input.
pub(crate) struct Rest<R> {
    read: std::io::Cursor<Vec<u8>>,
    pending: Option<std::io::Error>,
    inner: R,
}

impl<R: Read> Read for Rest<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.read.read(buf)?;
        if n > 0 || buf.is_empty() {
            return Ok(n);
        }
        match self.pending.take() {
            Some(e) => Err(e),
            None => self.inner.read(buf),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quotes_and_lone_carriage_returns_need_the_csv_parser() {
        assert!(!needs_csv_parser(b"1,2\r\n3,4\n"));
        assert!(needs_csv_parser(b"1,\"2\"\n"));
        assert!(needs_csv_parser(b"1,2\r3,4\n"));
        assert!(needs_csv_parser(b"1,2\r"));
    }

    #[test]
    fn lines_skip_blanks_and_comments_and_keep_their_index() {
        let mut seen = Vec::new();
        for_each_line(b"a,b\r\n\n# c\n\r\n d\nlast", |i, l| {
            seen.push((i, l.to_vec()));
            true
        });
        assert_eq!(
            seen,
            vec![
                (0, b"a,b".to_vec()),
                (4, b" d".to_vec()),
                (5, b"last".to_vec())
            ]
        );
        assert_eq!(count_lines(b"a\nb\n"), 2);
        assert_eq!(count_lines(b"a\nb"), 2);
    }

    #[test]
    fn blocks_end_at_line_ends_and_pieces_cover_the_block() {
        let text: Vec<u8> = (0..10_000)
            .flat_map(|i| format!("{i},{}\n", i * 3).into_bytes())
            .collect();
        let mut blocks = Blocks::new(&text[5..], &text[..5], 1 << 16);
        let mut joined = Vec::new();
        while let Some(block) = blocks.next_block().unwrap() {
            assert_eq!(block.last(), Some(&b'\n'));
            let parts = split_at_lines(block, 7);
            assert!(parts.iter().all(|p| p.last() == Some(&b'\n')));
            joined.extend(parts.concat());
        }
        assert_eq!(joined, text);
    }

    /// `parse_f64` against `str::parse::<f64>`: the same accept/reject and the same bits.
    fn agree(text: &str) {
        let fast = parse_f64(text.as_bytes());
        let std = text.parse::<f64>().ok();
        match (fast, std) {
            (Some(a), Some(b)) if a.is_nan() && b.is_nan() => {}
            (Some(a), Some(b)) => assert_eq!(a.to_bits(), b.to_bits(), "`{text}`"),
            (None, None) => {}
            _ => panic!("`{text}`: fast {fast:?}, std {std:?}"),
        }
    }

    #[test]
    fn fast_parser_agrees_with_std_bit_for_bit_on_hard_values() {
        let hard = [
            "0", "-0", "+0", "0.0", "-0.0", "1", "+1", "-1", "1.", ".5", "-.5", "+.5", ".", "-",
            "+", "", " 1", "1 ", "e5", "1e", "1e+", "1e-", "1e5", "1E5", "1e+5", "1e-5", "1.e5",
            ".e5", "1e5.", "1..2", "1.2.3", "--1", "+-1", "0x10", "1_000", "1,5", "١",
            "inf", "-inf", "+inf", "INF", "Infinity", "-infinity", "infin", "infinityx", "nan",
            "NaN", "-nan", "+NaN", "nanx", "in", "na",
            // Halfway and near-halfway cases, subnormals, limits, overflow and underflow.
            "2.2250738585072011e-308", "2.2250738585072012e-308", "4.9406564584124654e-324",
            "2.4703282292062327e-324", "2.4703282292062328e-324", "1e-400", "1e400",
            "1.7976931348623157e308", "1.7976931348623158e308", "1.7976931348623159e308",
            "9007199254740993", "9007199254740992.9999999999999999999", "0.1", "0.2", "0.3",
            "123456789012345678901234567890", "1e-0000000000000000000000001",
            "1e99999999999999999999", "1e-99999999999999999999", "0e99999999999",
            "7.038531e-26", "8.98846567431158e307", "0.000000000000000000000000000000000001",
            "1448997445238699", "179769313486231580793728971405303415079934132710037826936173778980444968292764750946649017977587207096330286416692887910946555547851940402630657488671505820681908902000708383676273854845817711531764475730270069855571366959622842914819860834936475292719074168444365510704342711559699508093042880177904174497791.9999999999999999999999999999999999999999999999999999999999999999999999",
            "2.2204460492503131e-16", "-3.14159265358979323846264338327950288", "6.02214076e23",
            "1.000000000000000111022302462515654042363166809082031250",
            "1.000000000000000111022302462515654042363166809082031251",
            "1.000000000000000111022302462515654042363166809082031249",
        ];
        for text in hard {
            agree(text);
        }
    }

    #[test]
    fn fast_parser_agrees_with_std_on_random_bits_and_digit_strings() {
        // xorshift: deterministic, no dependency.
        let mut h: u64 = 0x2545_F491_4F6C_DD1D;
        let mut next = || {
            h ^= h << 13;
            h ^= h >> 7;
            h ^= h << 17;
            h
        };
        for _ in 0..200_000 {
            let x = f64::from_bits(next());
            // Every float's shortest text, its exponent form and a 17-digit rounding.
            agree(&format!("{x}"));
            agree(&format!("{x:e}"));
            agree(&format!("{x:.16e}"));
            // Random digit strings with a random exponent: many are not shortest texts.
            let digits = next() % 10u64.pow(1 + (next() % 19) as u32);
            let exp = (next() % 700) as i64 - 350;
            agree(&format!("{digits}e{exp}"));
            agree(&format!("0.{digits:019}{}", next() % 1000));
        }
    }
}
