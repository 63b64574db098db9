//! The angle unit of a CSV or scan file: the `# angles: deg|rad` line (any case, anywhere
//! before the first data row; two that disagree are an error), `--angles`, and the warning when
//! degrees were assumed but every angle lies within ±π.

use std::path::Path;

use super::lines::next_line;
use super::{AngleUnit, Dataset};
use crate::error::{Error, Result};

/// The unit a `# angles: …` comment states, if the comment is a unit line.
fn directive(comment: &str, path: &Path, line: u64) -> Result<Option<AngleUnit>> {
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

/// The unit line of `path` and its line number: comment lines are read up to the first data
/// row (after `header_lines` non-comment lines: 1 for a header CSV, 0 for a scan). Two unit
/// lines that disagree are an error naming both.
pub(crate) fn file_directive(path: &Path, header_lines: u64) -> Result<Option<(AngleUnit, u64)>> {
    let mut reader = super::open(path)?;
    let mut buf = Vec::new();
    let (mut line, mut headers_left) = (0u64, header_lines);
    let mut found: Option<(AngleUnit, u64)> = None;
    while next_line(&mut reader, &mut buf, path)? {
        line += 1;
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
        if let Some(unit) = directive(t, path, line)? {
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
    let columns = [&ds.theta_i, &ds.phi_i, &ds.theta_r, &ds.phi_r];
    // Stored as radians of the degrees read: compare the degrees.
    let limit = std::f64::consts::PI.to_radians() * (1.0 + 1e-12);
    let within = columns.iter().all(|c| c.iter().all(|x| x.abs() <= limit));
    let varied = columns.iter().any(|c| c.iter().any(|&x| x != c[0]));
    let nonzero = columns.iter().any(|c| c.iter().any(|&x| x != 0.0));
    (ds.len() >= 2 && within && varied && nonzero).then(|| {
        format!(
            "{RADIANS_WARNING} (every angle lies within ±3.1416 while the unit is degrees; \
             add a `# angles: deg` line or pass --angles deg if they really are degrees)"
        )
    })
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
            assert_eq!(directive(text, p, 1).unwrap(), unit, "{text}");
        }
        assert!(directive("# angles: gradians", p, 3)
            .unwrap_err()
            .to_string()
            .contains("gradians"));
    }
}
