//! Fits of the datasets shipped in `data/` (made by `hairfit synth`, truth beside each), read
//! through the loader exactly as `hairfit fit` reads them.

use hairfit::data::{load, LoadOptions};
use hairfit::families::marschner::fit::{fit, MarschnerOutcome};
use hairfit::families::marschner::parameters::all_parameters;
use hairfit::families::marschner::parameters::report_factor;
use hairfit::families::marschner::params::ParamFile;
use hairfit::fit::{fit_data, FitOptions};

fn fit_file(name: &str, opts: &FitOptions) -> (MarschnerOutcome, ParamFile) {
    let root = env!("CARGO_MANIFEST_DIR");
    let (ds, _) = load(
        format!("{root}/data/{name}.csv").as_ref(),
        &LoadOptions::default(),
    )
    .unwrap();
    let truth: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(format!("{root}/data/{name}.truth.json")).unwrap(),
    )
    .unwrap();
    let truth: ParamFile = serde_json::from_value(truth["params"].clone()).unwrap();
    let out = fit(&fit_data(&ds), name, Default::default(), opts).unwrap();
    (out, truth)
}

/// (name, fitted, std error, status, truth) for every non-fixed parameter.
fn compare(
    out: &MarschnerOutcome,
    truth: &ParamFile,
) -> Vec<(String, f64, Option<f64>, String, f64)> {
    let t = truth.to_params();
    all_parameters(out.json.data.channels.len())
        .into_iter()
        .filter_map(|p| {
            let e = out
                .json
                .parameters
                .iter()
                .find(|e| e.name == p.json_name())?;
            (e.status.as_str() != "fixed").then(|| {
                (
                    e.name.clone(),
                    e.value.unwrap(),
                    e.std_error,
                    e.status.to_string(),
                    t.get(p) * report_factor(p),
                )
            })
        })
        .collect()
}

#[test]
fn photon_noise_longitudinal_scan_with_zero_readings() {
    // 10⁴ photons at value 1: many readings are 0 or a few counts; they must not wreck the fit.
    let (out, truth) = fit_file("longitudinal_rgb", &FitOptions::default());
    assert_eq!(out.json.status.as_str(), "converged");
    let chi2 = out.json.residuals.reduced_chi2.unwrap();
    // Correct σ and model: reduced χ² ≈ 1 within its scatter √(2/505) ≈ 0.06 (0.3 leaves room
    // for the Poisson skew of few-count readings).
    assert!((chi2 - 1.0).abs() < 0.3, "reduced chi2 {chi2}");
    for (name, v, se, status, want) in compare(&out, &truth) {
        let se = se.unwrap_or_else(|| panic!("{name}: {status}, no standard error"));
        // 4 SE: 11 parameters, so a 3-SE miss would happen now and then by chance alone.
        assert!(
            (v - want).abs() < 4.0 * se,
            "{name}: {v} ± {se}, truth {want}"
        );
    }
}

#[test]
fn specular_cone_scan_cannot_fix_the_longitudinal_lobes() {
    // Azimuthal scans with θ_r = −θ_i: θ_h ≡ 0, so α_R, β_R and the scale trade off exactly;
    // everything else is recovered exactly from noise-free data.
    let (out, truth) = fit_file("azimuthal_rgb", &FitOptions::default());
    assert_eq!(out.json.status.as_str(), "converged");
    for (name, v, _, status, want) in compare(&out, &truth) {
        if name == "alpha_r_deg" || name == "beta_r_deg" {
            assert_eq!(status, "undetermined", "{name}");
            assert!(out
                .json
                .warnings
                .iter()
                .any(|w| w.starts_with(&name) && w.contains("theta_h")));
        } else {
            // Noise-free: the determined parameters come back to rounding (1e-6 relative).
            assert!(
                (v - want).abs() <= 1e-6 * want.abs(),
                "{name}: {v} vs {want}"
            );
        }
    }
}

#[test]
fn additive_floor_noise_sphere_in_exact_mode() {
    // Synthesised in exact root mode with additive noise σ = 1e-3: half the readings are not
    // significantly positive and must be fitted linearly inside the log fit.
    let mut opts = FitOptions::default();
    opts.model.config.mode = hairfit::families::marschner::RootMode::Exact;
    let (out, truth) = fit_file("sphere_1ch", &opts);
    assert_eq!(out.json.status.as_str(), "converged");
    let chi2 = out.json.residuals.reduced_chi2.unwrap();
    // dof 393: χ²/dof scatters by √(2/393) ≈ 0.07; 0.3 is a generous but failing-capable bound.
    assert!((chi2 - 1.0).abs() < 0.3, "reduced chi2 {chi2}");
    for (name, v, se, status, want) in compare(&out, &truth) {
        let se = se.unwrap_or_else(|| panic!("{name}: {status}, no standard error"));
        assert!(
            (v - want).abs() < 4.0 * se,
            "{name}: {v} ± {se}, truth {want}"
        );
    }
}

#[test]
fn the_goniometer_scan_example_is_fitted_with_every_parameter_determined() {
    // data/README.md's scan, loaded with its documented options: a headerless rig file with a
    // polar-angle column, fixed incidence and saturated readings. Every parameter must be
    // determined and agree with the truth of the CSV it was made from.
    let root = env!("CARGO_MANIFEST_DIR");
    let options = LoadOptions {
        columns: ["phi_r", "theta_r", "radiance"].map(String::from).to_vec(),
        fixed: ["theta_i=20", "phi_i=0"].map(String::from).to_vec(),
        maps: vec!["theta_r=90-x".into()],
        missing: "?".into(),
        ..LoadOptions::default()
    };
    let (ds, report) = load(format!("{root}/data/scan_example.txt").as_ref(), &options).unwrap();
    assert_eq!(report.accepted, 167);
    let truth: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(format!("{root}/data/scan_example.truth.json")).unwrap(),
    )
    .unwrap();
    let truth: ParamFile = serde_json::from_value(truth["params"].clone()).unwrap();
    let out = fit(
        &fit_data(&ds),
        "scan_example",
        report,
        &FitOptions::default(),
    )
    .unwrap();
    assert_eq!(out.json.status.as_str(), "converged");
    let compared = compare(&out, &truth);
    assert_eq!(compared.len(), 6, "σ_a, α_R, β_R, k_G, w_c, a are free");
    for (name, v, se, status, want) in compared {
        assert_eq!(status, "free", "{name}");
        let se = se.unwrap_or_else(|| panic!("{name}: no standard error"));
        // 4 SE, as above: six parameters, so a 3-SE miss would happen now and then by chance.
        assert!(
            (v - want).abs() < 4.0 * se,
            "{name}: {v} ± {se}, truth {want}"
        );
    }
    let scale = out.json.scale[0].value.unwrap();
    assert!(
        (scale - 400.0).abs() < 4.0 * out.json.scale[0].std_error.unwrap(),
        "scale {scale}"
    );
}
