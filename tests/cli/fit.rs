//! `hairfit demo` / `hairfit fit` end to end through the binary: the output files of
//! contracts.md, bit-identical numbers with 1 and 2 threads, and a fit of the demo's own CSV.

use crate::support::cli;

use hairfit::families::marschner::params::ParameterFile as _;
use std::path::Path;

/// Run hairfit on `threads` rayon threads; it must succeed.
fn hairfit(args: &[&str], threads: &str) -> std::process::Output {
    let mut command = cli::hairfit_command(args);
    command.env("RAYON_NUM_THREADS", threads);
    cli::succeeded(cli::run_within(command, cli::DEFAULT_LIMIT).0, args)
}

/// fit.json, which holds no wall-clock field (those are in timing.json, the only file allowed
/// to differ between runs).
fn numbers(dir: &Path) -> serde_json::Value {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("fit.json")).unwrap()).unwrap();
    assert!(v.get("wall_time_s").is_none(), "fit.json holds a wall time");
    for t in v["trace"].as_array().unwrap() {
        assert!(
            t.get("wall_s").is_none(),
            "fit.json's trace holds a wall time"
        );
    }
    if let Some(r) = v["data"].as_object_mut() {
        r.remove("file");
        r.remove("load_report");
    }
    v
}

#[test]
fn demo_is_bit_identical_with_one_and_two_threads() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("t1"), tmp.path().join("t2"));
    hairfit(&["demo", "--out", a.to_str().unwrap()], "1");
    hairfit(&["demo", "--out", b.to_str().unwrap()], "2");
    // serde_json's Value compares f64 exactly: any difference in the last bit fails.
    assert_eq!(numbers(&a), numbers(&b));
    for f in ["params.json", "curves.csv"] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f} differs between 1 and 2 threads"
        );
    }
}

#[test]
fn robust_loss_and_particle_swarm_are_bit_identical_with_one_and_two_threads() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("t1"), tmp.path().join("t2"));
    let args = |d: &Path| {
        vec![
            "demo".to_string(),
            "--out".into(),
            d.to_str().unwrap().into(),
            "--global".into(),
            "pso".into(),
            "--loss".into(),
            "cauchy".into(),
            "--starts".into(),
            "4".into(),
        ]
    };
    let run = |d: &Path, t: &str| {
        let v = args(d);
        hairfit(&v.iter().map(String::as_str).collect::<Vec<_>>(), t)
    };
    run(&a, "1");
    run(&b, "2");
    assert_eq!(numbers(&a), numbers(&b));
}

#[test]
fn fit_of_the_demo_csv_writes_the_contract_files() {
    let tmp = tempfile::tempdir().unwrap();
    let demo = tmp.path().join("demo");
    let out = hairfit(&["demo", "--out", demo.to_str().unwrap()], "2");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("hairfit fit: converged"), "{text}");

    let fitdir = tmp.path().join("fits").join("again");
    let data = demo.join("data.csv");
    let out = hairfit(
        &[
            "fit",
            data.to_str().unwrap(),
            "--out",
            fitdir.to_str().unwrap(),
            "--fix",
            "eccentricity=0.9",
            "--loss",
            "huber",
            "--loss-scale",
            "3",
        ],
        "2",
    );
    let summary = String::from_utf8_lossy(&out.stdout);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fitdir.join("fit.json")).unwrap()).unwrap();
    for key in [
        "hairfit_version",
        "status",
        "data",
        "model",
        "options",
        "params",
        "parameters",
        "scale",
        "correlation",
        "warnings",
        "residuals",
        "trace",
    ] {
        assert!(v.get(key).is_some(), "fit.json lacks `{key}`");
    }
    // The run's wall-clock times are kept apart, in timing.json.
    let timing: hairfit::files::Timing =
        hairfit::files::read_json(&fitdir.join("timing.json"), "timing.json").unwrap();
    assert!(timing.wall_time_s > 0.0, "{timing:?}");
    let stages: Vec<&str> = timing.stages.iter().map(|s| s.stage.as_str()).collect();
    // The solver stages, the statistics at the optimum, then `--intervals auto` profiles a fit
    // this small.
    assert_eq!(
        stages,
        [
            "multistart",
            "polish",
            "standard_errors",
            "verdict",
            "curves",
            "profile"
        ]
    );
    assert_eq!(v["status"], "converged", "{summary}");
    assert_eq!(v["data"]["n_samples"], 2340);
    assert_eq!(v["data"]["load_report"]["accepted"], 2340);
    assert_eq!(v["options"]["loss"], "huber");
    assert_eq!(v["options"]["fixed"]["eccentricity"], 0.9);
    let ecc = v["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "eccentricity")
        .unwrap();
    assert_eq!(ecc["status"], "fixed");
    assert_eq!(ecc["value"], 0.9);
    // params.json is a plain parameter file that `hairfit eval` accepts.
    hairfit::families::marschner::params::ParamFile::load(fitdir.join("params.json"))
        .expect("valid ParamFile");
    let curves = std::fs::read_to_string(fitdir.join("curves.csv")).unwrap();
    let mut lines = curves.lines();
    assert_eq!(
        lines.next().unwrap(),
        "sample,line,channel,theta_i,phi_i,theta_r,phi_r,data,sigma,fit,fit_r,fit_tt,fit_trt,residual,weight"
    );
    assert_eq!(lines.count(), 2340 * 3);
}

#[test]
fn bad_fix_is_a_clear_error() {
    let out = cli::hairfit(&[
        "demo",
        "--out",
        "/nonexistent/never",
        "--fix",
        "eccentricity=0.5",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("eccentricity") && err.contains("domain") && err.contains("(0.70711, 1]"),
        "{err}"
    );
}
