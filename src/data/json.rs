//! The JSON dataset hairfit writes and reads: `{"channels":[..], "meta":{..}, "samples":[{"theta_i",
//! "phi_i","theta_r","phi_r" (degrees), "radiance": number or [..], "sigma"?, "weight"?}]}`.
//! `null` or an absent field is a missing value (a rejection); a wrong type is an input error.

use std::path::Path;

use serde::Deserialize;
use serde_json::{Map, Value};

use super::dataset::Dataset;
use super::options::{AngleUnit, LoadOptions};
use super::report::LoadReport;
use super::rows::{Cell, Rows};
use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::families::ModelFamily;

#[derive(Deserialize)]
struct FileJson {
    samples: Vec<SampleJson>,
    #[serde(default)]
    channels: Option<Vec<String>>,
    #[serde(default)]
    meta: Map<String, Value>,
}

#[derive(Deserialize)]
struct SampleJson {
    theta_i: Option<f64>,
    phi_i: Option<f64>,
    theta_r: Option<f64>,
    phi_r: Option<f64>,
    radiance: Option<Value>,
    sigma: Option<Value>,
    weight: Option<Value>,
}

/// A serde_json error as an input error at its line and column (column 0 = end of input).
fn json_error(path: &Path, e: &serde_json::Error) -> Error {
    if e.is_eof() && e.line() <= 1 && e.column() == 0 {
        return Error::input(path, 1, 1, "no data rows: the file is empty");
    }
    Error::json(
        path,
        e,
        Some("expected a hairfit JSON dataset: {\"samples\": [...]}"),
    )
}

/// The key that marks `object` as a parameter file: `sigma_a`, or a `"model"` naming a family
/// (a table family's file may have no σ_a).
fn parameter_key(object: &Map<String, Value>) -> Option<&'static str> {
    let tagged = (object.get("model").and_then(Value::as_str))
        .is_some_and(|tag| ModelFamily::parse(tag).is_ok());
    if object.contains_key("sigma_a") {
        Some("sigma_a")
    } else if tagged {
        Some("model")
    } else {
        None
    }
}

/// A hairfit file that is not a dataset, given where a dataset goes (`hairfit load`, `fit`,
/// `compare` DATA): a parameter file, a fit's fit.json, a synth truth sidecar. The error says
/// what the file is and where it belongs instead of serde's "missing field `samples`".
fn not_a_dataset(bytes: &[u8], path: &Path) -> Option<Error> {
    let value: Value = serde_json::from_slice(bytes).ok()?;
    let object = value.as_object()?;
    if object.contains_key("samples") {
        return None;
    }
    let shown = path.display();
    let what = "DATA takes measured samples: a CSV with a header, a headerless scan (--columns) \
                or a JSON dataset {\"samples\": [...]}";
    let result = object.contains_key("hairfit_version") && object.contains_key("params");
    let message = if result && object.contains_key("verdict") {
        let data = object
            .get("data")
            .and_then(|d| d.get("file"))
            .and_then(Value::as_str)
            .map_or(String::new(), |f| {
                format!(": the data it was fitted to are {f}")
            });
        let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
        format!(
            "{shown}: this is a fit result (fit.json), not a dataset{data}; to redraw the fit use \
             hairfit report {}, to evaluate it pass its params.json to --params of hairfit eval. {what}",
            dir.map_or(".".into(), |d| d.display().to_string())
        )
    } else if result {
        let samples = path
            .to_str()
            .and_then(|p| p.strip_suffix(".truth.json"))
            .map(|stem| std::path::PathBuf::from(format!("{stem}.csv")))
            .filter(|csv| csv.is_file())
            .map_or(String::new(), |csv| {
                format!(": its samples are in {}", csv.display())
            });
        format!(
            "{shown}: this is a synth truth file (the parameters a dataset was made from), not \
             a dataset{samples}. {what}"
        )
    } else if let Some(key) = parameter_key(object) {
        // The family its `"model"` names, when not the default `--model`.
        let model = object
            .get("model")
            .and_then(Value::as_str)
            .and_then(|tag| ModelFamily::parse(tag).ok())
            .filter(|family| *family != ModelFamily::default())
            .map_or(String::new(), |family| format!(" --model {family}"));
        format!(
            "{shown}: this looks like a parameter file (it has \"{key}\"), not a dataset: a \
             parameter file goes to --params, e.g. hairfit eval{model} --params {shown} --input \
             ANGLES.csv, or hairfit synth{model} --params {shown} --rig RIG --output DATA.csv to \
             make a dataset from it. {what}"
        )
    } else {
        return None;
    };
    Some(Error::Other(message))
}

/// Line and column (1-based) where each element of the top-level `"samples"` array starts,
/// found by a small scan that tracks strings and nesting depth (serde_json keeps no positions).
fn sample_positions(bytes: &[u8]) -> Vec<(u64, u64)> {
    let mut out = Vec::new();
    let (mut line, mut col) = (1u64, 0u64);
    let (mut depth, mut in_str, mut escaped) = (0usize, false, false);
    let mut str_start = 0;
    let mut last_key: &[u8] = b"";
    let mut after_samples_key = false;
    let mut samples_depth: Option<usize> = None;
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'\n' {
            line += 1;
            col = 0;
            continue;
        }
        col += 1;
        if in_str {
            if escaped {
                escaped = false;
            } else if b == b'\\' {
                escaped = true;
            } else if b == b'"' {
                in_str = false;
                if depth == 1 {
                    last_key = &bytes[str_start..i];
                }
            }
            continue;
        }
        match b {
            b'"' => {
                in_str = true;
                str_start = i + 1;
            }
            b':' => after_samples_key = depth == 1 && last_key == b"samples",
            b'[' => {
                depth += 1;
                if after_samples_key && depth == 2 {
                    samples_depth = Some(depth);
                }
                after_samples_key = false;
            }
            b'{' => {
                if samples_depth == Some(depth) {
                    out.push((line, col));
                }
                depth += 1;
            }
            b']' | b'}' => {
                if samples_depth == Some(depth) {
                    samples_depth = None;
                }
                depth = depth.saturating_sub(1);
            }
            _ => {}
        }
    }
    out
}

/// Cells of a radiance/sigma/weight value: a number (broadcast when `broadcast`), an array with
/// one number or null per channel, or null/absent (all missing).
fn channel_cells(
    value: Option<&Value>,
    n: usize,
    broadcast: bool,
    out: &mut [Cell],
) -> std::result::Result<(), String> {
    match value {
        None | Some(Value::Null) => out.fill(None),
        Some(Value::Number(x)) if n == 1 || broadcast => out.fill(x.as_f64()),
        Some(Value::Number(_)) => {
            return Err(format!(
                "a single number for {n} channels: give an array of {n}"
            ))
        }
        Some(Value::Array(items)) if items.len() == n => {
            for (cell, item) in out.iter_mut().zip(items) {
                *cell = match item {
                    Value::Null => None,
                    Value::Number(x) => x.as_f64(),
                    other => return Err(format!("`{other}` is not a number or null")),
                };
            }
        }
        Some(Value::Array(items)) => {
            return Err(format!(
                "an array of {} values for {n} channels",
                items.len()
            ))
        }
        Some(other) => return Err(format!("`{other}` is not a number, an array or null")),
    }
    Ok(())
}

/// The channel names: `"channels"` if given, else `["radiance"]` when radiance is a number.
fn channels_of(file: &FileJson, path: &Path, positions: &[(u64, u64)]) -> Result<Vec<String>> {
    if let Some(ch) = &file.channels {
        if ch.is_empty() {
            return Err(Error::input(path, 1, 1, "\"channels\" is empty"));
        }
        // The same rules as a CSV header's `radiance_<channel>` columns.
        let mut seen = std::collections::HashSet::new();
        for name in ch {
            if name.trim().is_empty() {
                return Err(Error::input(
                    path,
                    1,
                    1,
                    "\"channels\" has an empty name: name every channel",
                ));
            }
            if !seen.insert(name.to_ascii_lowercase()) {
                return Err(Error::input(
                    path,
                    1,
                    1,
                    format!("\"channels\" names `{name}` twice: channel names must differ"),
                ));
            }
        }
        return Ok(ch.clone());
    }
    let first_array = file
        .samples
        .iter()
        .position(|s| matches!(s.radiance, Some(Value::Array(_))));
    if let Some(i) = first_array {
        let (line, col) = positions.get(i).copied().unwrap_or((1, 1));
        return Err(Error::input(
            path,
            line,
            col,
            "radiance is an array but the file has no \"channels\" list naming the channels",
        ));
    }
    Ok(vec!["radiance".into()])
}

/// Load a JSON dataset (angles in degrees).
pub(crate) fn load_json(path: &Path, options: &LoadOptions) -> Result<(Dataset, LoadReport)> {
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(&mut super::lines::open(path)?, &mut bytes)
        .map_err(|e| super::lines::read_error(path, e))?;
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&bytes);
    let file: FileJson = serde_json::from_slice(bytes)
        .map_err(|e| not_a_dataset(bytes, path).unwrap_or_else(|| json_error(path, &e)))?;
    let positions = sample_positions(bytes);
    if file.samples.is_empty() {
        return Err(Error::input(
            path,
            1,
            1,
            "no data rows: \"samples\" is empty",
        ));
    }
    let channels = channels_of(&file, path, &positions)?;
    let nc = channels.len();
    let has = |f: fn(&SampleJson) -> &Option<Value>| {
        file.samples
            .iter()
            .any(|s| !matches!(f(s), None | Some(Value::Null)))
    };
    let (has_sigma, has_weight) = (has(|s| &s.sigma), has(|s| &s.weight));
    let mut rows = Rows::new(
        channels,
        has_sigma,
        has_weight,
        AngleUnit::Deg,
        options.negative_tolerance,
    )
    // The format itself says degrees (and refuses --angles rad): nothing to guess.
    .unit_stated(true);
    *rows.meta_mut() = file.meta.clone();
    let mut radiance: Vec<Cell> = vec![None; nc];
    let mut sigma: Vec<Cell> = vec![None; if has_sigma { nc } else { 0 }];
    let mut weight: Vec<Cell> = vec![None; if has_weight { nc } else { 0 }];
    for (i, s) in file.samples.iter().enumerate() {
        let (line, col) = positions.get(i).copied().unwrap_or((1, 1));
        let err = |what: &str, m: String| {
            Error::input(path, line, col, format!("sample {}: {what} is {m}", i + 1))
        };
        channel_cells(s.radiance.as_ref(), nc, false, &mut radiance)
            .map_err(|m| err("radiance", m))?;
        if has_sigma {
            channel_cells(s.sigma.as_ref(), nc, true, &mut sigma).map_err(|m| err("sigma", m))?;
        }
        if has_weight {
            channel_cells(s.weight.as_ref(), nc, true, &mut weight)
                .map_err(|m| err("weight", m))?;
        }
        let angles = [s.theta_i, s.phi_i, s.theta_r, s.phi_r];
        rows.row(line, angles, &radiance, &sigma, &weight);
    }
    Ok(rows.finish())
}

/// A per-channel value as JSON: a number for one channel, else an array.
fn channel_value(values: &[f64]) -> Value {
    if values.len() == 1 {
        Value::from(values[0])
    } else {
        Value::from(values.to_vec())
    }
}

/// Write `dataset` as a JSON dataset (angles in degrees), one sample per line so that a loaded
/// sample's `source_line` points at it.
pub fn write_json(dataset: &Dataset, path: &Path) -> Result<()> {
    let nc = dataset.n_channels();
    let io = |e| Error::io(path, e);
    let ser = |v: &Value| serde_json::to_string(v).map_err(|e| Error::Other(e.to_string()));
    write_atomically(path, |w| {
        writeln!(w, "{{").map_err(io)?;
        writeln!(
            w,
            "\"channels\": {},",
            ser(&Value::from(dataset.channels.clone()))?
        )
        .map_err(io)?;
        writeln!(
            w,
            "\"meta\": {},",
            ser(&Value::Object(dataset.meta.clone()))?
        )
        .map_err(io)?;
        writeln!(w, "\"samples\": [").map_err(io)?;
        for i in 0..dataset.len() {
            let a = dataset.angles_deg(i);
            let row = i * nc..(i + 1) * nc;
            let mut s = Map::new();
            for (name, v) in ["theta_i", "phi_i", "theta_r", "phi_r"].iter().zip(a) {
                s.insert(name.to_string(), Value::from(v));
            }
            s.insert(
                "radiance".into(),
                channel_value(&dataset.radiance[row.clone()]),
            );
            if let Some(sig) = &dataset.sigma {
                s.insert("sigma".into(), channel_value(&sig[row.clone()]));
            }
            if let Some(wt) = &dataset.weight {
                s.insert("weight".into(), channel_value(&wt[row.clone()]));
            }
            let sep = if i + 1 < dataset.len() { "," } else { "" };
            writeln!(w, "{}{sep}", ser(&Value::Object(s))?).map_err(io)?;
        }
        writeln!(w, "]").map_err(io)?;
        writeln!(w, "}}").map_err(io)?;
        Ok(())
    })
}
