//! `hairfit compare` end to end: on data made by one family, the comparison prefers it, names
//! where the other misses, and writes both fit directories, compare.json and index.html.

#[path = "support/cli.rs"]
mod cli;

use cli::{hairfit_ok, s as p, stdout, write};
use std::path::Path;

use hairfit::compare::Comparison;

/// Synthesize with `model` and `params`, 2% relative noise, and compare.
fn compare_on(dir: &Path, model: &str, params: &str) -> (Comparison, String) {
    let truth = write(dir, &format!("{model}.json"), params);
    let data = dir.join(format!("{model}.csv"));
    hairfit_ok(&[
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
    ]);
    let out = dir.join(format!("cmp_{model}"));
    let text = stdout(&hairfit_ok(&[
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

/// A small 3-channel Marschner dataset (36 samples) for the tests of compare's rules, which
/// need data but no particular fit.
fn small_data(dir: &Path) -> std::path::PathBuf {
    let truth = write(
        dir,
        "truth.json",
        r#"{"sigma_a": [0.3, 0.5, 0.9], "alpha_r_deg": -7, "beta_r_deg": 7.5, "k_g": 2, "w_c_deg": 15, "eccentricity": 0.9}"#,
    );
    let data = dir.join("d.csv");
    hairfit_ok(&[
        "synth",
        "--params",
        p(&truth),
        "--rig",
        "azimuthal:incidences=15,30,45:steps=12",
        "--noise",
        "relative:0.02",
        "--output",
        p(&data),
    ]);
    data
}

/// compare's quickest options, then `extra`.
fn quick_compare<'a>(data: &'a Path, out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let mut a = vec![
        "compare",
        p(data),
        "--starts",
        "2",
        "--width-nodes",
        "128",
        "--intervals",
        "linear",
        "--no-progress",
        "--out",
        p(out),
    ];
    a.extend_from_slice(extra);
    a
}

/// Every path under `dir` whose name marks a lock or a staging directory.
fn bookkeeping_inside(dir: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let entry = entry.unwrap();
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.contains("hairfit-lock") || name.contains("hairfit-stage") {
            found.push(entry.path().display().to_string());
        }
        if entry.path().is_dir() {
            found.extend(bookkeeping_inside(&entry.path()));
        }
    }
    found
}

/// The walkthrough found `.marschner.hairfit-lock` and `.chiang.hairfit-lock` inside a
/// finished compare's --out: each fit directory was locked on its own, beside it, i.e. inside
/// DIR. DIR is now published as one set, as `fit` publishes its --out: its one lock sits
/// beside DIR, and a rerun into it replaces it whole.
#[test]
fn a_finished_compare_leaves_no_lock_or_staging_inside_its_out() {
    let dir = tempfile::tempdir().unwrap();
    let data = small_data(dir.path());
    let out = dir.path().join("cmp");
    for run in ["first", "rerun"] {
        hairfit_ok(&quick_compare(&data, &out, &[]));
        assert_eq!(bookkeeping_inside(&out), Vec::<String>::new(), "{run}");
        for f in ["compare.json", "marschner/fit.json", "chiang/index.html"] {
            assert!(out.join(f).is_file(), "{run}: {f} missing");
        }
        let beside: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains("hairfit-"))
            .collect();
        assert_eq!(
            beside,
            [".cmp.hairfit-lock"],
            "{run}: one lock, beside --out"
        );
    }
    // Each fit directory is still a fit's directory of its own.
    hairfit_ok(&["report", p(&out.join("chiang"))]);
}

/// `compare --out FILE` said "File exists (os error 17)"; it now says what `fit` says, naming
/// the option and the file, and leaves the file alone.
#[test]
fn compare_out_that_is_a_file_is_refused_like_fit_does() {
    let dir = tempfile::tempdir().unwrap();
    let data = small_data(dir.path());
    let file = write(dir.path(), "notes.txt", "mine");
    let out = cli::hairfit(&quick_compare(&data, &file, &[]));
    cli::assert_fails_with(
        &out,
        &["--out", "notes.txt", "that is a file, not a directory"],
    );
    assert!(
        !cli::stderr(&out).contains("os error"),
        "{}",
        cli::stderr(&out)
    );
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
}

/// `compare --fix k_g=2` failed only after the Marschner fit had run and been written (the
/// Chiang model has no k_g). Every --fix is now checked for both families before anything
/// is fitted: a parameter of one family names the family that lacks it and lists what both
/// have; nothing is written.
#[test]
fn compare_fix_is_checked_for_both_families_before_any_fit() {
    let dir = tempfile::tempdir().unwrap();
    let data = small_data(dir.path());
    let out = dir.path().join("cmp");
    let both = "sigma_a (every channel), sigma_a[c] (one channel), eta";
    for (fix, needles) in [
        (
            "k_g=2",
            &[
                "`k_g` is a Marschner parameter the Chiang model does not have",
                both,
            ][..],
        ),
        (
            "alpha_deg=-2",
            &[
                "`alpha_deg` is a Chiang parameter the Marschner model does not have",
                "--model chiang --fix alpha_deg=-2",
            ][..],
        ),
        (
            "bogus=1",
            &["neither model family has a parameter `bogus`", both][..],
        ),
        // Known only once the data load (3 channels), still before either fit.
        (
            "sigma_a[5]=0.3",
            &[
                "`sigma_a[5]` names a channel the data do not have",
                "3 channels",
            ][..],
        ),
    ] {
        let run = cli::hairfit(&quick_compare(&data, &out, &["--fix", fix]));
        cli::assert_fails_with(&run, needles);
        assert!(!out.exists(), "--fix {fix}: nothing may be written");
    }
    // What both families have is fixed in both fits.
    hairfit_ok(&quick_compare(&data, &out, &["--fix", "eta=1.6"]));
    let c = Comparison::load(&out.join("compare.json")).unwrap();
    for m in &c.models {
        let eta = serde_json::to_value(&m.params).unwrap()["eta"].as_f64();
        assert_eq!(eta, Some(1.6), "{}", m.family);
    }
}
