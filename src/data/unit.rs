//! The angle unit of a CSV or scan file: the `# angles: deg|rad` line ([`UnitLine`], any case,
//! anywhere before the first data row; two that disagree are an error), `--angles`, and the
//! warning when degrees were assumed but every angle lies within ±π ([`RadiansEvidence`]).

use std::path::Path;

use super::dataset::Dataset;
use super::lines::next_line;
use super::options::AngleUnit;
use crate::error::{Error, Result};

/// The unit line `# angles: deg|rad`: read by [`UnitLine::parse`], written by its `Display`
/// (eval writes it into an output whose angles are radians, so the output reads back right).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct UnitLine(pub AngleUnit);

impl std::fmt::Display for UnitLine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "# angles: {}", name(self.0))
    }
}

impl UnitLine {
    /// The unit a `# angles: …` comment states, if the comment is a unit line.
    fn parse(comment: &str, path: &Path, line: u64) -> Result<Option<AngleUnit>> {
        let body = comment.trim_start_matches('#').trim().to_ascii_lowercase();
        let Some(rest) = body.strip_prefix("angles") else {
            return Ok(None);
        };
        let Some(value) = rest.trim_start().strip_prefix(':') else {
            return Ok(None);
        };
        match value.trim() {
            "deg" | "degree" | "degrees" => Ok(Some(AngleUnit::Deg)),
            "rad" | "radian" | "radians" => Ok(Some(AngleUnit::Rad)),
            other => Err(Error::input(
                path,
                line,
                1,
                format!("unit line `angles: {other}`: write `# angles: deg` or `# angles: rad`"),
            )),
        }
    }
}

/// The unit line of `path` and its line number: comment lines are read up to the first data
/// row (after `header_lines` non-comment lines: 1 for a header CSV, 0 for a scan). Two unit
/// lines that disagree are an error naming both.
pub(crate) fn file_directive(path: &Path, header_lines: u64) -> Result<Option<(AngleUnit, u64)>> {
    directive_in(&mut super::lines::open(path)?, path, header_lines, None)
}

/// Bytes of comment and header lines a stream may hold before its first data row; a stream
/// (a pipe) is read once, so they are kept to be read again.
pub(crate) const STREAM_PREAMBLE_LIMIT: usize = 1 << 24;

/// [`file_directive`] on a stream already open. With `keep`, every line read is appended to it
/// (for a stream that cannot be read twice); more than [`STREAM_PREAMBLE_LIMIT`] bytes kept is an
/// error.
pub(crate) fn directive_in(
    reader: &mut impl std::io::BufRead,
    path: &Path,
    header_lines: u64,
    mut keep: Option<&mut Vec<u8>>,
) -> Result<Option<(AngleUnit, u64)>> {
    let mut buf = Vec::new();
    let (mut line, mut headers_left) = (0u64, header_lines);
    let mut found: Option<(AngleUnit, u64)> = None;
    while next_line(reader, &mut buf, path)? {
        line += 1;
        if let Some(kept) = keep.as_deref_mut() {
            kept.extend_from_slice(&buf);
            if kept.len() > STREAM_PREAMBLE_LIMIT {
                let mib = STREAM_PREAMBLE_LIMIT >> 20;
                let message = if kept.len() > buf.len() {
                    format!(
                        "more than {mib} MiB of comments and headers before the first data row \
                         of a stream; save it to a file and give that file"
                    )
                } else {
                    // The first line alone passes the bound (in the loader's words).
                    format!(
                        "line {line} is longer than {mib} MiB with no line break: not a text \
                         table (a binary file or a device?)"
                    )
                };
                return Err(Error::input(path, line, 1, message));
            }
        }
        let text = String::from_utf8_lossy(&buf);
        let t = text.trim_start_matches('\u{feff}').trim();
        if t.is_empty() {
            continue;
        }
        if !t.starts_with('#') {
            if headers_left == 0 {
                break;
            }
            headers_left -= 1;
            continue;
        }
        if let Some(unit) = UnitLine::parse(t, path, line)? {
            match found {
                Some((earlier, at)) if earlier != unit => {
                    return Err(Error::input(
                        path,
                        line,
                        1,
                        format!(
                            "this unit line says `angles: {}` but line {at} says `angles: {}`: keep one",
                            name(unit),
                            name(earlier)
                        ),
                    ))
                }
                Some(_) => {}
                None => found = Some((unit, line)),
            }
        }
    }
    Ok(found)
}

/// The angle unit: `--angles` only if it agrees with the file's own unit line; degrees when
/// neither says.
pub(crate) fn resolve(
    option: Option<AngleUnit>,
    directive: Option<(AngleUnit, u64)>,
    path: &Path,
) -> Result<AngleUnit> {
    match (option, directive) {
        (Some(o), Some((d, line))) if o != d => Err(Error::input(
            path,
            line,
            1,
            format!(
                "the file says its angles are in {} but --angles {} was given; drop --angles",
                name(d),
                name(o)
            ),
        )),
        (Some(o), _) => Ok(o),
        (None, Some((d, _))) => Ok(d),
        (None, None) => Ok(AngleUnit::Deg),
    }
}

pub(crate) fn name(u: AngleUnit) -> &'static str {
    match u {
        AngleUnit::Deg => "deg",
        AngleUnit::Rad => "rad",
    }
}

/// The warning's text (the verdict's `--strict` turns it into an error).
pub const RADIANS_WARNING: &str = "angles look like radians: pass --angles rad";

/// When degrees were assumed (no unit line, no `--angles`): a warning if every angle of every
/// accepted sample lies within ±π (as degrees, a scan of a few degrees at most — as radians, a
/// whole scan). A dataset of one direction, or all zeros, says nothing.
pub(crate) fn radians_warning(ds: &Dataset) -> Option<String> {
    let mut evidence = RadiansEvidence::default();
    for i in 0..ds.len() {
        if evidence.settled() {
            break;
        }
        evidence.add([ds.theta_i[i], ds.phi_i[i], ds.theta_r[i], ds.phi_r[i]]);
    }
    evidence.warning()
}

/// The rule of [`radians_warning`] taken one row at a time, so a reader that streams (eval)
/// applies it to every row it reads, as the loader does to a whole dataset.
#[derive(Debug, Clone, Default)]
pub(crate) struct RadiansEvidence {
    rows: u64,
    first: [f64; 4],
    /// Some angle lies beyond ±π (as degrees): no warning, whatever follows.
    beyond_pi: bool,
    varied: bool,
    nonzero: bool,
}

impl RadiansEvidence {
    /// Take one row's θ_i, φ_i, θ_r, φ_r (radians of the degrees read).
    pub(crate) fn add(&mut self, angles: [f64; 4]) {
        // Stored as radians of the degrees read: compare the degrees.
        let limit = std::f64::consts::PI.to_radians() * (1.0 + 1e-12);
        if self.beyond_pi || angles.iter().any(|x| x.abs() > limit) {
            self.beyond_pi = true;
            return;
        }
        if self.rows == 0 {
            self.first = angles;
        }
        self.varied |= angles != self.first;
        self.nonzero |= angles.iter().any(|&x| x != 0.0);
        self.rows += 1;
    }

    /// True once no later row can bring a warning (some angle lay beyond ±π).
    pub(crate) fn settled(&self) -> bool {
        self.beyond_pi
    }

    /// The warning, if the rows taken so far look like radians.
    pub(crate) fn warning(&self) -> Option<String> {
        (!self.beyond_pi && self.rows >= 2 && self.varied && self.nonzero).then(|| {
            format!(
                "{RADIANS_WARNING} (every angle lies within ±3.1416 while the unit is degrees; \
                 add a `# angles: deg` line or pass --angles deg if they really are degrees)"
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_lines_are_read_in_any_case_and_spacing() {
        let p = Path::new("f.csv");
        for (text, unit) in [
            ("# angles: rad", Some(AngleUnit::Rad)),
            ("# Angles: RAD", Some(AngleUnit::Rad)),
            ("#ANGLES : Degrees", Some(AngleUnit::Deg)),
            ("# angles in degrees", None),
            ("# a comment", None),
        ] {
            assert_eq!(UnitLine::parse(text, p, 1).unwrap(), unit, "{text}");
        }
        assert!(UnitLine::parse("# angles: gradians", p, 3)
            .unwrap_err()
            .to_string()
            .contains("gradians"));
    }

    /// The line eval writes is the line every reader reads back.
    #[test]
    fn a_written_unit_line_reads_back() {
        for unit in [AngleUnit::Deg, AngleUnit::Rad] {
            let text = UnitLine(unit).to_string();
            assert_eq!(
                UnitLine::parse(&text, Path::new("f.csv"), 1).unwrap(),
                Some(unit)
            );
        }
    }
}
