//! Round trips: data synthesised from the model at known parameters (≥ 20 seeded sets over
//! MODEL.md's typical ranges, three rig geometries) is fitted from the default start design —
//! never from the truth — and every free parameter must come back.

use crate::support;
use hairfit::families::marschner::fit::{fit, MarschnerOutcome};
use hairfit::families::marschner::parameters::{is_angle, report_factor};
use hairfit::families::marschner::{ParamName, Params};
use hairfit::fit::{EffectsChoice, FitOptions};

/// Default options, every effect on (the data is synthesised with every effect on).
fn options() -> FitOptions {
    FitOptions {
        effects: EffectsChoice::All,
        ..FitOptions::default()
    }
}

fn run(truth: &Params<f64>, geometry: usize, noise: f64, seed: u64) -> (String, MarschnerOutcome) {
    let (name, angles) = support::fit::geometry(geometry, seed);
    let data = support::fit::data(truth, &angles, noise, seed);
    let out = fit(&data, name, Default::default(), &options()).expect("fit runs");
    (name.to_string(), out)
}

/// Value and standard error of `p` in reporting units (degrees for angles).
fn reported(out: &MarschnerOutcome, p: ParamName) -> (f64, Option<f64>, String) {
    let e = out
        .json
        .parameters
        .iter()
        .find(|e| e.name == p.json_name())
        .expect("every parameter is listed");
    (e.value.expect("finite"), e.std_error, e.status.to_string())
}

fn free(out: &MarschnerOutcome) -> Vec<ParamName> {
    let nc = out.json.data.channels.len();
    hairfit::families::marschner::parameters::all_parameters(nc)
        .into_iter()
        .filter(|p| {
            out.json
                .parameters
                .iter()
                .any(|e| e.name == p.json_name() && e.status.as_str() != "fixed")
        })
        .collect()
}

#[test]
fn noise_free_data_recovers_every_free_parameter() {
    let mut failures = Vec::new();
    let n_sets = 21;
    for set in 0..n_sets {
        let seed = 1000 + set as u64;
        let nc = if set % 2 == 0 { 3 } else { 1 };
        let truth = support::fit::random_params(seed, nc);
        let (geom, out) = run(&truth, set, 0.0, seed);
        assert_eq!(out.json.status.as_str(), "converged", "set {set} ({geom})");
        for p in free(&out) {
            let want = truth.get(p) * report_factor(p);
            let (got, _, _) = reported(&out, p);
            // Noise-free data: the optimum is the truth, and LM runs to rounding level, so the
            // task's 1e-6 relative (1e-4° for angles) holds with margin for weakly determined
            // directions (k_g·w_c trade-offs) where cost ~ error² hides the last digits.
            let ok = if is_angle(p) {
                (got - want).abs() <= 1e-4
            } else {
                (got - want).abs() <= 1e-6 * want.abs()
            };
            if !ok {
                failures.push(format!(
                    "set {set} ({geom}, {nc} ch): {} = {got} want {want}",
                    p.json_name()
                ));
            }
        }
        let scales = support::fit::scales(nc);
        for (c, s) in out.json.scale.iter().enumerate() {
            let got = s.value.unwrap();
            if (got - scales[c]).abs() > 1e-6 * scales[c] {
                failures.push(format!(
                    "set {set} ({geom}): scale[{c}] = {got} want {}",
                    scales[c]
                ));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} misses:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn noisy_data_errors_lie_within_three_reported_standard_errors() {
    let (mut inside, mut total) = (0usize, 0usize);
    let mut misses = Vec::new();
    for set in 0..21 {
        let seed = 2000 + set as u64;
        let nc = if set % 2 == 0 { 3 } else { 1 };
        let truth = support::fit::random_params(seed, nc);
        let (geom, out) = run(&truth, set, 0.02, seed);
        for p in free(&out) {
            let want = truth.get(p) * report_factor(p);
            let (got, se, status) = reported(&out, p);
            total += 1;
            match se {
                Some(se) if (got - want).abs() <= 3.0 * se => inside += 1,
                _ => misses.push(format!(
                    "set {set} ({geom}): {} = {got} ± {se:?} ({status}), truth {want}",
                    p.json_name()
                )),
            }
        }
    }
    eprintln!("{inside}/{total} parameter errors within 3 reported standard errors");
    // Gaussian errors with correct standard errors fall within 3σ 99.7% of the time; the task
    // asks for ≥ 95%, which leaves room for the linearisation of a nonlinear model.
    assert!(
        inside as f64 >= 0.95 * total as f64,
        "{inside}/{total} within 3 SE; misses:\n{}",
        misses.join("\n")
    );
}

/// Spread of estimates over repeated noise vs the mean reported standard error.
fn spread_vs_reported(set: usize, n_noise: usize) -> Vec<(String, f64, f64)> {
    let seed = 3000 + set as u64;
    let nc = if set.is_multiple_of(2) { 3 } else { 1 };
    let truth = support::fit::random_params(seed, nc);
    let mut values: Vec<Vec<f64>> = Vec::new();
    let mut ses: Vec<Vec<f64>> = Vec::new();
    let mut names = Vec::new();
    for k in 0..n_noise {
        let (_, out) = run(&truth, set, 0.02, seed * 100 + k as u64);
        let ps = free(&out);
        if names.is_empty() {
            names = ps.iter().map(|p| p.json_name()).collect();
            values = vec![Vec::new(); ps.len()];
            ses = vec![Vec::new(); ps.len()];
        }
        for (j, &p) in ps.iter().enumerate() {
            let (v, se, _) = reported(&out, p);
            values[j].push(v);
            ses[j].push(se.unwrap_or(f64::NAN));
        }
    }
    names
        .into_iter()
        .enumerate()
        .map(|(j, name)| {
            let n = values[j].len() as f64;
            let mean = values[j].iter().sum::<f64>() / n;
            let sd = (values[j].iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            let se = ses[j].iter().sum::<f64>() / n;
            (name, sd, se)
        })
        .collect()
}

#[test]
fn reported_standard_errors_match_the_spread_over_noise_seeds() {
    let mut bad = Vec::new();
    for set in [0, 2] {
        for (name, sd, se) in spread_vs_reported(set, 24) {
            eprintln!(
                "set {set}: {name}: spread {sd:.3e} reported {se:.3e} ratio {:.2}",
                sd / se
            );
            // With 24 repeats the sample standard deviation itself scatters by ~15% (1/√(2·23)),
            // so a factor of 2 is a real test of the covariance, not of the sampling.
            if !(se.is_finite() && sd / se < 2.0 && se / sd < 2.0) {
                bad.push(format!(
                    "set {set}: {name}: spread {sd:.3e} vs reported {se:.3e}"
                ));
            }
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// Heavier version over all three geometries and 100 noise seeds:
/// `cargo test --release --test fit recovery:: -- --ignored`.
#[test]
#[ignore]
fn reported_standard_errors_match_the_spread_heavy() {
    let mut bad = Vec::new();
    for set in 0..6 {
        for (name, sd, se) in spread_vs_reported(set, 100) {
            // 100 repeats: sample-SD scatter ~7%; factor 2 as in the light test.
            if !(se.is_finite() && sd / se < 2.0 && se / sd < 2.0) {
                bad.push(format!(
                    "set {set}: {name}: spread {sd:.3e} vs reported {se:.3e}"
                ));
            }
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn freed_eta_is_recovered_from_noise_free_data() {
    for (set, eta) in [(0usize, 1.52), (2, 1.58)] {
        let seed = 4000 + set as u64;
        let mut truth = support::fit::random_params(seed, 3);
        truth.eta = eta;
        let (_, angles) = support::fit::geometry(set, seed);
        let data = support::fit::data(&truth, &angles, 0.0, seed);
        let opts = FitOptions {
            free_eta: true,
            ..options()
        };
        let out = fit(&data, "eta", Default::default(), &opts).unwrap();
        let (got, _, status) = reported(&out, ParamName::Eta);
        assert_eq!(status, "free");
        // Same 1e-6 relative as every other noise-free recovery.
        assert!(
            (got - eta).abs() <= 1e-6 * eta,
            "set {set}: eta {got} want {eta}"
        );
    }
}
