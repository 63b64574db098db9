//! The four angle columns of an eval input: finding them in the header, reading a row's angles
//! with errors naming line and column, the unit's bounds on θ and φ, and the conversion to model
//! angles.

use std::path::Path;

use super::{Fields, ANGLE_COLUMNS};
use crate::data::records::parse_f64;
use crate::data::AngleUnit;
use crate::error::{Error, Result};
use crate::geometry::Angles;

/// Indices of the four angle columns, or an error naming the missing ones.
pub(super) fn locate_angle_columns(
    source: &Path,
    header_line: u64,
    headers: &[String],
) -> Result<[usize; 4]> {
    let mut index = [0usize; 4];
    let mut missing = Vec::new();
    for (slot, name) in index.iter_mut().zip(ANGLE_COLUMNS) {
        match headers.iter().position(|h| h == name) {
            Some(i) => *slot = i,
            None => missing.push(name),
        }
    }
    if missing.is_empty() {
        return Ok(index);
    }
    // A semicolon or tab table reads as one column: say so, with a conversion.
    let other_delimiter = headers.len() == 1
        && [';', '\t'].iter().any(|&d| {
            ANGLE_COLUMNS
                .iter()
                .all(|n| headers[0].split(d).any(|h| h.trim() == *n))
        });
    let hint = if other_delimiter {
        "; the columns are separated by `;` or tabs, and eval reads commas: convert the file, \
         e.g. `tr ';\\t' ',,' < IN > OUT` (with no commas inside the cells)"
    } else {
        ""
    };
    Err(Error::input(
        source,
        header_line,
        1,
        format!(
            "missing column(s) {}; the header must name theta_i,phi_i,theta_r,phi_r (degrees), found: {}{hint}",
            missing.join(", "),
            headers.join(",")
        ),
    ))
}

/// The unit's name in messages.
fn unit_name(unit: AngleUnit) -> &'static str {
    match unit {
        AngleUnit::Deg => "degrees",
        AngleUnit::Rad => "radians",
    }
}

/// θ_i, φ_i, θ_r, φ_r as read (in `unit`) as model angles.
pub(super) fn to_angles([theta_i, phi_i, theta_r, phi_r]: [f64; 4], unit: AngleUnit) -> Angles {
    match unit {
        AngleUnit::Deg => Angles::from_degrees(theta_i, phi_i, theta_r, phi_r),
        AngleUnit::Rad => Angles {
            theta_i,
            phi_i,
            theta_r,
            phi_r,
        },
    }
}

/// Parse one row's angles (in `unit`, kept there) with errors naming line and column.
pub(super) fn parse_angles(
    source: &Path,
    line: u64,
    record: &impl Fields,
    index: &[usize; 4],
    headers: &[String],
    unit: AngleUnit,
) -> Result<[f64; 4]> {
    let (theta_limit, phi_limit, unit_name) =
        (unit.theta_limit(), unit.phi_limit(), unit_name(unit));
    let mut values = [0.0f64; 4];
    for (k, &col) in index.iter().enumerate() {
        let field = record.field(col);
        // Fast path: plain ASCII digits parse exactly as `str::parse` reads them after `trim`.
        let value = match parse_f64(field.trim_ascii()) {
            Some(v) => v,
            None => parse_text(source, line, field, col, &headers[col], unit_name)?,
        };
        if !value.is_finite() {
            let text = String::from_utf8_lossy(field);
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
        if !is_theta && value.abs() > phi_limit {
            return Err(Error::input(
                source,
                line,
                col as u64 + 1,
                format!(
                    "{} = {value} {unit_name} is more than two turns; azimuths must satisfy \
                     |φ| ≤ 720° (4π), as the loader requires",
                    headers[col]
                ),
            ));
        }
        values[k] = value;
    }
    Ok(values)
}

/// The slow path of a field the fast parser refused: UTF-8 text, trimmed of any whitespace,
/// through `str::parse` (the errors name line and column).
fn parse_text(
    source: &Path,
    line: u64,
    field: &[u8],
    col: usize,
    header: &str,
    unit_name: &str,
) -> Result<f64> {
    let text = std::str::from_utf8(field)
        .map_err(|_| Error::input(source, line, col as u64 + 1, "the field is not valid UTF-8"))?;
    text.trim().parse().map_err(|_| {
        Error::input(
            source,
            line,
            col as u64 + 1,
            format!(
                "`{}` is not a number (column `{header}`, {unit_name}){}",
                text.trim(),
                crate::data::records::decimal_comma_hint(text.trim())
            ),
        )
    })
}
