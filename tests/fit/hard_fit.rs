//! Fits on hard data end with a result or a clear error: never a panic, a hang, or a NaN/inf in
//! any output file, and every fitted parameter inside its bound. Through the library (`fit::fit`,
//! `fit::write_outputs`, `solve::run_local`) and through the `hairfit fit` binary.
//!
//! Cases: starts on the bounds; data at grazing θ_d; data exactly on the glint; all-zero and
//! constant radiance; values from 1e-300 to 1e+300; a single sample.

use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;
use std::time::Duration;

use crate::support::hard::*;
use hairfit::families::marschner::azimuthal::caustic_position;
use hairfit::families::marschner::fit::fit;
use hairfit::families::marschner::fit::forward::fit_bound;
use hairfit::families::marschner::fit::forward::MarschnerForward;
use hairfit::families::marschner::fit::synthetic::synthesize;
use hairfit::families::marschner::parameters::fitted_parameters;
use hairfit::families::marschner::parameters::reference_params;
use hairfit::families::marschner::{Effects, ModelConfig, Params, RootMode};
use hairfit::fit::bounds::Bound;
use hairfit::fit::problem::{Evaluator, FitData, Space};
use hairfit::fit::solve::run_local;
use hairfit::fit::{EffectsChoice, FitOptions, Loss};
use hairfit::geometry::Angles;
use proptest::prelude::*;

/// A fit that is short but complete (multi-start, polish, covariance, curves): the subject is
/// robustness, not accuracy.
fn quick(space: Space) -> FitOptions {
    FitOptions {
        space,
        starts: 3,
        polish: 1,
        subsample: 400,
        start_iters: 20,
        polish_iters: 60,
        ..FitOptions::default()
    }
}

/// One-channel truth from MODEL.md's known-value table, round fiber (so φ_c is known exactly).
fn truth() -> Params<f64> {
    Params {
        eta: 1.55,
        sigma_a: vec![0.4],
        alpha_r: (-7f64).to_radians(),
        beta_r: 8f64.to_radians(),
        k_g: 2.0,
        w_c: 15f64.to_radians(),
        eccentricity: 1.0,
        delta_eta_prime: 0.3,
        delta_h_m: 0.5,
    }
}

/// Noise-free model data × 3 at `angles` (all lobes and effects, cubic mode).
fn model_data(angles: Vec<Angles>) -> FitData {
    let mut d = synthesize(&truth(), &ModelConfig::default(), &angles, &[3.0], 0.0, 7);
    d.channels = vec!["radiance".into()];
    d
}

/// A goniometer-like grid: θ_i ∈ {−30, 0, 30}°, θ_r every 15°, φ_r every 20°.
fn grid() -> Vec<Angles> {
    let mut v = Vec::new();
    for ti in [-30.0, 0.0, 30.0] {
        for tr in (-4..=4).map(|k| k as f64 * 15.0) {
            for pr in (-9..=9).map(|k| k as f64 * 20.0) {
                v.push(Angles::from_degrees(ti, 0.0, tr, pr));
            }
        }
    }
    v
}

/// The same angles with other values.
fn with_values(angles: Vec<Angles>, f: impl Fn(usize) -> f64) -> FitData {
    let n = angles.len();
    FitData {
        channels: vec!["radiance".into()],
        angles,
        values: (0..n).map(f).collect(),
        sigma: None,
        weight: None,
        line: (2..n as u64 + 2).collect(),
    }
}

/// θ_d within 1e-6 rad (and 1e-3, 0.1) of ±90°, θ_h = 0 or half the margin (so both |θ| stay
/// below 90°, as valid input must), φ all round.
fn grazing_angles() -> Vec<Angles> {
    let mut v = Vec::new();
    for d in [1e-6, 1e-3, 0.1] {
        for sign in [1.0, -1.0] {
            let td = sign * (FRAC_PI_2 - d);
            for th in [0.0, d / 2.0] {
                for k in -9..=9 {
                    v.push(Angles {
                        theta_i: th - td,
                        phi_i: 0.0,
                        theta_r: th + td,
                        phi_r: k as f64 * PI / 9.0,
                    });
                }
            }
        }
    }
    v
}

/// Samples exactly at φ = ±φ_c of the cubic map (a = 1, so TRT sees η) for several θ_d and θ_h.
fn glint_angles() -> Vec<Angles> {
    let eta = truth().eta;
    let mut v = Vec::new();
    for td_deg in [0.0, 10.0, 20.0, 30.0, 40.0] {
        let td = f64::to_radians(td_deg);
        let (s, c) = td.sin_cos();
        let eta_p = (eta * eta - s * s).sqrt() / c;
        let (phi_c, _) = caustic_position(RootMode::Cubic, eta_p).expect("below the merge");
        for th in [-10.0, 0.0, 10.0] {
            let th = f64::to_radians(th);
            for phi in [phi_c, -phi_c] {
                for phi_i in [0.0, 0.8] {
                    v.push(Angles {
                        theta_i: th - td,
                        phi_i,
                        theta_r: th + td,
                        phi_r: phi_i + phi,
                    });
                }
            }
        }
    }
    v
}

/// Fit through the library and write the outputs to `dir`; `Ok(fit.json)` after the output
/// checks of [`check_fit_dir`], or the library's error.
fn fit_and_write(
    data: &FitData,
    opts: &FitOptions,
    dir: &Path,
    what: &str,
) -> Result<serde_json::Value, String> {
    match fit(data, what, Default::default(), opts) {
        Ok(outcome) => {
            hairfit::fit::write_outputs(dir, &outcome)
                .unwrap_or_else(|e| panic!("{what}: write: {e}"));
            Ok(check_fit_dir(dir, what))
        }
        Err(e) => Err(e.to_string()),
    }
}

/// A fit that reports success must have a finite cost: finite rms, and a final trace cost.
fn assert_honest_status(fit: &serde_json::Value, what: &str) {
    let status = fit["status"].as_str().unwrap();
    if status != "failed" {
        assert!(
            fit["residuals"]["rms"].as_f64().is_some_and(f64::is_finite),
            "{what}: status `{status}` but rms is {}; warnings {}",
            fit["residuals"]["rms"],
            fit["warnings"]
        );
        let last = fit["trace"].as_array().and_then(|t| t.last()).unwrap();
        assert!(
            last["cost"].as_f64().is_some_and(f64::is_finite),
            "{what}: status `{status}` but final cost is {}",
            last["cost"]
        );
    }
}

#[test]
fn grazing_data_fits_cleanly() {
    let data = model_data(grazing_angles());
    assert!(data.values.iter().all(|v| v.is_finite()));
    for space in [Space::Log, Space::Linear] {
        let dir = tempfile::tempdir().unwrap();
        let what = format!("grazing, {space}");
        match fit_and_write(&data, &quick(space), dir.path(), &what) {
            Ok(j) => assert_honest_status(&j, &what),
            Err(e) => panic!("{what}: model data at grazing must fit, got `{e}`"),
        }
    }
}

#[test]
fn data_exactly_on_the_glint_fits_cleanly() {
    let data = model_data(glint_angles());
    for mode in [RootMode::Cubic, RootMode::Exact] {
        for space in [Space::Log, Space::Linear] {
            let dir = tempfile::tempdir().unwrap();
            let what = format!("on the glint, {mode}, {space}");
            let mut opts = FitOptions {
                effects: EffectsChoice::All,
                ..quick(space)
            };
            opts.model.config.mode = mode;
            let j = fit_and_write(&data, &opts, dir.path(), &what)
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_honest_status(&j, &what);
            // Noise-free data from the model in the same mode should be matched closely: the
            // log rms of a working fit is ≪ 1 (0.3 allows the short, 3-start budget).
            if mode == RootMode::Cubic && space == Space::Log {
                let rms = j["residuals"]["rms"].as_f64().unwrap();
                assert!(rms < 0.3, "{what}: rms {rms}");
            }
        }
    }
}

#[test]
fn all_zero_radiance_is_a_clear_error_in_log_space_and_a_result_in_linear() {
    let data = with_values(grid(), |_| 0.0);
    let dir = tempfile::tempdir().unwrap();
    let err = fit_and_write(&data, &quick(Space::Log), dir.path(), "zeros, log")
        .expect_err("log of zero cannot be fitted");
    assert!(
        err.contains("no positive value") && err.contains("--space linear"),
        "unclear error: {err}"
    );
    assert!(
        !dir.path().join("fit.json").exists(),
        "an error writes no fit.json"
    );
    let j = fit_and_write(&data, &quick(Space::Linear), dir.path(), "zeros, linear")
        .expect("linear space fits zeros");
    assert_honest_status(&j, "zeros, linear");
    // The only consistent answer for all-zero data is a zero scale.
    assert_eq!(j["scale"][0]["value"].as_f64(), Some(0.0));
}

#[test]
fn constant_radiance_fits_cleanly() {
    for space in [Space::Log, Space::Linear] {
        let data = with_values(grid(), |_| 1.0);
        let dir = tempfile::tempdir().unwrap();
        let what = format!("constant, {space}");
        let j = fit_and_write(&data, &quick(space), dir.path(), &what)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_honest_status(&j, &what);
    }
}

#[test]
fn values_from_1e_minus_300_to_1e_plus_300_end_cleanly() {
    let mut rng = hairfit::fit::design::SplitMix64::new(11);
    let exps: Vec<f64> = (0..grid().len())
        .map(|_| -300.0 + 600.0 * rng.uniform())
        .collect();
    let data = with_values(grid(), |i| 10f64.powf(exps[i]));
    assert!(data.values.iter().all(|v| v.is_finite() && *v > 0.0));
    for space in [Space::Log, Space::Linear] {
        let dir = tempfile::tempdir().unwrap();
        let what = format!("1e±300, {space}");
        match fit_and_write(&data, &quick(space), dir.path(), &what) {
            Ok(j) => assert_honest_status(&j, &what),
            Err(e) => assert!(
                e.contains("space") || e.contains("overflow"),
                "{what}: unclear error `{e}`"
            ),
        }
    }
}

#[test]
fn a_single_sample_ends_cleanly() {
    let data = model_data(vec![Angles::from_degrees(-20.0, 0.0, 25.0, 30.0)]);
    for space in [Space::Log, Space::Linear] {
        for effects in [EffectsChoice::Auto, EffectsChoice::All] {
            let dir = tempfile::tempdir().unwrap();
            let what = format!("single sample, {space}, {effects:?}");
            let opts = FitOptions {
                effects,
                ..quick(space)
            };
            match fit_and_write(&data, &opts, dir.path(), &what) {
                Ok(j) => {
                    assert_honest_status(&j, &what);
                    // One value cannot determine any shape parameter: no standard errors.
                    for p in j["parameters"].as_array().unwrap() {
                        assert!(p["std_error"].is_null(), "{what}: {p}");
                    }
                    assert!(
                        !j["warnings"].as_array().unwrap().is_empty(),
                        "{what}: no warning"
                    );
                }
                Err(e) => assert!(!e.is_empty(), "{what}"),
            }
        }
    }
}

#[test]
fn empty_data_is_a_clear_error() {
    let data = with_values(Vec::new(), |_| 1.0);
    let err = fit(&data, "empty.csv", Default::default(), &quick(Space::Log))
        .expect_err("nothing to fit");
    assert!(err.to_string().contains("no samples"), "{err}");
}

/// Local runs started exactly on the bounds (the MINUIT sine transform has dx/du = 0 there):
/// finite cost, never worse than the start, every parameter inside its bound.
#[test]
fn local_runs_started_on_the_bounds_stay_finite_and_inside() {
    let data = model_data(grid());
    let forward = MarschnerForward {
        config: ModelConfig::default(),
        measurement: Default::default(),
    };
    let free = fitted_parameters(&Effects::default(), 1, true);
    let (ev, _) = Evaluator::new(
        &forward,
        &data,
        Space::Log,
        Loss::L2,
        1.0,
        reference_params(1),
        free.clone(),
    )
    .unwrap();
    let corner = |upper: bool| -> Vec<f64> {
        free.iter()
            .map(|&p| {
                let b = fit_bound(p);
                let x = match (b, upper) {
                    (Bound::Free, false) => -PI / 6.0,
                    (Bound::Free, true) => PI / 6.0,
                    (Bound::Lower(lo), false) => lo,
                    (Bound::Lower(lo), true) => lo + 1e6,
                    (Bound::Both(lo, _), false) => lo,
                    (Bound::Both(_, hi), true) => hi,
                };
                b.to_internal(x)
            })
            .collect()
    };
    let mut moved = 0;
    for (name, u0) in [
        ("lower corner", corner(false)),
        ("upper corner", corner(true)),
    ] {
        let start = ev.eval_internal(&u0, false).cost();
        let r = run_local(&ev, &u0, 100, &None);
        assert!(r.cost.is_finite(), "{name}: cost {}", r.cost);
        assert!(
            r.cost <= start || !start.is_finite(),
            "{name}: {} > start {start}",
            r.cost
        );
        let x = ev.natural(&r.u);
        for (&p, &v) in free.iter().zip(&x) {
            assert_eq!(
                fit_bound(p).clamp(v),
                v,
                "{name}: {} = {v} leaves its bound",
                p.json_name()
            );
        }
        if r.cost < start {
            moved += 1;
        }
    }
    // At least the run whose start is not a stationary corner must make progress.
    assert!(moved >= 1, "no run started on the bounds improved its cost");
}

/// The same cases through the binary, as a user meets them: exit 0 with clean outputs, or exit 1
/// with a one-line `hairfit: error:` message; never a panic (exit 101), a signal or a hang.
#[test]
fn binary_ends_cleanly_on_every_hard_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = hairfit::fit::design::SplitMix64::new(3);
    let cases: Vec<(&str, FitData)> = vec![
        ("grazing", model_data(grazing_angles())),
        ("glint", model_data(glint_angles())),
        ("zeros", with_values(grid(), |_| 0.0)),
        ("constant", with_values(grid(), |_| 1.0)),
        ("span", {
            let e: Vec<f64> = (0..grid().len())
                .map(|_| -300.0 + 600.0 * rng.uniform())
                .collect();
            with_values(grid(), |i| 10f64.powf(e[i]))
        }),
        (
            "single",
            model_data(vec![Angles::from_degrees(-20.0, 0.0, 25.0, 30.0)]),
        ),
    ];
    for (name, data) in &cases {
        let csv = dir.path().join(format!("{name}.csv"));
        write_csv(data, &csv);
        for space in ["log", "linear"] {
            let out = dir.path().join(format!("out-{name}-{space}"));
            let args = [
                "fit",
                csv.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
                "--space",
                space,
                "--starts",
                "3",
                "--polish",
                "1",
                "--polish-iters",
                "60",
                "--no-progress",
            ];
            // 120 s: each of these fits takes well under a second; only a hang reaches it.
            let f = run_hairfit(&args, &[], Duration::from_secs(120));
            let what = format!("{name}, {space}");
            match f.status.code() {
                Some(0) => {
                    let j = check_fit_dir(&out, &what);
                    assert_honest_status(&j, &what);
                    // The summary opens with the verdict, then the status line.
                    assert!(
                        f.stdout.starts_with("verdict: ") && f.stdout.contains("\nhairfit fit: "),
                        "{what}: {}",
                        f.stdout
                    );
                }
                // A fit that ran but did not fit: its files are written, its verdict says so.
                Some(1) if out.join("fit.json").exists() => {
                    let j = check_fit_dir(&out, &what);
                    assert_eq!(j["verdict"], "failed", "{what}: exit 1 with a written fit");
                    assert!(
                        f.stdout.starts_with("verdict: failed"),
                        "{what}: {}",
                        f.stdout
                    );
                }
                Some(1) => {
                    let msg = f.stderr.trim();
                    assert!(
                        msg.starts_with("hairfit: error: ") && msg.lines().count() == 1,
                        "{what}: unclear error output: {msg}"
                    );
                    assert!(
                        !out.join("fit.json").exists(),
                        "{what}: error but fit.json written"
                    );
                }
                other => panic!("{what}: exit {other:?} (panic or signal)\n{}", f.stderr),
            }
        }
    }
}

fn any_truth() -> impl Strategy<Value = (Params<f64>, f64)> {
    (
        0.0..3.0f64,
        -12.0..-3.0f64,
        3.0..15.0f64,
        0.0..6.0f64,
        5.0..30.0f64,
        0.75..1.0f64,
        -6.0..6.0f64,
    )
        .prop_map(|(s, a, b, kg, wc, e, log_scale)| {
            let p = Params {
                eta: 1.55,
                sigma_a: vec![s],
                alpha_r: a.to_radians(),
                beta_r: b.to_radians(),
                k_g: kg,
                w_c: wc.to_radians(),
                eccentricity: e,
                delta_eta_prime: 0.3,
                delta_h_m: 0.5,
            };
            (p, 10f64.powf(log_scale))
        })
}

proptest! {
    // Each case is a complete (short) fit, ~0.1–0.3 s: 8 cases keep the test a few seconds while
    // varying truth, scale over 12 decades, noise, space and root mode.
    #![proptest_config(ProptestConfig::with_cases(8))]

    #[test]
    fn fitted_parameters_stay_inside_their_bounds(
        (p, scale) in any_truth(), noise in 0.0..0.3f64, linear in any::<bool>(),
        exact in any::<bool>(), seed in 0u64..1000,
    ) {
        let mode = if exact { RootMode::Exact } else { RootMode::Cubic };
        let cfg = ModelConfig { mode, ..ModelConfig::default() };
        let mut data = synthesize(&p, &cfg, &grid(), &[scale], noise, seed);
        data.channels = vec!["radiance".into()];
        let space = if linear { Space::Linear } else { Space::Log };
        let mut opts = FitOptions { seed, effects: EffectsChoice::All, ..quick(space) };
        opts.model.config.mode = mode;
        let outcome = fit(&data, "prop", Default::default(), &opts).unwrap();
        let j = serde_json::to_value(&outcome.json).unwrap();
        assert_params_in_bounds(&j, "proptest fit");
        for name in hairfit::families::marschner::parameters::all_parameters(1) {
            let v = outcome.params.get(name);
            prop_assert_eq!(fit_bound(name).clamp(v), v, "{} = {}", name.json_name(), v);
        }
        prop_assert!(outcome.params.validate().is_ok());
    }
}
