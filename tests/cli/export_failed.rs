//! `hairfit export` of a fit whose verdict is `failed`: its parameters are not a fit (no data
//! chose them), so the export is refused unless `--allow-failed`, which exports with a warning.

use crate::support::cli;

use cli::{hairfit, s, shipped, stderr, write};

/// sphere_1ch.csv with every radiance 0: a linear-space fit of it has nothing to fit and ends
/// `failed` with a result written (as a batch item of the same data does).
fn failed_fit(dir: &std::path::Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(shipped("sphere_1ch.csv")).unwrap();
    let mut col = None;
    let mut out = String::new();
    for line in text.lines() {
        if line.starts_with('#') {
            out += line;
        } else if let Some(c) = col {
            let mut cells: Vec<&str> = line.split(',').collect();
            cells[c] = "0";
            out += &cells.join(",");
        } else {
            col = line.split(',').position(|h| h == "radiance");
            out += line;
        }
        out += "\n";
    }
    let data = write(dir, "zero.csv", out);
    let fit_dir = dir.join("f");
    let r = hairfit(&[
        "fit",
        s(&data),
        "--space",
        "linear",
        "--starts",
        "2",
        "--no-progress",
        "--out",
        s(&fit_dir),
    ]);
    assert_eq!(r.status.code(), Some(1), "{}", stderr(&r));
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fit_dir.join("fit.json")).unwrap()).unwrap();
    assert_eq!(fit["verdict"], "failed");
    fit_dir
}

#[test]
fn a_failed_fit_is_exported_only_with_allow_failed_and_then_with_a_warning() {
    let tmp = tempfile::tempdir().unwrap();
    let fit_dir = failed_fit(tmp.path());
    let target = tmp.path().join("hair.pbrt");

    let refused = hairfit(&[
        "export",
        s(&fit_dir),
        "--to",
        "pbrt",
        "--output",
        s(&target),
    ]);
    cli::assert_fails_with(
        &refused,
        &["verdict is failed", "--allow-failed", "fit.json"],
    );
    assert!(!target.exists(), "a refused export writes nothing");

    let allowed = hairfit(&[
        "export",
        s(&fit_dir),
        "--to",
        "pbrt",
        "--output",
        s(&target),
        "--allow-failed",
    ]);
    let all = format!(
        "{}{}",
        String::from_utf8_lossy(&allowed.stdout),
        stderr(&allowed)
    );
    // Past the verdict check: either exported with the warning, or stopped by the mapping fit
    // itself (an all-zero fit's scale 0 has no log), never by the verdict again.
    assert!(!all.contains("verdict is failed"), "{all}");
    if allowed.status.success() {
        assert!(
            all.contains("not a fit"),
            "the warning says what was exported: {all}"
        );
        assert!(target.exists());
    } else {
        assert!(all.contains("mapping fit"), "{all}");
        assert!(!target.exists(), "a failed export writes nothing");
    }
}
