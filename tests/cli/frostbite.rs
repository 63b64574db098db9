//! `--model frostbite` through the binary: synth → fit recovering noise-free truth, the demo's
//! verdict and standard errors, `--terms` switching lobes (and the parameters fitted), and the
//! errors for another family's options, unknown terms and values outside the domain.

use crate::support::cli;

use std::path::Path;

use cli::{failed, hairfit, hairfit_ok, stdout};
use hairfit::files::{FitJson, Truth};

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// `hairfit CMD --model frostbite ARGS…`, which must succeed.
fn frostbite(cmd: &str, args: &[&str]) -> std::process::Output {
    let mut all = vec![cmd, "--model", "frostbite"];
    all.extend_from_slice(args);
    hairfit_ok(&all)
}

const TRUTH: &str = r#"{"model": "frostbite", "base_color": [0.15, 0.4, 0.75],
    "smoothness": 0.88, "radial_smoothness": 0.65, "cuticle_angle_deg": 2.5}"#;

fn value(fit: &FitJson, name: &str) -> (f64, Option<f64>) {
    let e = fit.parameters.iter().find(|p| p.name == name).unwrap();
    (e.value.unwrap(), e.std_error)
}

/// Noise-free data of `synth --model frostbite` is recovered by `fit --model frostbite`: the
/// same model makes and fits the data, so the truth is an exact zero of the residual and 1e-6
/// relative leaves room only for the solver's stopping tolerance.
#[test]
fn synth_then_fit_recovers_noise_free_truth() {
    let dir = tempfile::tempdir().unwrap();
    let truth = write(dir.path(), "truth.json", TRUTH);
    let data = dir.path().join("d.csv");
    frostbite(
        "synth",
        &[
            "--params",
            p(&truth),
            "--rig",
            "sphere:n=1500:max=80",
            "--scale",
            "2,1.5,1",
            "--seed",
            "4",
            "--output",
            p(&data),
        ],
    );
    let t = Truth::load(&dir.path().join("d.truth.json")).unwrap();
    assert_eq!(t.params.family(), hairfit::families::ModelFamily::Frostbite);
    let out = dir.path().join("fit");
    let summary = stdout(&frostbite(
        "fit",
        &[p(&data), "--starts", "4", "--no-progress", "--out", p(&out)],
    ));
    assert!(summary.contains("model: frostbite"), "{summary}");
    let fit = FitJson::load(&out.join("fit.json")).unwrap();
    for (name, want) in [
        ("base_color[0]", 0.15),
        ("base_color[1]", 0.4),
        ("base_color[2]", 0.75),
        ("smoothness", 0.88),
        ("radial_smoothness", 0.65),
        ("cuticle_angle_deg", 2.5),
    ] {
        let (got, _) = value(&fit, name);
        assert!((got - want).abs() <= 1e-6 * want, "{name}: {got} vs {want}");
    }
    for (c, s) in [2.0, 1.5, 1.0].iter().enumerate() {
        let v = fit.scale[c].value.unwrap();
        assert!((v - s).abs() <= 1e-6 * s, "scale {c}: {v}");
    }
    // η is held at HDRP's 1.55 unless asked for.
    let eta = fit.parameters.iter().find(|p| p.name == "eta").unwrap();
    assert_eq!(eta.value, Some(1.55));
}

/// The demo (2% noise, 2340 samples × 3 channels) ends with verdict good and every fitted
/// parameter within 3 standard errors of the truth.
#[test]
fn demo_recovers_the_truth_within_its_standard_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let text = stdout(&frostbite("demo", &["--no-progress", "--out", p(&out)]));
    assert!(text.contains("verdict: good"), "{text}");
    let fit = FitJson::load(&out.join("fit.json")).unwrap();
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("truth.json")).unwrap()).unwrap();
    let params = &truth["params"];
    for e in fit.parameters.iter().filter(|e| e.std_error.is_some()) {
        let (base, channel) = match e.name.split_once('[') {
            Some((b, c)) => (b, c.trim_end_matches(']').parse::<usize>().ok()),
            None => (e.name.as_str(), None),
        };
        let want = match channel {
            Some(c) => params[base][c].as_f64().unwrap(),
            None => params[base].as_f64().unwrap(),
        };
        let (got, se) = (e.value.unwrap(), e.std_error.unwrap());
        assert!(
            (got - want).abs() <= 3.0 * se,
            "{}: {got} ± {se} vs {want}",
            e.name
        );
    }
    // Its fit exports to Unity (S is non-negative everywhere, which the export checks).
    let unity = dir.path().join("other").join("u.json");
    std::fs::create_dir_all(unity.parent().unwrap()).unwrap();
    hairfit_ok(&["export", p(&out), "--to", "unity", "--output", p(&unity)]);
    assert!(unity.is_file());
}

/// The family's defaults (docs/frostbite.md's table) synthesise on a dense sphere rig: synth
/// refuses negative or non-finite S, which a tabulated N_p produced in its tails.
#[test]
fn synth_takes_the_defaults_on_a_dense_sphere() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(
        dir.path(),
        "defaults.json",
        r#"{"model": "frostbite", "base_color": 0.5, "smoothness": 0.85,
            "radial_smoothness": 0.7, "cuticle_angle_deg": 3}"#,
    );
    let csv = dir.path().join("d.csv");
    frostbite(
        "synth",
        &[
            "--params",
            p(&params),
            "--rig",
            "sphere:n=400:max=85",
            "--output",
            p(&csv),
        ],
    );
    assert!(csv.is_file());
}

/// `--terms R` evaluates R alone (TT and TRT columns zero) and its fit does not vary Base
/// Color, which only TT and TRT read.
#[test]
fn terms_switch_lobes_and_the_parameters_fitted() {
    let dir = tempfile::tempdir().unwrap();
    let truth = write(dir.path(), "truth.json", TRUTH);
    let data = dir.path().join("r.csv");
    frostbite(
        "synth",
        &[
            "--terms",
            "R",
            "--params",
            p(&truth),
            "--rig",
            "sphere:n=600:max=80",
            "--output",
            p(&data),
        ],
    );
    let out = dir.path().join("fit");
    frostbite(
        "fit",
        &[
            p(&data),
            "--terms",
            "R",
            "--starts",
            "2",
            "--no-progress",
            "--out",
            p(&out),
        ],
    );
    let fit = FitJson::load(&out.join("fit.json")).unwrap();
    let base = fit
        .parameters
        .iter()
        .find(|p| p.name == "base_color[0]")
        .unwrap();
    assert!(base.std_error.is_none(), "{base:?}");
    let (smoothness, _) = value(&fit, "smoothness");
    assert!((smoothness - 0.88).abs() < 1e-6, "{smoothness}");
    let curves = hairfit::files::read_curves_csv(&out.join("curves.csv")).unwrap();
    assert!(curves.iter().all(|r| r.fit_tt == 0.0 && r.fit_trt == 0.0));
}

/// Another family's options, an unknown term and a value outside the domain are errors that
/// say whose option it is or what the domain is.
#[test]
fn bad_input_is_refused_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", TRUTH);
    let input = write(
        dir.path(),
        "a.csv",
        "theta_i,phi_i,theta_r,phi_r\n20,0,-10,30\n",
    );
    let eval = |extra: &[&str], params: &Path| {
        let mut args = vec!["eval", "--model", "frostbite", "--params", p(params)];
        args.extend_from_slice(&["--input", p(&input)]);
        args.extend_from_slice(extra);
        failed(&hairfit(&args))
    };
    let e = eval(&["--lobes", "R"], &params);
    assert!(e.contains("--lobes"), "{e}");
    let e = eval(&["--width-nodes", "64"], &params);
    assert!(e.contains("--width-nodes"), "{e}");
    let e = eval(&["--terms", "R,TRRT"], &params);
    assert!(e.contains("frostbite") && e.contains("TRRT"), "{e}");
    let rough = write(
        dir.path(),
        "rs.json",
        r#"{"model": "frostbite", "base_color": 0.3, "smoothness": 0.9,
            "radial_smoothness": 0.97, "cuticle_angle_deg": 3}"#,
    );
    let e = eval(&[], &rough);
    assert!(e.contains("radial_smoothness") && e.contains("0.95"), "{e}");
    // The same file evaluates once the value is inside the domain.
    let ok = write(
        dir.path(),
        "ok.json",
        r#"{"model": "frostbite", "base_color": 0.3, "smoothness": 0.9,
            "radial_smoothness": 0.95, "cuticle_angle_deg": 3}"#,
    );
    hairfit_ok(&[
        "eval",
        "--model",
        "frostbite",
        "--params",
        p(&ok),
        "--input",
        p(&input),
    ]);
}
