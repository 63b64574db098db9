//! `hairfit load` end to end: the summary, `--json`, and errors on stderr with a failing status.

use crate::support::cli;

use cli::hairfit;
use std::path::Path;

#[test]
fn load_prints_the_documented_scan_report() {
    let out = hairfit(&[
        "load",
        "data/scan_example.txt",
        "--columns",
        "phi_r,theta_r,radiance",
        "--fixed",
        "theta_i=20,phi_i=0",
        "--missing",
        "?",
        "--map",
        "theta_r=90-x",
    ]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("169 rows read, 167 accepted, 2 rejected"),
        "{text}"
    );
    assert!(text.contains("missing value: 2 (lines 152, 165)"), "{text}");
}

#[test]
fn load_json_prints_a_machine_readable_report() {
    let out = hairfit(&["load", "tests/data/loader/messy.csv", "--json"]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["rows_read"], 14);
    assert_eq!(v["accepted"], 4);
    assert_eq!(
        v["rejected"]["missing_value"]["first_lines"],
        serde_json::json!([4, 5])
    );
}

#[test]
fn load_errors_go_to_stderr_with_file_line_column() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.csv");
    std::fs::write(&p, "theta_i,phi_i,theta_r,phi_r,radiance\n1,2,3,4,five\n").unwrap();
    let out = hairfit(&["load", p.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(out.stdout.is_empty());
    let err = String::from_utf8(out.stderr).unwrap();
    let place = format!("{}:2:5:", Path::new(&p).display());
    assert!(
        err.contains(&place) && err.contains("`five` is not a number"),
        "{err}"
    );
}

/// A parameter file (or a fit.json, or a synth truth file) given as DATA said "missing field
/// `samples`": `load`, `fit` and `compare` now say what the file is and where it goes.
#[test]
fn a_parameter_file_given_as_data_is_named_as_such() {
    let dir = tempfile::tempdir().unwrap();
    let params = cli::write(
        dir.path(),
        "params.json",
        r#"{"sigma_a": [0.3, 0.5, 0.9], "alpha_r_deg": -7, "beta_r_deg": 7.5, "k_g": 2, "w_c_deg": 15}"#,
    );
    let chiang = cli::write(
        dir.path(),
        "chiang.json",
        r#"{"model": "chiang", "sigma_a": 0.3, "beta_m": 0.25, "beta_n": 0.35, "alpha_deg": -2}"#,
    );
    // A table family's file may have no sigma_a: its tag marks it.
    let karis = cli::write(
        dir.path(),
        "karis.json",
        r#"{"model": "karis", "base_color": 0.5, "roughness": 0.4}"#,
    );
    let out = dir.path().join("out");
    let p = |path: &Path| path.to_str().unwrap().to_string();
    for (file, model) in [
        (&params, ""),
        (&chiang, " --model chiang"),
        (&karis, " --model karis"),
    ] {
        let f = p(file);
        for args in [
            vec!["load", f.as_str()],
            vec!["fit", f.as_str(), "--out", out.to_str().unwrap()],
            vec!["compare", f.as_str(), "--out", out.to_str().unwrap()],
        ] {
            let run = hairfit(&args);
            cli::assert_fails_with(
                &run,
                &[
                    &format!("{f}: this looks like a parameter file"),
                    "not a dataset",
                    &format!("hairfit eval{model} --params {f}"),
                    &format!("hairfit synth{model} --params {f}"),
                ],
            );
            assert!(!cli::stderr(&run).contains("missing field"), "{args:?}");
            assert!(!out.exists(), "{args:?}");
        }
    }
    // synth's truth sidecar points at its samples; a fit.json at the data it was fitted to.
    let data = dir.path().join("d.csv");
    cli::hairfit_ok(&[
        "synth",
        "--params",
        &p(&params),
        "--rig",
        "azimuthal:incidences=30:steps=24",
        "--output",
        &p(&data),
    ]);
    let truth = dir.path().join("d.truth.json");
    cli::assert_fails_with(
        &hairfit(&["load", &p(&truth)]),
        &[
            "this is a synth truth file",
            &format!("its samples are in {}", p(&data)),
        ],
    );
    cli::hairfit_ok(&[
        "fit",
        &p(&data),
        "--starts",
        "2",
        "--intervals",
        "linear",
        "--no-progress",
        "--out",
        &p(&out),
    ]);
    cli::assert_fails_with(
        &hairfit(&["load", &p(&out.join("fit.json"))]),
        &[
            "this is a fit result (fit.json), not a dataset",
            &format!("fitted to are {}", p(&data)),
            &format!("hairfit report {}", p(&out)),
        ],
    );
}
