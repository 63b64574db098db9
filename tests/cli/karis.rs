//! `--model karis` through the binary: noise-free synthetic data recovered to 1e-6, the demo's
//! noisy fit within its standard errors with verdict good, the scatter term fitted only when
//! switched on, `--free eta`, and the errors for another family's options or an unknown term.

use crate::support::cli;

use std::path::Path;

use cli::{hairfit, hairfit_ok, s, stderr, stdout, write};
use serde_json::Value;

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Synthesize noise-free karis data from `truth` on 1500 random directions (3 channels at
/// different exposures) and fit it with `extra` options; fit.json.
fn synth_and_fit(dir: &Path, truth: &str, extra: &[&str]) -> Value {
    let params = write(dir, "truth.json", truth);
    let data = dir.join("d.csv");
    let mut synth = vec![
        "synth",
        "--model",
        "karis",
        "--params",
        s(&params),
        "--rig",
        "sphere:n=1500:max=80",
        "--scale",
        "1,2,0.5",
        "--seed",
        "3",
        "--output",
        s(&data),
    ];
    let terms: Vec<&str> = extra
        .windows(2)
        .filter(|w| w[0] == "--terms")
        .flat_map(|w| w.to_vec())
        .collect();
    synth.extend(&terms);
    hairfit_ok(&synth);
    let out = dir.join("fit");
    let mut fit = vec!["fit", s(&data), "--model", "karis", "--out", s(&out)];
    fit.extend(extra);
    hairfit_ok(&fit);
    read_json(&out.join("fit.json"))
}

/// Every free parameter of `fit` equals `truth`'s to `tol` relative.
fn assert_recovered(fit: &Value, truth: &Value, tol: f64) {
    for p in fit["parameters"].as_array().unwrap() {
        let name = p["name"].as_str().unwrap();
        if p["status"] != "free" {
            continue;
        }
        let (key, channel) = match name.split_once('[') {
            Some((k, c)) => (k, Some(c.trim_end_matches(']').parse::<usize>().unwrap())),
            None => (name, None),
        };
        let want = match channel {
            Some(c) => truth[key][c].as_f64().unwrap(),
            None => truth[key].as_f64().unwrap(),
        };
        let got = p["value"].as_f64().unwrap();
        assert!(((got - want) / want).abs() < tol, "{name}: {got} vs {want}");
    }
}

/// Noise-free data of the default terms (R, TT, TRT) give back every free parameter to 1e-6
/// relative — Base Color per channel, Roughness, Specular — with the per-channel scales
/// projected out; Scatter, Backlit, η and the shift are held at their table values.
#[test]
fn noise_free_data_are_recovered() {
    let dir = tempfile::tempdir().unwrap();
    let truth = r#"{"model": "karis", "base_color": [0.2, 0.45, 0.7], "roughness": 0.4,
        "specular": 0.35, "scatter": 0}"#;
    let fit = synth_and_fit(dir.path(), truth, &[]);
    let truth: Value = serde_json::from_str(truth).unwrap();
    assert_recovered(&fit, &truth, 1e-6);
    let status = |name: &str| {
        let all = fit["parameters"].as_array().unwrap();
        let p = all.iter().find(|p| p["name"] == name).unwrap();
        p["status"].as_str().unwrap().to_string()
    };
    for held in ["scatter", "backlit", "eta", "shift_deg"] {
        assert_eq!(status(held), "fixed", "{held}");
    }
    assert_eq!(fit["terms"], serde_json::json!(["R", "TT", "TRT"]));
}

/// With `--terms R,TT,TRT,scatter` the Scatter weight is fitted too (noise-free: 1e-6).
#[test]
fn the_scatter_term_is_fitted_when_switched_on() {
    let dir = tempfile::tempdir().unwrap();
    let truth = r#"{"model": "karis", "base_color": [0.15, 0.3, 0.6], "roughness": 0.55,
        "specular": 0.6, "scatter": 0.25}"#;
    let fit = synth_and_fit(dir.path(), truth, &["--terms", "R,TT,TRT,scatter"]);
    let truth: Value = serde_json::from_str(truth).unwrap();
    assert_recovered(&fit, &truth, 1e-6);
    let scatter = (fit["parameters"].as_array().unwrap().iter())
        .find(|p| p["name"] == "scatter")
        .unwrap()
        .clone();
    assert_eq!(scatter["status"], "free");
}

/// `--free eta` frees η (the engine's fixed 1.55) and the noise-free fit finds the truth's 1.6.
#[test]
fn free_eta_fits_the_index() {
    let dir = tempfile::tempdir().unwrap();
    let truth = r#"{"model": "karis", "base_color": [0.3, 0.5, 0.8], "roughness": 0.45,
        "specular": 0.5, "scatter": 0, "eta": 1.6}"#;
    let fit = synth_and_fit(dir.path(), truth, &["--free", "eta"]);
    let truth: Value = serde_json::from_str(truth).unwrap();
    assert_recovered(&fit, &truth, 1e-6);
    assert!((fit["params"]["eta"].as_f64().unwrap() - 1.6).abs() < 1e-6);
}

/// `hairfit demo --model karis` (2% noise, 3 channels): verdict good, and every free parameter
/// within 3 standard errors of the truth (for 5 parameters with correct errors, all fall within
/// 3 SE with probability 0.987; the seed is fixed, so this is deterministic).
#[test]
fn the_demo_ends_good_within_its_standard_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let run = hairfit_ok(&["demo", "--model", "karis", "--out", s(&out)]);
    assert!(stdout(&run).contains("verdict: good"), "{}", stdout(&run));
    let fit = read_json(&out.join("fit.json"));
    let truth = read_json(&out.join("truth.json"))["params"].clone();
    let mut free = 0;
    for p in fit["parameters"].as_array().unwrap() {
        if p["status"] != "free" {
            continue;
        }
        free += 1;
        let name = p["name"].as_str().unwrap();
        let (key, c) = match name.split_once('[') {
            Some((k, c)) => (k, c.trim_end_matches(']').parse::<usize>().ok()),
            None => (name, None),
        };
        let want = c.map_or(&truth[key], |c| &truth[key][c]).as_f64().unwrap();
        let (got, se) = (
            p["value"].as_f64().unwrap(),
            p["std_error"].as_f64().unwrap(),
        );
        assert!(
            (got - want).abs() < 3.0 * se,
            "{name}: {got} ± {se} vs {want}"
        );
    }
    assert_eq!(free, 5, "base_color x3, roughness, specular");
}

/// Another family's options are errors naming whose they are; an unknown term lists karis's.
#[test]
fn other_families_options_and_unknown_terms_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(
        dir.path(),
        "p.json",
        r#"{"model": "karis", "base_color": 0.4, "roughness": 0.5, "specular": 0.5, "scatter": 0}"#,
    );
    let angles = write(
        dir.path(),
        "a.csv",
        "theta_i,phi_i,theta_r,phi_r\n20,0,-15,30\n",
    );
    let eval = |extra: &[&str]| {
        let mut args = vec![
            "eval",
            "--model",
            "karis",
            "--params",
            s(&params),
            "--input",
            s(&angles),
        ];
        args.extend(extra);
        hairfit(&args)
    };
    cli::assert_fails_with(&eval(&["--lobes", "R,TT"]), &["--lobes", "marschner"]);
    cli::assert_fails_with(
        &eval(&["--width-nodes", "64"]),
        &["--width-nodes", "chiang"],
    );
    cli::assert_fails_with(
        &eval(&["--terms", "R,MS"]),
        &["unknown karis term `MS`", "R, TT, TRT, scatter"],
    );
    let ok = eval(&["--terms", "R,scatter"]);
    assert!(ok.status.success(), "{}", stderr(&ok));
    let marschner = write(
        dir.path(),
        "m.json",
        r#"{"eta": 1.55, "sigma_a": 0.5, "alpha_r_deg": -5, "beta_r_deg": 7.5, "k_g": 2,
            "w_c_deg": 15, "eccentricity": 0.9}"#,
    );
    let out = hairfit(&[
        "eval",
        "--model",
        "karis",
        "--params",
        s(&marschner),
        "--input",
        s(&angles),
    ]);
    cli::assert_fails_with(&out, &["marschner parameter file", "--model marschner"]);
    let out = hairfit(&["demo", "--model", "karis", "--fix", "shift=2", "--out", "x"]);
    cli::assert_fails_with(&out, &["shift"]);
}
