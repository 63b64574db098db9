//! The fast path of an eval data line: each angle field parsed where it lies, the field ends and
//! the line end found by the parse itself, with no splitting of the line first. It takes only
//! lines the general path reads to the same values; any other line (a comment, a blank, spaces
//! around a number, a wrong field count, a bad or out-of-range θ or φ) is left to the general
//! path, which reads it as before and names the error.

use crate::data::records::parse_f64_prefix;
use crate::data::AngleUnit;

/// How a data line maps to the angles, from the header.
pub(super) struct PlainRow {
    /// Per header field: the angle it holds (`0..4`, in `ANGLE_COLUMNS` order) or `None`.
    slots: Vec<Option<usize>>,
    /// |θ| must stay below this, in the file's unit.
    theta_limit: f64,
    /// |φ| must not exceed this, in the file's unit.
    phi_limit: f64,
}

/// A line the fast path read.
pub(super) struct PlainLine {
    /// θ_i, φ_i, θ_r, φ_r in the file's unit, finite and in range.
    pub values: [f64; 4],
    /// End of the line's text (before its `\n` or `\r\n`).
    pub end: usize,
    /// Start of the next line.
    pub next: usize,
}

impl PlainRow {
    /// For a header of `n_fields` fields with the angles at `angle_index`, in `unit`.
    pub(super) fn new(n_fields: usize, angle_index: &[usize; 4], unit: AngleUnit) -> Self {
        let mut slots = vec![None; n_fields];
        for (angle, &field) in angle_index.iter().enumerate() {
            slots[field] = Some(angle);
        }
        PlainRow {
            slots,
            theta_limit: unit.theta_limit(),
            phi_limit: unit.phi_limit(),
        }
    }

    /// Read the line at `block[start..]` (`block`: whole lines with no quote and no lone `\r`,
    /// see `needs_csv_parser`), or `None` for the general path to read it.
    pub(super) fn read(&self, block: &[u8], start: usize) -> Option<PlainLine> {
        if block.get(start) == Some(&b'#') {
            return None;
        }
        let mut values = [0.0f64; 4];
        let mut pos = start;
        let last = self.slots.len().checked_sub(1)?;
        for (k, slot) in self.slots.iter().enumerate() {
            let rest = &block[pos..];
            match *slot {
                // The field is this number only if a delimiter or the line end follows it
                // (checked next): then `parse_f64(field)` is the same value.
                Some(angle) => {
                    let (value, len) = parse_f64_prefix(rest)?;
                    values[angle] = value;
                    pos += len;
                }
                None => pos += memchr::memchr2(b',', b'\n', rest).unwrap_or(rest.len()),
            }
            if k < last {
                if block.get(pos) != Some(&b',') {
                    return None;
                }
                pos += 1;
            }
        }
        let (end, next) = match block.get(pos) {
            None => (pos, pos),
            // A last field that is not an angle runs to the `\n`; its line ends before a `\r`.
            Some(b'\n') if pos > start && block[pos - 1] == b'\r' => (pos - 1, pos + 1),
            Some(b'\n') => (pos, pos + 1),
            Some(b'\r') if block.get(pos + 1) == Some(&b'\n') => (pos, pos + 2),
            Some(_) => return None,
        };
        let in_range = values.iter().all(|v| v.is_finite())
            && values[0].abs() < self.theta_limit
            && values[2].abs() < self.theta_limit
            && values[1].abs() <= self.phi_limit
            && values[3].abs() <= self.phi_limit;
        in_range.then_some(PlainLine { values, end, next })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::records::{needs_csv_parser, parse_f64};

    /// The general path's reading of one line: fields split at every comma, the angles trimmed
    /// and parsed, `None` where it would report an error.
    fn general(line: &[u8], row: &PlainRow) -> Option<[f64; 4]> {
        let fields: Vec<&[u8]> = line.split(|&b| b == b',').collect();
        if fields.len() != row.slots.len() || line.first() == Some(&b'#') {
            return None;
        }
        let mut values = [0.0; 4];
        for (field, slot) in fields.iter().zip(&row.slots) {
            if let Some(angle) = *slot {
                let v = parse_f64(field.trim_ascii())?;
                let theta = angle % 2 == 0;
                let out_of_range = if theta {
                    v.abs() >= row.theta_limit
                } else {
                    v.abs() > row.phi_limit
                };
                if !v.is_finite() || out_of_range {
                    return None;
                }
                values[angle] = v;
            }
        }
        Some(values)
    }

    /// Every line the fast path reads, it reads as the general path does (text, values, where
    /// the next line starts); the lines it leaves are the general path's errors, comments, or
    /// lines with spaces around a number.
    #[test]
    fn the_fast_path_reads_what_the_general_path_reads_or_leaves_the_line() {
        let layouts = [
            PlainRow::new(4, &[0, 1, 2, 3], AngleUnit::Deg),
            PlainRow::new(6, &[5, 1, 3, 0], AngleUnit::Deg),
        ];
        let lines: &[&[u8]] = &[
            b"1,2,3,4",
            b"-1.5,+2e1,3.25E-1,.5",
            b"1.,2,3,4",
            b"1,2,3",
            b"1,2,3,4,",
            b"1,2,3,4,5",
            b",2,3,4",
            b"1,,3,4",
            b"1,2,3,",
            b" 1,2,3,4",
            b"1 ,2,3,4",
            b"1,2,3,4 ",
            b"#1,2,3,4",
            b"",
            b"   ",
            b"1e,2,3,4",
            b"1e+,2,3,4",
            b"1x,2,3,4",
            b"inf,2,3,4",
            b"1,nan,3,4",
            b"1,infinity,3,4",
            b"90,0,0,0",
            b"-89.99999999999999,0,89.9,0",
            b"0,0,90.0,0",
            b"0,720,0,-720",
            b"0,720.0000000001,0,0",
            b"0,0,0,-800",
            b"1,2,3,4\r",
            b"a,b,c,d,e,f",
            b"1,2,x,3,y,4",
            b"1,2,,3,,4",
            b"4,2,x,3,y,1",
            b"4,2,x,3,y,1,",
            b"4,2,x,3,y",
            b"4,2,x,3,y,1e400",
            b"0x1,2,3,4",
            b"1_0,2,3,4",
            b"4,2,x,3,y,z",
            b"4,2,x,3,y\r",
            b"1,2,3,4\r\r",
        ];
        for row in &layouts {
            for &line in lines {
                for ending in [&b"\n"[..], b"\r\n", b""] {
                    let full = [line, ending].concat();
                    let block = [&full[..], b"9,9,9,9\n"].concat();
                    let block = if ending.is_empty() { &full } else { &block };
                    if needs_csv_parser(block) {
                        continue;
                    }
                    // The line as `for_each_line` hands it out.
                    let text = full.strip_suffix(b"\n").unwrap_or(&full);
                    let text = text.strip_suffix(b"\r").unwrap_or(text);
                    let shown = String::from_utf8_lossy(&full);
                    let expected = general(text, row);
                    match row.read(block, 0) {
                        Some(read) => {
                            assert_eq!(Some(read.values), expected, "`{shown}`");
                            assert_eq!(&block[..read.end], text, "`{shown}`");
                            assert_eq!(read.next, full.len(), "`{shown}`");
                        }
                        None => assert!(
                            expected.is_none() || text.contains(&b' '),
                            "`{shown}` was left though it reads as {expected:?}"
                        ),
                    }
                }
            }
        }
        // Plain lines do take the fast path.
        assert!(layouts[0].read(b"1,2,3,4\n", 0).is_some());
        assert!(layouts[0].read(b"-1.5,+2e1,3.25E-1,.5\r\n", 0).is_some());
        assert!(layouts[1].read(b"4,2,x,3,y,1", 0).is_some());
    }
}
