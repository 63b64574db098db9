//! Shared helpers of the hard-fit and reliability tests: running the binary with a deadline (the
//! shared `support::cli`, also as `support::hard::cli`), writing data CSVs, and checking a fit's
//! output directory (finite text, bounds, no temp files).

#![allow(dead_code)]

use hairfit::families::marschner::params::ParameterFile as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Output};
use std::time::Duration;

use hairfit::families::marschner::fit::forward::fit_bound;
use hairfit::families::marschner::parameters::all_parameters;
use hairfit::families::marschner::parameters::report_factor;
use hairfit::fit::bounds::Bound;
use hairfit::fit::problem::FitData;

pub use super::cli;

/// How a child process ended, its output as text.
pub struct Finished {
    pub status: ExitStatus,
    pub stdout: String,
    pub stderr: String,
    pub wall: Duration,
}

impl From<(Output, Duration)> for Finished {
    fn from((out, wall): (Output, Duration)) -> Self {
        Finished {
            status: out.status,
            stdout: cli::stdout(&out),
            stderr: cli::stderr(&out),
            wall,
        }
    }
}

/// Wait for `child` at most `limit` ([`cli::wait_within`]).
pub fn wait_with_deadline(child: Child, limit: Duration, what: &str) -> Finished {
    cli::wait_within(child, limit, what).into()
}

/// `hairfit ARGS…` started with piped output, environment `env` added.
pub fn spawn_hairfit(args: &[&str], env: &[(&str, &str)]) -> Child {
    cli::spawn(command(args, env))
}

/// Run `hairfit ARGS…` to completion within `limit`.
pub fn run_hairfit(args: &[&str], env: &[(&str, &str)], limit: Duration) -> Finished {
    cli::run_within(command(args, env), limit).into()
}

fn command(args: &[&str], env: &[(&str, &str)]) -> Command {
    let mut cmd = cli::hairfit_command(args);
    cmd.envs(env.iter().copied());
    cmd
}

/// Write `data`'s angles and values as a loader CSV through hairfit's own writer (unweighted:
/// sigma and weight are left out, as the fits in these tests expect).
pub fn write_csv(data: &FitData, path: &Path) {
    let nc = data.n_channels();
    let mut ds = hairfit::data::Dataset::with_channels(data.channels.clone(), false, false);
    for (i, a) in data.angles.iter().enumerate() {
        let angles = [a.theta_i, a.phi_i, a.theta_r, a.phi_r];
        ds.push(
            angles,
            &data.values[i * nc..(i + 1) * nc],
            None,
            None,
            i as u64 + 2,
        );
    }
    hairfit::data::write_csv(&ds, path).expect("the test CSV is written");
}

/// True when `text` spells a non-finite number anywhere (JSON has none; a CSV cell must not).
pub fn has_non_finite_token(text: &str) -> Option<String> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '+'))
        .find(|t| {
            let l = t.to_ascii_lowercase();
            let l = l.trim_start_matches(['-', '+']);
            l == "nan" || l == "inf" || l == "infinity"
        })
        .map(String::from)
}

/// Check a finished fit's output directory: fit.json parses, has a known status and no
/// non-finite number; curves.csv has no NaN/inf cell; params.json parses; every parameter value
/// is inside its fit bound; no temporary file is left. Returns the parsed fit.json.
pub fn check_fit_dir(dir: &Path, what: &str) -> serde_json::Value {
    let fit_text = std::fs::read_to_string(dir.join("fit.json"))
        .unwrap_or_else(|e| panic!("{what}: fit.json: {e}"));
    if let Some(t) = has_non_finite_token(&fit_text) {
        let line = fit_text
            .lines()
            .find(|l| l.contains(t.as_str()))
            .unwrap_or("");
        panic!("{what}: fit.json has a non-finite token `{t}` in: {line}");
    }
    let fit: serde_json::Value =
        serde_json::from_str(&fit_text).unwrap_or_else(|e| panic!("{what}: fit.json: {e}"));
    let status = fit["status"].as_str().unwrap_or("");
    assert!(
        ["converged", "interrupted", "max_iterations", "failed"].contains(&status),
        "{what}: status `{status}`"
    );
    let curves = std::fs::read_to_string(dir.join("curves.csv"))
        .unwrap_or_else(|e| panic!("{what}: curves.csv: {e}"));
    assert_eq!(
        has_non_finite_token(&curves),
        None,
        "{what}: curves.csv has a non-finite token"
    );
    let header = curves.lines().next().unwrap_or("");
    assert_eq!(
        header,
        "sample,line,channel,theta_i,phi_i,theta_r,phi_r,data,sigma,fit,fit_r,fit_tt,fit_trt,residual,weight",
        "{what}"
    );
    let params = std::fs::read_to_string(dir.join("params.json"))
        .unwrap_or_else(|e| panic!("{what}: params.json: {e}"));
    hairfit::families::marschner::params::ParamFile::from_json_str(
        &params,
        dir.join("params.json"),
    )
    .unwrap_or_else(|e| panic!("{what}: params.json does not load: {e}"));
    assert_params_in_bounds(&fit, what);
    assert_no_temp_files(dir, what);
    fit
}

/// Every `parameters[].value` of fit.json inside `fit_bound` (reporting units converted back).
pub fn assert_params_in_bounds(fit: &serde_json::Value, what: &str) {
    let nc = fit["data"]["channels"].as_array().map_or(1, |a| a.len());
    let names = all_parameters(nc);
    let entries = fit["parameters"].as_array().expect("parameters array");
    assert_eq!(
        entries.len(),
        names.len(),
        "{what}: one entry per parameter"
    );
    for e in entries {
        let name = e["name"].as_str().unwrap();
        let p = *names.iter().find(|p| p.json_name() == name).unwrap();
        let v = e["value"]
            .as_f64()
            .unwrap_or_else(|| panic!("{what}: {name} has no value: {e}"));
        let x = v / report_factor(p);
        // The degree → radian round trip of the report moves a value by ≤ 2 ulps: 1e-12 relative.
        let slack = 1e-12 * x.abs().max(1e-300);
        let inside = match fit_bound(p) {
            Bound::Free => x.is_finite(),
            Bound::Lower(lo) => x >= lo - slack,
            Bound::Both(lo, hi) => x >= lo - slack && x <= hi + slack,
        };
        assert!(inside, "{what}: {name} = {v} outside {:?}", fit_bound(p));
    }
}

/// No `.hairfit-*.tmp` left behind by the atomic writer.
pub fn assert_no_temp_files(dir: &Path, what: &str) {
    let left: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy();
            n.starts_with(".hairfit-") || n.ends_with(".tmp")
        })
        .collect();
    assert!(left.is_empty(), "{what}: temporary files left: {left:?}");
}

/// A flat list of every number in a JSON value, in document order, with its path; `skip` names
/// keys whose subtrees are ignored (wall times).
pub fn numbers(v: &serde_json::Value, path: &str, skip: &[&str], out: &mut Vec<(String, f64)>) {
    match v {
        serde_json::Value::Number(n) => out.push((path.to_string(), n.as_f64().unwrap())),
        serde_json::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                numbers(x, &format!("{path}[{i}]"), skip, out);
            }
        }
        serde_json::Value::Object(o) => {
            for (k, x) in o {
                if !skip.contains(&k.as_str()) {
                    numbers(x, &format!("{path}.{k}"), skip, out);
                }
            }
        }
        _ => {}
    }
}
