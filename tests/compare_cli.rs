//! `hairfit compare` end to end: on data made by one family, the comparison prefers it, names
//! where the other misses, and writes both fit directories, compare.json and index.html.

use std::path::Path;
use std::process::{Command, Output};

use hairfit::compare::Comparison;

fn hairfit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hairfit"))
        .args(args)
        .output()
        .expect("the hairfit binary runs")
}

fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "hairfit failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// Synthesize with `model` and `params`, 2% relative noise, and compare.
fn compare_on(dir: &Path, model: &str, params: &str) -> (Comparison, String) {
    let truth = dir.join(format!("{model}.json"));
    std::fs::write(&truth, params).unwrap();
    let data = dir.join(format!("{model}.csv"));
    ok(&hairfit(&[
        "synth",
        "--model",
        model,
        "--params",
        p(&truth),
        "--rig",
        "azimuthal:incidences=15,30,45:steps=36",
        "--noise",
        "relative:0.02",
        "--seed",
        "3",
        "--output",
        p(&data),
    ]));
    let out = dir.join(format!("cmp_{model}"));
    let text = ok(&hairfit(&[
        "compare",
        p(&data),
        "--starts",
        "4",
        "--width-nodes",
        "256",
        "--no-progress",
        "--out",
        p(&out),
    ]));
    for f in [
        "compare.json",
        "index.html",
        "compare.svg",
        "compare.png",
        "marschner/fit.json",
        "marschner/params.json",
        "chiang/fit.json",
        "chiang/params.json",
        "chiang/index.html",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    (Comparison::load(&out.join("compare.json")).unwrap(), text)
}

#[test]
fn compare_prefers_the_family_that_made_the_data() {
    let dir = tempfile::tempdir().unwrap();
    let (m, text) = compare_on(
        dir.path(),
        "marschner",
        r#"{"sigma_a": [0.3, 0.5, 0.9], "alpha_r_deg": -7, "beta_r_deg": 7.5, "k_g": 2, "w_c_deg": 15, "eccentricity": 0.9}"#,
    );
    assert_eq!(m.better, "marschner", "{text}");
    assert!(m.delta_aic > 0.0);
    assert!(text.contains("Marschner fits better"), "{text}");
    assert!(
        m.findings.iter().any(|f| f.starts_with("Chiang misses")),
        "{:?}",
        m.findings
    );
    assert!(m.scale_note.contains("not comparable"));

    let (c, text) = compare_on(
        dir.path(),
        "chiang",
        r#"{"sigma_a": [0.3, 0.5, 0.9], "beta_m": 0.25, "beta_n": 0.35, "alpha_deg": -2.5}"#,
    );
    assert_eq!(c.better, "chiang", "{text}");
    assert!(c.delta_aic < 0.0);
    assert!(
        c.findings.iter().any(|f| f.starts_with("Marschner misses")),
        "{:?}",
        c.findings
    );
    // σ is in the data (relative noise), so χ² is a log-likelihood and AIC = χ² + 2k.
    for s in &c.models {
        assert!((s.aic - (s.chi2 + 2.0 * s.n_params as f64)).abs() < 1e-6 * s.aic.abs());
    }
}
