//! `hairfit report` from the command line: a fit directory renders; a missing or malformed
//! fit.json fails with an error naming the file (and line and column), never a panic.

use crate::support::cli;

use cli::{failed, hairfit, hairfit_ok, s, stderr, write};

#[test]
fn report_of_a_demo_fit_writes_index_html() {
    let dir = tempfile::tempdir().unwrap();
    let fit_dir = dir.path().join("demo");
    hairfit_ok(&[
        "demo",
        "--starts",
        "2",
        "--no-progress",
        "--out",
        s(&fit_dir),
    ]);
    let out = hairfit(&["report", s(&fit_dir)]);
    let stderr = stderr(&out);
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
    hairfit_ok(&["report", "--linear", s(&fit_dir)]);
}

#[test]
fn a_missing_or_malformed_fit_json_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let stderr = failed(&hairfit(&["report", s(dir.path())]));
    assert!(stderr.contains("fit.json"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");

    write(
        dir.path(),
        "fit.json",
        "{\n  \"hairfit_version\": \"0.1.0\",\n  \"status\": \"sideways\"\n}\n",
    );
    let stderr = failed(&hairfit(&["report", s(dir.path())]));
    // The bad status value is on line 3.
    assert!(stderr.contains("fit.json:3:"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// `report` has no --out or --force: given a file, a folder without fit.json or a compare
/// directory, it says what it takes (and for a compare directory, which fit to report).
#[test]
fn what_is_not_a_fit_directory_is_named_as_such() {
    let dir = tempfile::tempdir().unwrap();
    let file = write(
        dir.path(),
        "data.csv",
        "theta_i,phi_i,theta_r,phi_r,radiance\n",
    );
    let stderr = failed(&hairfit(&["report", s(&file)]));
    assert!(
        stderr.contains("is a file") && stderr.contains("fit.json"),
        "{stderr}"
    );
    let stderr = failed(&hairfit(&["report", s(dir.path())]));
    assert!(stderr.contains("not a fit's directory"), "{stderr}");
    assert!(!stderr.contains("--force"), "{stderr}");
    let compare = dir.path().join("cmp");
    std::fs::create_dir_all(compare.join("marschner")).unwrap();
    write(&compare.join("marschner"), "fit.json", "{}");
    let stderr = failed(&hairfit(&["report", s(&compare)]));
    assert!(
        stderr.contains("compare directory") && stderr.contains("marschner"),
        "{stderr}"
    );
    // `compare --models karis,deon` writes no marschner or chiang folder: any family's counts.
    let tables = dir.path().join("cmp_tables");
    std::fs::create_dir_all(tables.join("deon")).unwrap();
    write(&tables.join("deon"), "fit.json", "{}");
    let stderr = failed(&hairfit(&["report", s(&tables)]));
    assert!(
        stderr.contains("compare directory") && stderr.contains("deon"),
        "{stderr}"
    );
}
