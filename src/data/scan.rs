//! Headerless goniometer scans that hold some angles fixed: whitespace- or comma-separated
//! columns mapped by `--columns`, the other angles given by `--fixed`, optional `--map NAME=EXPR`
//! (linear in x) per column, and a missing token (`?`) where the rig could not measure.

use std::path::Path;

use super::csv_rows::parse_cell;
use super::dataset::{Dataset, ANGLE_COLUMNS};
use super::expr::Linear;
use super::options::{AngleUnit, LoadOptions, Role};
use super::report::LoadReport;
use super::rows::{Cell, RowCells, Rows};
use crate::error::{Error, Result};

/// The scan layout resolved from `--columns`, `--fixed` and `--map`.
#[derive(Debug)]
struct Layout {
    targets: Vec<Role>,
    names: Vec<String>,
    maps: Vec<Linear>,
    fixed: [Option<f64>; 4],
    channels: Vec<String>,
    has_sigma: bool,
    has_weight: bool,
}

fn option_error(msg: String) -> Error {
    Error::Other(msg)
}

/// The channel names `--columns` declares for a headerless scan (`None` when the options do
/// not describe one; loading it then says why).
pub(crate) fn column_channels(options: &LoadOptions) -> Option<Vec<String>> {
    layout(options).ok().map(|l| l.channels)
}

/// Resolve the scan options into a layout, with an error naming the offending option.
fn layout(options: &LoadOptions) -> Result<Layout> {
    const VALID: &str = "theta_i, phi_i, theta_r, phi_r, radiance or radiance_<ch>, \
                         sigma[_<ch>], weight[_<ch>], `_` or `skip`";
    if options.columns.is_empty() {
        return Err(option_error(format!(
            "a headerless scan needs --columns (e.g. `--columns phi_r,theta_r,radiance`; \
             valid names: {VALID}); files are read by extension: .csv and .tsv as tables with \
             a header, .json as a JSON dataset, anything else as a scan (or give --format)"
        )));
    }
    let mut targets = Vec::new();
    let mut names = Vec::new();
    let mut channels: Vec<String> = Vec::new();
    let mut sigma_cols = Vec::new();
    let mut weight_cols = Vec::new();
    for raw in &options.columns {
        let name = raw.trim().to_string();
        let lower = name.to_ascii_lowercase();
        if lower != "_" && lower != "skip" && names.contains(&lower) {
            return Err(option_error(format!("--columns names `{name}` twice")));
        }
        let suffix = |p: &str| lower.strip_prefix(p).map(|_| name[p.len()..].to_string());
        let target = if let Some(a) = ANGLE_COLUMNS.iter().position(|&n| n == lower) {
            Role::Angle(a)
        } else if lower == "_" || lower == "skip" {
            Role::Ignored
        } else if lower == "radiance" {
            channels.push("radiance".into());
            Role::Radiance(channels.len() - 1)
        } else if let Some(ch) = suffix("radiance_").filter(|c| !c.is_empty()) {
            channels.push(ch);
            Role::Radiance(channels.len() - 1)
        } else if lower == "sigma" || lower.starts_with("sigma_") {
            sigma_cols.push((targets.len(), suffix("sigma_")));
            Role::Ignored
        } else if lower == "weight" || lower.starts_with("weight_") {
            weight_cols.push((targets.len(), suffix("weight_")));
            Role::Ignored
        } else {
            return Err(option_error(format!(
                "--columns: unknown column name `{name}` (valid: {VALID})"
            )));
        };
        targets.push(target);
        names.push(lower);
    }
    if channels.is_empty() {
        return Err(option_error(
            "--columns must name a radiance column (`radiance` or `radiance_<ch>`)".into(),
        ));
    }
    if channels.len() > 1 && channels.iter().any(|c| c == "radiance") {
        return Err(option_error(
            "--columns mixes `radiance` with `radiance_<ch>`: use one form".into(),
        ));
    }
    for (cols, is_sigma) in [(&sigma_cols, true), (&weight_cols, false)] {
        let what = if is_sigma { "sigma" } else { "weight" };
        if cols.len() > 1 && cols.iter().any(|(_, ch)| ch.is_none()) {
            return Err(option_error(format!(
                "--columns mixes `{what}` with `{what}_<ch>`: use one form"
            )));
        }
        for (k, ch) in cols.iter() {
            let c = match ch {
                None => None,
                Some(n) => Some(channels.iter().position(|c| c == n).ok_or_else(|| {
                    option_error(format!("--columns: `{what}_{n}` has no `radiance_{n}`"))
                })?),
            };
            targets[*k] = if is_sigma {
                Role::Sigma(c)
            } else {
                Role::Weight(c)
            };
        }
        let broadcast = cols.iter().any(|(_, ch)| ch.is_none());
        if !cols.is_empty() && !broadcast && cols.len() != channels.len() {
            return Err(option_error(format!(
                "--columns: give a `{what}_<ch>` column for every radiance channel"
            )));
        }
    }
    let fixed = parse_fixed(options, &targets)?;
    let maps = parse_maps(options, &names, &targets)?;
    for (a, angle) in ANGLE_COLUMNS.iter().enumerate() {
        if fixed[a].is_none() && !targets.contains(&Role::Angle(a)) {
            return Err(option_error(format!(
                "angle `{angle}` is not given: add it to --columns or fix it with \
                 --fixed {angle}=VALUE"
            )));
        }
    }
    Ok(Layout {
        targets,
        names,
        maps,
        fixed,
        has_sigma: !sigma_cols.is_empty(),
        has_weight: !weight_cols.is_empty(),
        channels,
    })
}

/// `--fixed NAME=VALUE` for angles not in the columns.
fn parse_fixed(options: &LoadOptions, targets: &[Role]) -> Result<[Option<f64>; 4]> {
    let mut fixed = [None; 4];
    for item in &options.fixed {
        let (name, value) = item.split_once('=').ok_or_else(|| {
            option_error(format!(
                "--fixed `{item}`: write NAME=VALUE, e.g. theta_i=30"
            ))
        })?;
        let name = name.trim().to_ascii_lowercase();
        let a = ANGLE_COLUMNS
            .iter()
            .position(|&n| n == name)
            .ok_or_else(|| {
                option_error(format!(
                    "--fixed `{item}`: `{name}` is not an angle (theta_i, phi_i, theta_r, phi_r)"
                ))
            })?;
        if targets.contains(&Role::Angle(a)) {
            return Err(option_error(format!(
                "--fixed `{item}`: `{name}` is also a column in --columns; give it once"
            )));
        }
        if fixed[a].is_some() {
            return Err(option_error(format!("--fixed gives `{name}` twice")));
        }
        let v: f64 = value
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| {
                option_error(format!(
                    "--fixed `{item}`: `{value}` is not a finite number"
                ))
            })?;
        fixed[a] = Some(v);
    }
    Ok(fixed)
}

/// A fixed θ on or past the axis would reject every row; say so once instead.
fn check_fixed_theta(fixed: &[Option<f64>; 4], unit: AngleUnit) -> Result<()> {
    let (limit, name) = match unit {
        AngleUnit::Deg => (90.0, "90"),
        AngleUnit::Rad => (std::f64::consts::FRAC_PI_2, "pi/2"),
    };
    for a in [0, 2] {
        if let Some(v) = fixed[a].filter(|v| v.abs() >= limit) {
            return Err(option_error(format!(
                "--fixed {}={v}: |theta| must be below {name} (the fiber axis is degenerate)",
                ANGLE_COLUMNS[a]
            )));
        }
    }
    Ok(())
}

/// `--map NAME=EXPR`, one linear map per column (identity where none is given).
fn parse_maps(options: &LoadOptions, names: &[String], targets: &[Role]) -> Result<Vec<Linear>> {
    let mut maps = vec![Linear::IDENTITY; names.len()];
    let mut mapped = vec![false; names.len()];
    for item in &options.maps {
        let (name, expr) = item.split_once('=').ok_or_else(|| {
            option_error(format!(
                "--map `{item}`: write NAME=EXPR, e.g. theta_r=90-x"
            ))
        })?;
        let name = name.trim().to_ascii_lowercase();
        let k = names
            .iter()
            .position(|n| *n == name)
            .filter(|&k| targets[k] != Role::Ignored)
            .ok_or_else(|| {
                option_error(format!(
                    "--map `{item}`: `{name}` is not one of the --columns ({})",
                    names.join(",")
                ))
            })?;
        if mapped[k] {
            return Err(option_error(format!("--map gives `{name}` twice")));
        }
        mapped[k] = true;
        maps[k] = Linear::parse(expr)
            .map_err(|e| option_error(format!("--map `{}`: expression {e}", abbreviate(item))))?;
    }
    Ok(maps)
}

/// At most 40 characters of `text` (a hostile `--map` can be 100k characters long).
fn abbreviate(text: &str) -> String {
    match text.char_indices().nth(40) {
        Some((end, _)) => format!("{}…", &text[..end]),
        None => text.to_string(),
    }
}

/// Split a scan line into fields: on commas when it has any, else on runs of whitespace.
fn split_fields<'a>(line: &'a [u8], out: &mut Vec<&'a [u8]>) {
    out.clear();
    if line.contains(&b',') {
        out.extend(line.split(|&b| b == b','));
    } else {
        out.extend(
            line.split(|b| b.is_ascii_whitespace())
                .filter(|f| !f.is_empty()),
        );
    }
}

/// Trim ASCII whitespace (including a CR from CRLF) from both ends.
fn trim_bytes(mut s: &[u8]) -> &[u8] {
    while let [first, rest @ ..] = s {
        if first.is_ascii_whitespace() {
            s = rest;
        } else {
            break;
        }
    }
    while let [rest @ .., last] = s {
        if last.is_ascii_whitespace() {
            s = rest;
        } else {
            break;
        }
    }
    s
}

/// Load a headerless scan.
pub(crate) fn load_scan(path: &Path, options: &LoadOptions) -> Result<(Dataset, LoadReport)> {
    let lay = layout(options).map_err(|e| match e {
        Error::Other(m) => Error::Other(format!("{}: {m}", path.display())),
        other => other,
    })?;
    let directive = super::unit::file_directive(path, 0)?;
    let unit = super::unit::resolve(options.angles, directive, path)?;
    check_fixed_theta(&lay.fixed, unit)?;
    let mut rows = Rows::new(
        lay.channels.clone(),
        lay.has_sigma,
        lay.has_weight,
        unit,
        options.negative_tolerance,
    )
    .unit_stated(options.angles.is_some() || directive.is_some());
    let fixed: Vec<String> = ANGLE_COLUMNS
        .iter()
        .zip(lay.fixed)
        .filter_map(|(n, v)| v.map(|v| format!("{n}={v}")))
        .collect();
    if !fixed.is_empty() {
        rows.note(format!("fixed angles: {}", fixed.join(", ")));
    }
    for (name, m) in lay.names.iter().zip(&lay.maps) {
        if *m != Linear::IDENTITY {
            rows.note(format!("column {name} mapped by x -> {m}"));
        }
    }
    let mut reader = super::lines::open(path)?;
    let nc = lay.channels.len();
    let mut buf = Vec::new();
    let mut radiance: Vec<Cell> = vec![None; nc];
    let mut sigma: Vec<Cell> = vec![None; if lay.has_sigma { nc } else { 0 }];
    let mut weight: Vec<Cell> = vec![None; if lay.has_weight { nc } else { 0 }];
    let mut line_no = 0u64;
    loop {
        if !super::lines::next_line(&mut reader, &mut buf, path)? {
            break;
        }
        line_no += 1;
        let mut line = buf.as_slice();
        if line_no == 1 {
            line = line.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(line);
        }
        let line = trim_bytes(line);
        if line.is_empty() || line[0] == b'#' {
            continue;
        }
        let mut fields: Vec<&[u8]> = Vec::with_capacity(lay.targets.len());
        split_fields(line, &mut fields);
        if fields.len() != lay.targets.len() {
            return Err(Error::input(
                path,
                line_no,
                (fields.len().min(lay.targets.len()) + 1) as u64,
                format!(
                    "expected {} columns as given by --columns ({}), found {}",
                    lay.targets.len(),
                    lay.names.join(","),
                    fields.len()
                ),
            ));
        }
        let mut angles: [Cell; 4] = lay.fixed;
        for (k, field) in fields.iter().enumerate() {
            let target = lay.targets[k];
            if target == Role::Ignored {
                continue;
            }
            let cell = parse_cell(
                trim_bytes(field),
                &options.missing,
                path,
                line_no,
                k as u64 + 1,
                &lay.names[k],
            )?
            .map(|x| lay.maps[k].apply(x));
            let mut cells = RowCells {
                angles: &mut angles,
                radiance: &mut radiance,
                sigma: &mut sigma,
                weight: &mut weight,
            };
            cells.place(target, cell);
        }
        rows.row(line_no, angles, &radiance, &sigma, &weight);
    }
    if rows.rows_read() == 0 {
        return Err(Error::input(
            path,
            line_no.max(1),
            1,
            "no data rows: the scan has no data lines",
        ));
    }
    Ok(rows.finish())
}
