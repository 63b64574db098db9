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
    // Past the verdict check (the all-zero fit's scale 0 may still stop the mapping fit, which
    // is that fit's own trouble): the export with sane parameters is the test below.
    assert!(
        !all.contains("or pass --allow-failed"),
        "not refused again: {all}"
    );
    assert!(
        allowed.status.success() || all.contains("mapping fit"),
        "--allow-failed got past the verdict check: {all}"
    );
}

/// A fit with sane parameters whose fit.json says `failed` (a copied fit directory with its
/// verdict tampered, as a fit stopped before it moved would say): `--allow-failed` exports it,
/// exit 0, with the warning on stderr and the verdict in the file's header.
#[test]
fn allow_failed_exports_a_failed_fit_with_sane_parameters_and_warns() {
    let tmp = tempfile::tempdir().unwrap();
    let fit_dir = tmp.path().join("f");
    cli::hairfit_ok(&[
        "fit",
        s(&shipped("azimuthal_rgb.csv")),
        "--starts",
        "2",
        "--intervals",
        "linear",
        "--no-progress",
        "--out",
        s(&fit_dir),
    ]);
    let fit_json = fit_dir.join("fit.json");
    let mut fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&fit_json).unwrap()).unwrap();
    fit["verdict"] = "failed".into();
    fit["reasons"] = serde_json::json!(["no progress from the start point"]);
    std::fs::write(&fit_json, serde_json::to_string_pretty(&fit).unwrap()).unwrap();
    let target = tmp.path().join("hair.pbrt");
    let export = |extra: &[&str]| {
        let mut args = vec![
            "export",
            s(&fit_dir),
            "--to",
            "pbrt",
            "--output",
            s(&target),
        ];
        args.extend_from_slice(extra);
        hairfit(&args)
    };

    cli::assert_fails_with(
        &export(&[]),
        &[
            "verdict is failed (no progress from the start point)",
            "--allow-failed",
        ],
    );
    assert!(!target.exists(), "a refused export writes nothing");

    let allowed = export(&["--allow-failed"]);
    let err = stderr(&allowed);
    assert_eq!(allowed.status.code(), Some(0), "{err}");
    assert!(
        err.contains("warning:")
            && err.contains("exported because of --allow-failed: these parameters are not a fit"),
        "{err}"
    );
    let text = std::fs::read_to_string(&target).unwrap();
    assert!(
        text.contains("verdict failed"),
        "the header says so: {text}"
    );
    assert!(text.contains("MakeNamedMaterial"), "{text}");
}
