//! `hairfit report` from the command line: a fit directory renders; a missing or malformed
//! fit.json fails with an error naming the file (and line and column), never a panic.

#[path = "support/cli.rs"]
mod cli;

use std::process::Command;

fn hairfit() -> Command {
    cli::hairfit_command(&[])
}

#[test]
fn report_of_a_demo_fit_writes_index_html() {
    let dir = tempfile::tempdir().unwrap();
    let fit_dir = dir.path().join("demo");
    let out = hairfit()
        .args(["demo", "--starts", "2", "--no-progress", "--out"])
        .arg(&fit_dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = hairfit().arg("report").arg(&fit_dir).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("index.html"), "{stderr}");
    // The fit's own model settings reproduce its fit column: no mismatch note.
    assert!(!stderr.contains("differs"), "{stderr}");
    for f in [
        "index.html",
        "curves.png",
        "curves.svg",
        "residuals.png",
        "polar.png",
    ] {
        assert!(fit_dir.join(f).is_file(), "{f} missing");
    }
    let out = hairfit()
        .arg("report")
        .arg("--linear")
        .arg(&fit_dir)
        .output()
        .unwrap();
    assert!(out.status.success());
}

#[test]
fn a_missing_or_malformed_fit_json_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = hairfit().arg("report").arg(dir.path()).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("fit.json"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");

    std::fs::write(
        dir.path().join("fit.json"),
        "{\n  \"hairfit_version\": \"0.1.0\",\n  \"status\": \"sideways\"\n}\n",
    )
    .unwrap();
    let out = hairfit().arg("report").arg(dir.path()).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    // The bad status value is on line 3.
    assert!(stderr.contains("fit.json:3:"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}
