//! `--model chiang` end to end, as a user runs it: eval against CHIANG.md's known values (both
//! directions, both sets), synth → fit recovering noise-free truth, demo, and the errors that
//! keep the two families' files apart.

use crate::support::cli;

use cli::{failed, hairfit, hairfit_ok, s as p, stdout, write};
use std::path::Path;

use crate::support::chiang::{model, s, set_a, set_b};
use hairfit::families::FamilyParams;
use hairfit::files::{FitJson, ParameterFile as _, Truth};

/// (θ_i, φ_i, θ_r, φ_r) in degrees; A: S(i,r), S(r,i); B: S(i,r), S(r,i) (CHIANG.md).
const TABLE: [([f64; 4], [f64; 4]); 4] = [
    (
        [-20.0, 0.0, 25.0, 30.0],
        [2.02865e-2, 2.15018e-2, 6.03184e-3, 6.09737e-3],
    ),
    (
        [10.0, -40.0, -5.0, 170.0],
        [3.88822e-1, 3.83488e-1, 2.71516e-1, 2.62119e-1],
    ),
    (
        [-60.0, 10.0, 45.0, -80.0],
        [9.29393e-2, 1.03574e-1, 4.74659e-2, 4.93730e-2],
    ),
    (
        [-10.0, 0.0, 75.0, 0.0],
        [2.62094e-3, 1.24974e-2, 1.07126e-10, 2.85840e-9],
    ),
];

/// CHIANG.md prints 6 significant digits (up to 5e-6 relative rounding), so "1e-6 relative" is
/// checked up to the print: half a unit of the last printed digit plus 1e-6 relative.
fn agrees(got: f64, printed: f64) -> bool {
    let unit = 10f64.powf(printed.abs().log10().floor()) * 1e-5;
    (got - printed).abs() <= 0.5 * unit + 1e-6 * printed.abs()
}

const SET_A: &str =
    r#"{"eta": 1.55, "sigma_a": 0.4, "beta_m": 0.3, "beta_n": 0.3, "alpha_deg": 2}"#;
const SET_B: &str = r#"{"sigma_a": 1.2, "beta_m": 0.1, "beta_n": 0.5, "alpha_deg": -3}"#;

#[test]
fn eval_matches_the_known_values_in_both_directions() {
    let dir = tempfile::tempdir().unwrap();
    let mut csv = String::from("theta_i,phi_i,theta_r,phi_r\n");
    for (a, _) in TABLE {
        csv += &format!("{},{},{},{}\n", a[0], a[1], a[2], a[3]);
        csv += &format!("{},{},{},{}\n", a[2], a[3], a[0], a[1]);
    }
    let input = write(dir.path(), "angles.csv", &csv);
    let m = model(4096);
    let mut failures = Vec::new();
    for (set, text, lib) in [(0, SET_A, set_a()), (1, SET_B, set_b())] {
        let params = write(dir.path(), &format!("set{set}.json"), text);
        let out = stdout(&hairfit_ok(&[
            "eval",
            "--model",
            "chiang",
            "--width-nodes",
            "4096",
            "--params",
            p(&params),
            "--input",
            p(&input),
        ]));
        let values: Vec<f64> = out
            .lines()
            .skip(1)
            .map(|l| l.rsplit(',').next().unwrap().parse().unwrap())
            .collect();
        assert_eq!(values.len(), 8);
        for (row, (a, expected)) in TABLE.iter().enumerate() {
            let swapped = [a[2], a[3], a[0], a[1]];
            for (k, angles) in [*a, swapped].into_iter().enumerate() {
                let got = values[2 * row + k];
                // The command prints the library's value (shortest round-trip text); its batch
                // path integrates at |φ| where the one-sample path takes φ, equal to rounding.
                let lib_value = s(&lib, &m, angles);
                assert!(
                    (got - lib_value).abs() <= 1e-12 * lib_value.abs(),
                    "row {row} direction {k}: {got} vs {lib_value}"
                );
                let printed = expected[2 * set + k];
                if !agrees(got, printed) {
                    failures.push(format!("set {set} {angles:?}: {got:.6e} vs {printed:.5e}"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_model_tag_must_agree_with_the_option() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(
        dir.path(),
        "a.csv",
        "theta_i,phi_i,theta_r,phi_r\n0,0,0,30\n",
    );
    let chiang = write(
        dir.path(),
        "c.json",
        r#"{"model": "chiang", "sigma_a": 0.4, "beta_m": 0.3, "beta_n": 0.3, "alpha_deg": 2}"#,
    );
    let e = failed(&hairfit(&[
        "eval",
        "--params",
        p(&chiang),
        "--input",
        p(&input),
    ]));
    assert!(e.contains("c.json") && e.contains("--model"), "{e}");
    let marschner = write(
        dir.path(),
        "m.json",
        r#"{"model": "marschner", "sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2, "w_c_deg": 15}"#,
    );
    let e = failed(&hairfit(&[
        "eval",
        "--model",
        "chiang",
        "--params",
        p(&marschner),
        "--input",
        p(&input),
    ]));
    assert!(e.contains("m.json") && e.contains("--model"), "{e}");
    // The Marschner tag is accepted by the Marschner model and dropped.
    hairfit_ok(&["eval", "--params", p(&marschner), "--input", p(&input)]);
    // Unknown keys are an error naming the key.
    let extra = write(
        dir.path(),
        "x.json",
        r#"{"sigma_a": 0.4, "beta_m": 0.3, "beta_n": 0.3, "alpha_deg": 2, "k_g": 1}"#,
    );
    let e = failed(&hairfit(&[
        "eval",
        "--model",
        "chiang",
        "--params",
        p(&extra),
        "--input",
        p(&input),
    ]));
    assert!(e.contains("k_g"), "{e}");
    // A domain error names the parameter and the file; η is capped so η² cannot overflow.
    let huge = write(
        dir.path(),
        "h.json",
        r#"{"eta": 1e200, "sigma_a": 0.4, "beta_m": 0.3, "beta_n": 0.3, "alpha_deg": 2}"#,
    );
    let e = failed(&hairfit(&[
        "eval",
        "--model",
        "chiang",
        "--params",
        p(&huge),
        "--input",
        p(&input),
    ]));
    assert!(e.contains("eta") && e.contains("h.json"), "{e}");
    // Options of the other family are refused, not ignored.
    let e = failed(&hairfit(&[
        "eval",
        "--model",
        "chiang",
        "--lobes",
        "R",
        "--params",
        p(&chiang),
        "--input",
        p(&input),
    ]));
    assert!(e.contains("--lobes"), "{e}");
    let e = failed(&hairfit(&[
        "eval",
        "--width-nodes",
        "64",
        "--params",
        p(&marschner),
        "--input",
        p(&input),
    ]));
    assert!(e.contains("--width-nodes"), "{e}");
}

/// `synth --model chiang` of the parameters `truth` (JSON, written to `dir/truth.json`) on three
/// azimuthal scans into `dir/d.csv` (its truth beside it), with `extra` options.
fn synth_on_the_rig(dir: &Path, truth: &str, extra: &[&str]) -> std::path::PathBuf {
    let truth = write(dir, "truth.json", truth);
    let data = dir.join("d.csv");
    let mut args = vec![
        "synth",
        "--model",
        "chiang",
        "--params",
        p(&truth),
        "--rig",
        "azimuthal:incidences=15,30,45:steps=36",
        "--output",
        p(&data),
    ];
    args.extend_from_slice(extra);
    hairfit_ok(&args);
    data
}

/// Noise-free data of `synth --model chiang` is recovered by `fit --model chiang`. The same
/// width rule makes and fits the data, so the truth is an exact zero of the residual: 1e-6
/// relative leaves room only for the solver's stopping tolerance.
#[test]
fn synth_then_fit_recovers_noise_free_truth() {
    let dir = tempfile::tempdir().unwrap();
    let truth = r#"{"eta": 1.55, "sigma_a": [0.3, 0.5, 0.9], "beta_m": 0.25, "beta_n": 0.35, "alpha_deg": -2.5}"#;
    let data = synth_on_the_rig(
        dir.path(),
        truth,
        &["--width-nodes", "256", "--scale", "2,1.5,1"],
    );
    let t = Truth::load(&dir.path().join("d.truth.json")).unwrap();
    assert!(matches!(t.params, FamilyParams::Chiang(_)));
    assert_eq!(
        t.family_record.unwrap().chiang().unwrap().width_nodes,
        hairfit::families::chiang::WidthNodes::Fixed(256)
    );
    let out = dir.path().join("fit");
    let summary = stdout(&hairfit_ok(&[
        "fit",
        p(&data),
        "--model",
        "chiang",
        "--width-nodes",
        "256",
        "--starts",
        "4",
        "--no-progress",
        "--out",
        p(&out),
    ]));
    assert!(summary.contains("model: chiang"), "{summary}");
    let fit = FitJson::load(&out.join("fit.json")).unwrap();
    let params = hairfit::families::chiang::ChiangParamFile::load(out.join("params.json")).unwrap();
    assert_eq!(Some(&params), fit.params.chiang());
    assert_eq!(params.model.as_deref(), Some("chiang"));
    let got = params.to_params();
    let want = [0.3, 0.5, 0.9, 0.25, 0.35, -2.5];
    let have = [
        got.sigma_a[0],
        got.sigma_a[1],
        got.sigma_a[2],
        got.beta_m,
        got.beta_n,
        got.alpha.to_degrees(),
    ];
    for (h, w) in have.iter().zip(want) {
        assert!((h - w).abs() <= 1e-6 * w.abs(), "{have:?} vs {want:?}");
    }
    for (c, s) in [2.0, 1.5, 1.0].iter().enumerate() {
        let v = fit.scale[c].value.unwrap();
        assert!((v - s).abs() <= 1e-6 * s, "scale {c}: {v}");
    }
    // The report evaluated the Chiang model (its page says so) and curves.csv is in data order.
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("Chiang 2016"));
    let curves = hairfit::files::read_curves_csv(&out.join("curves.csv")).unwrap();
    assert!(curves.windows(2).all(|w| w[0].line <= w[1].line));
    assert!(curves.iter().all(|r| r.residual.abs() < 1e-9));
    // Determinism: the same fit again writes the same fit.json, byte for byte.
    let again = dir.path().join("again");
    hairfit_ok(&[
        "fit",
        p(&data),
        "--model",
        "chiang",
        "--width-nodes",
        "256",
        "--starts",
        "4",
        "--no-progress",
        "--out",
        p(&again),
    ]);
    let text = |d: &Path| std::fs::read_to_string(d.join("fit.json")).unwrap();
    assert_eq!(text(&out), text(&again));
    // The Chiang fit reads with --fix by CHIANG.md's names; Marschner names are refused.
    let e = failed(&hairfit(&[
        "fit",
        p(&data),
        "--model",
        "chiang",
        "--fix",
        "k_g=1",
        "--out",
        p(&dir.path().join("x")),
    ]));
    assert!(e.contains("k_g") && e.contains("beta_m"), "{e}");
}

#[test]
fn demo_runs_the_chiang_family() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let text = stdout(&hairfit_ok(&[
        "demo",
        "--model",
        "chiang",
        "--width-nodes",
        "128",
        "--starts",
        "2",
        "--subsample",
        "300",
        "--polish",
        "1",
        "--no-progress",
        "--out",
        p(&out),
    ]));
    assert!(
        text.contains("model: chiang") && text.contains("beta_n 0.35"),
        "{text}"
    );
    let fit = FitJson::load(&out.join("fit.json")).unwrap();
    let truth = Truth::load(&out.join("truth.json")).unwrap();
    assert_eq!(fit.family(), hairfit::families::ModelFamily::Chiang);
    assert_eq!(
        truth.params.family(),
        hairfit::families::ModelFamily::Chiang
    );
    // 2% noise on 2340 samples × 3 channels: β and α land within a few standard errors.
    let beta_n = fit.parameters.iter().find(|p| p.name == "beta_n").unwrap();
    assert!((beta_n.value.unwrap() - 0.35).abs() < 0.02, "{beta_n:?}");
    assert!(out.join("index.html").exists());
}

/// The cost ledger's Chiang section: the accuracy–time trade-off of the width rule, with the
/// default family's time as the yardstick. Accuracy bounds from docs/chiang.md's measurements
/// (β = 0.3: rounding level at every node count; β = 0.05: 1e-6 needs 1024 nodes).
#[test]
fn cost_ledger_has_the_chiang_section() {
    let dir = tempfile::tempdir().unwrap();
    let ledger = hairfit::cost::run_cost(
        &dir.path().join("cost"),
        &hairfit::cost::CostOptions {
            quick: true,
            family: hairfit::families::ModelFamily::Chiang,
            ..Default::default()
        },
    )
    .unwrap();
    let row = |section: &str, setting: &str| {
        ledger
            .rows
            .iter()
            .find(|r| r.section == section && r.setting == setting)
            .unwrap_or_else(|| panic!("{section} {setting} missing"))
    };
    assert!(row("baseline", "marschner, default options, every term").time_s > 0.0);
    assert!(row("chiang-b0.3", "256 nodes, rig, cached").error_max < 1e-10);
    assert!(row("chiang-b0.05", "1024 nodes, rig, cached").error_max < 1e-6);
    assert!(row("chiang-b0.05", "256 nodes, random, uncached").error_max > 1e-3);
    for f in ["cost.csv", "cost.json", "cost.svg", "cost.png"] {
        assert!(dir.path().join("cost").join(f).exists(), "{f}");
    }
}

/// The default (automatic) width rule fits noisy data to the parameters the plain 1024-node rule
/// finds, within a hundredth of each standard error (issue 30's bar for a faster rule), with
/// the same verdict — at β_n = 0.5, where the plain rule's kink error (≈4e-7) is largest of the
/// two. fit.json records which rule ran.
#[test]
fn auto_width_rule_fits_like_the_plain_rule() {
    let dir = tempfile::tempdir().unwrap();
    let truth =
        r#"{"eta": 1.55, "sigma_a": [0.3, 0.9], "beta_m": 0.2, "beta_n": 0.5, "alpha_deg": 3}"#;
    let data = synth_on_the_rig(dir.path(), truth, &["--noise", "relative:0.02"]);
    let fit = |rule: &str| {
        let out = dir.path().join(format!("fit-{rule}"));
        hairfit_ok(&[
            "fit",
            p(&data),
            "--model",
            "chiang",
            "--width-nodes",
            rule,
            "--starts",
            "4",
            "--intervals",
            "linear",
            "--no-progress",
            "--out",
            p(&out),
        ]);
        FitJson::load(&out.join("fit.json")).unwrap()
    };
    let (auto, plain) = (fit("auto"), fit("1024"));
    assert_eq!(
        auto.family_record.unwrap().chiang().unwrap().width_nodes,
        hairfit::families::chiang::WidthNodes::Auto
    );
    assert_eq!(
        plain.family_record.unwrap().chiang().unwrap().width_nodes,
        hairfit::families::chiang::WidthNodes::Fixed(1024)
    );
    assert_eq!(auto.verdict, plain.verdict);
    assert_eq!(
        auto.verdict,
        hairfit::files::Verdict::Good,
        "{:?}",
        auto.reasons
    );
    let mut compared = 0;
    for (a, b) in auto.parameters.iter().zip(&plain.parameters) {
        assert_eq!(a.name, b.name);
        let (Some(se), Some(va), Some(vb)) = (b.std_error, a.value, b.value) else {
            continue;
        };
        compared += 1;
        assert!(
            (va - vb).abs() <= se / 100.0,
            "{}: auto {va} vs plain {vb} (SE {se})",
            a.name
        );
    }
    // σ_a per channel, β_m, β_n and α: every free parameter was compared.
    assert_eq!(compared, 5, "{:?}", auto.parameters);
}
