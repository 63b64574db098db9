//! The header CSV format (`theta_i,phi_i,theta_r,phi_r,radiance[_<ch>]...,[sigma...],[weight...]`)
//! reader (header, columns, cells; the rows are streamed by [`super::csv_rows`] in bounded
//! blocks, so memory is the accepted samples) and writer.
//! Comment lines before the header may carry the unit directive `# angles: deg|rad`;
//! [`write_csv`] writes degrees and says so.

use std::collections::{HashMap, HashSet};
use std::io::BufRead;
use std::path::Path;

use super::csv_rows::{read_rows, Columns, Input};
use super::dataset::{Dataset, ANGLE_COLUMNS};
use super::lines::{next_line, read_error};
use super::options::{LoadOptions, Role};
use super::report::LoadReport;
use super::rows::Rows;
use crate::atomic::write_atomically;
use crate::error::{Error, Result};

/// What comes before the data: the header fields and the number of lines consumed (comments,
/// blanks and the header). The unit line is read by [`super::unit::file_directive`].
struct Preamble {
    header: csv::StringRecord,
    lines: u64,
}

/// Strip a UTF-8 byte-order mark at the start of the stream.
fn skip_bom(reader: &mut impl BufRead, path: &Path) -> Result<()> {
    let buf = reader.fill_buf().map_err(|e| read_error(path, e))?;
    if buf.starts_with(b"\xEF\xBB\xBF") {
        reader.consume(3);
    }
    Ok(())
}

/// Read the comment/blank lines and the header line at the top of a CSV file.
fn read_preamble(reader: &mut impl BufRead, delimiter: u8, path: &Path) -> Result<Preamble> {
    skip_bom(reader, path)?;
    let mut buf = Vec::new();
    let mut lines = 0u64;
    loop {
        if !next_line(reader, &mut buf, path)? {
            return Err(Error::input(
                path,
                lines.max(1),
                1,
                "no data rows: the file has no header line \
                 (expected `theta_i,phi_i,theta_r,phi_r,radiance`)",
            ));
        }
        lines += 1;
        let text = String::from_utf8_lossy(&buf);
        let t = text.trim();
        if t.is_empty() {
            continue;
        }
        if t.starts_with('#') {
            continue;
        }
        let header = parse_header_line(&buf, delimiter, path, lines)?;
        return Ok(Preamble { header, lines });
    }
}

/// Split the header line into trimmed UTF-8 names.
fn parse_header_line(
    line: &[u8],
    delimiter: u8,
    path: &Path,
    line_no: u64,
) -> Result<csv::StringRecord> {
    let mut r = csv::ReaderBuilder::new()
        .delimiter(delimiter)
        .has_headers(false)
        .trim(csv::Trim::All)
        .from_reader(line);
    let mut rec = csv::ByteRecord::new();
    r.read_byte_record(&mut rec)
        .map_err(|e| Error::input(path, line_no, 1, format!("unreadable header: {e}")))?;
    let mut out = csv::StringRecord::new();
    for (k, field) in rec.iter().enumerate() {
        let name = std::str::from_utf8(field).map_err(|_| {
            Error::input(
                path,
                line_no,
                k as u64 + 1,
                "header is not UTF-8 text (is this a CSV file?)",
            )
        })?;
        out.push_field(name);
    }
    Ok(out)
}

/// What the header should look like, for error messages.
const HEADER_HELP: &str = "required: theta_i, phi_i, theta_r, phi_r and either `radiance` or \
     `radiance_<channel>` columns; optional: sigma[_<channel>], weight[_<channel>]";

/// A hint when the header is one column that looks split by another separator.
fn separator_hint(header: &csv::StringRecord) -> &'static str {
    match header.iter().next() {
        Some(h) if header.len() == 1 && (h.contains(';') || h.contains('\t')) => {
            " (the file seems to use `;` or tabs between columns: give --delimiter ';' or \
             --delimiter tab; for a headerless scan give --columns)"
        }
        _ => "",
    }
}

/// The first column whose name (in any case) an earlier column already has: every reader of a
/// header (the loader, eval) refuses it, since which of the two counts would be a guess.
pub(crate) fn repeated_column<'a>(header: impl IntoIterator<Item = &'a str>) -> Option<usize> {
    // Hash lookups keep a header of many columns linear (a list search was quadratic: 100k
    // columns took 14 s).
    let mut seen: HashSet<String> = HashSet::new();
    header
        .into_iter()
        .position(|name| !seen.insert(name.to_ascii_lowercase()))
}

/// The error text for [`repeated_column`]'s column.
pub(crate) fn repeated_column_message(name: &str) -> String {
    format!("column `{name}` appears twice in the header: rename or remove one")
}

/// Assign a role to every header column and check the set is complete and consistent.
fn columns_from_header(header: &csv::StringRecord, path: &Path, line: u64) -> Result<Columns> {
    let err = |col: usize, msg: String| Error::input(path, line, col as u64 + 1, msg);
    let found = || {
        header
            .iter()
            .map(|h| format!("`{h}`"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut roles = vec![Role::Ignored; header.len()];
    let mut channels: Vec<String> = Vec::new();
    let mut plain_radiance = false;
    // (column, channel name or None) for sigma and weight, resolved once channels are known.
    let mut sigma_cols: Vec<(usize, Option<String>)> = Vec::new();
    let mut weight_cols: Vec<(usize, Option<String>)> = Vec::new();
    let mut ignored = Vec::new();
    if let Some(k) = repeated_column(header.iter()) {
        return Err(err(k, repeated_column_message(&header[k])));
    }
    for (k, name) in header.iter().enumerate() {
        let lower = name.to_ascii_lowercase();
        let suffix = |prefix: &str| {
            lower
                .strip_prefix(prefix)
                .map(|_| name[prefix.len()..].to_string())
        };
        if let Some(a) = ANGLE_COLUMNS.iter().position(|&n| n == lower) {
            roles[k] = Role::Angle(a);
        } else if lower == "radiance" {
            plain_radiance = true;
            roles[k] = Role::Radiance(channels.len());
            channels.push("radiance".into());
        } else if let Some(ch) = suffix("radiance_") {
            roles[k] = Role::Radiance(channels.len());
            channels.push(ch);
        } else if lower == "sigma" {
            sigma_cols.push((k, None));
        } else if let Some(ch) = suffix("sigma_") {
            sigma_cols.push((k, Some(ch)));
        } else if lower == "weight" {
            weight_cols.push((k, None));
        } else if let Some(ch) = suffix("weight_") {
            weight_cols.push((k, Some(ch)));
        } else {
            ignored.push(name.to_string());
        }
    }
    for (a, angle) in ANGLE_COLUMNS.iter().enumerate() {
        if !roles.contains(&Role::Angle(a)) {
            return Err(err(
                0,
                format!(
                    "header has no `{angle}` column ({HEADER_HELP}); found: {}{}",
                    found(),
                    separator_hint(header)
                ),
            ));
        }
    }
    if channels.is_empty() {
        return Err(err(
            0,
            format!(
                "header has no radiance column ({HEADER_HELP}); found: {}",
                found()
            ),
        ));
    }
    if plain_radiance && channels.len() > 1 {
        return Err(err(
            0,
            "header mixes `radiance` with `radiance_<channel>` columns: use one form".into(),
        ));
    }
    let has_sigma = !sigma_cols.is_empty();
    let has_weight = !weight_cols.is_empty();
    let channel_index: HashMap<&str, usize> = channels
        .iter()
        .enumerate()
        .map(|(c, name)| (name.as_str(), c))
        .collect();
    for (cols, what) in [(&sigma_cols, "sigma"), (&weight_cols, "weight")] {
        let mut covered = vec![false; channels.len()];
        let broadcast = cols.iter().any(|(_, ch)| ch.is_none());
        if broadcast && cols.len() > 1 {
            return Err(err(
                cols[1].0,
                format!("header mixes `{what}` with `{what}_<channel>`: use one form"),
            ));
        }
        for (k, ch) in cols.iter() {
            let role_ch = match ch {
                None => None,
                Some(name) => {
                    let c = channel_index.get(name.as_str()).copied().ok_or_else(|| {
                        err(
                            *k,
                            format!(
                                "`{what}_{name}` has no matching `radiance_{name}` column \
                                 (channels: {})",
                                channels.join(", ")
                            ),
                        )
                    })?;
                    covered[c] = true;
                    Some(c)
                }
            };
            roles[*k] = if what == "sigma" {
                Role::Sigma(role_ch)
            } else {
                Role::Weight(role_ch)
            };
        }
        if !broadcast {
            if let Some(c) = covered.iter().position(|&c| !c) {
                if !cols.is_empty() {
                    return Err(err(
                        0,
                        format!(
                            "header has `{what}_<channel>` columns but none for channel `{}`",
                            channels[c]
                        ),
                    ));
                }
            }
        }
    }
    Ok(Columns {
        roles,
        channels,
        has_sigma,
        has_weight,
        ignored,
    })
}

/// The channel names a CSV file's header declares, read from the header alone (the loader
/// reads the same header the same way); `None` when the file or its header cannot be read
/// (loading it then says why).
pub(crate) fn header_channels(path: &Path, options: &LoadOptions) -> Option<Vec<String>> {
    let mut reader = super::lines::open(path).ok()?;
    let delimiter = options.delimiter_for(path).ok()?;
    let pre = read_preamble(&mut reader, delimiter, path).ok()?;
    columns_from_header(&pre.header, path, pre.lines)
        .ok()
        .map(|c| c.channels)
}

/// Load a header CSV file.
pub(crate) fn load_csv(path: &Path, options: &LoadOptions) -> Result<(Dataset, LoadReport)> {
    let mut reader = super::lines::open(path)?;
    let delimiter = options.delimiter_for(path)?;
    let pre = read_preamble(&mut reader, delimiter, path)?;
    let directive = super::unit::file_directive(path, 1)?;
    let unit = super::unit::resolve(options.angles, directive, path)?;
    let header_line = pre.lines;
    let cols = columns_from_header(&pre.header, path, header_line)?;
    let mut rows = Rows::new(
        cols.channels.clone(),
        cols.has_sigma,
        cols.has_weight,
        unit,
        options.negative_tolerance,
    )
    .unit_stated(options.angles.is_some() || directive.is_some());
    if !cols.ignored.is_empty() {
        rows.note(format!("ignored columns: {}", cols.ignored.join(", ")));
    }
    let file_len = reader.get_ref().get_ref().metadata().map_or(0, |m| m.len());
    let input = Input {
        path,
        header: &pre.header,
        header_line,
        file_len,
        delimiter,
    };
    let prefix = reader.buffer().to_vec();
    read_rows(
        reader.into_inner(),
        &prefix,
        &input,
        options,
        &cols,
        &mut rows,
    )?;
    if rows.rows_read() == 0 {
        return Err(Error::input(
            path,
            header_line,
            1,
            "no data rows: the file has a header but no samples",
        ));
    }
    Ok(rows.finish())
}

/// Column name for a channel's value: `radiance` for the lone default channel, else
/// `radiance_<channel>` (and likewise for sigma and weight).
fn channel_column(prefix: &str, channels: &[String], c: usize) -> String {
    if channels.len() == 1 && channels[0] == "radiance" {
        prefix.to_string()
    } else {
        format!("{prefix}_{}", channels[c])
    }
}

/// Write `dataset` as header CSV with angles in degrees (marked by `# angles: deg`, so a stray
/// `--angles rad` is an error rather than a silent misreading), every number in Rust's shortest
/// round-trip form. Angles go through
/// [`round_trip_degrees`](super::round_trip_degrees), so loading gives back the same
/// radians bit for bit whenever some degree value maps to them (always for angles that began
/// as degrees, e.g. everything the synthesizer makes), else within 1 ulp; the other values
/// come back bit for bit.
pub fn write_csv(dataset: &Dataset, path: &Path) -> Result<()> {
    write_csv_with(dataset, &[], path)
}

/// [`write_csv`] with `extra` columns after the dataset's own: (name, one value per sample).
/// The loader ignores them (and says so); `hairfit trace` writes its per-order values there.
pub fn write_csv_with(
    dataset: &Dataset,
    extra_columns: &[(String, Vec<f64>)],
    path: &Path,
) -> Result<()> {
    if let Some((name, col)) = extra_columns
        .iter()
        .find(|(_, col)| col.len() != dataset.len())
    {
        return Err(Error::Other(format!(
            "column `{name}` has {} values for {} samples",
            col.len(),
            dataset.len()
        )));
    }
    if let Some(bad) = dataset
        .channels
        .iter()
        .find(|c| c.is_empty() || c.contains([',', '"', '\n', '\r', '#']))
    {
        return Err(Error::Other(format!(
            "channel name `{bad}` cannot be a CSV column name (use letters, digits and `_`)"
        )));
    }
    let nc = dataset.n_channels();
    let mut header: Vec<String> = ANGLE_COLUMNS.iter().map(|s| s.to_string()).collect();
    let extra = |prefix: &str| {
        (0..nc)
            .map(|c| channel_column(prefix, &dataset.channels, c))
            .collect::<Vec<_>>()
    };
    header.extend(extra("radiance"));
    if dataset.sigma.is_some() {
        header.extend(extra("sigma"));
    }
    if dataset.weight.is_some() {
        header.extend(extra("weight"));
    }
    header.extend(extra_columns.iter().map(|(name, _)| name.clone()));
    write_atomically(path, |w| {
        let io = |e| Error::io(path, e);
        writeln!(w, "# written by hairfit; angles in degrees").map_err(io)?;
        writeln!(w, "# angles: deg").map_err(io)?;
        writeln!(w, "{}", header.join(",")).map_err(io)?;
        let mut line = String::new();
        for i in 0..dataset.len() {
            use std::fmt::Write as _;
            line.clear();
            let a = dataset.angles_deg(i);
            // `{:?}`: exponent form for tiny or huge angles instead of hundreds of digits.
            let _ = write!(line, "{:?},{:?},{:?},{:?}", a[0], a[1], a[2], a[3]);
            let row = i * nc..(i + 1) * nc;
            for v in &dataset.radiance[row.clone()] {
                let _ = write!(line, ",{v}");
            }
            for arr in [&dataset.sigma, &dataset.weight].into_iter().flatten() {
                for v in &arr[row.clone()] {
                    let _ = write!(line, ",{v}");
                }
            }
            for (_, col) in extra_columns {
                let _ = write!(line, ",{}", col[i]);
            }
            line.push('\n');
            w.write_all(line.as_bytes()).map_err(io)?;
        }
        Ok(())
    })
}
