//! `hairfit load` end to end: the summary, `--json`, and errors on stderr with a failing status.

#[path = "support/cli.rs"]
mod cli;

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
