//! Degenerate rigs: the fit converges on what the data determines, names what it does not, and
//! never panics or writes NaN.

use crate::support;
use hairfit::cli::summary::summary;
use hairfit::families::marschner::fit::{fit, MarschnerOutcome};
use hairfit::fit::{write_outputs, EffectsChoice, FitOptions};
use hairfit::geometry::Angles;

fn fit_angles(angles: Vec<Angles>, effects: EffectsChoice) -> MarschnerOutcome {
    let truth = support::fit::random_params(77, 3);
    let data = support::fit::data(&truth, &angles, 0.02, 77);
    let opts = FitOptions {
        effects,
        ..FitOptions::default()
    };
    fit(&data, "degenerate", Default::default(), &opts).expect("fit runs")
}

/// Written files contain no NaN/inf, and each undetermined parameter has a null error.
fn assert_clean(out: &MarschnerOutcome) {
    let dir = tempfile::tempdir().unwrap();
    write_outputs(dir.path(), out).unwrap();
    let text = std::fs::read_to_string(dir.path().join("fit.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).expect("fit.json parses");
    assert!(!text.contains("NaN") && !text.contains("inf"), "{text}");
    for p in v["parameters"].as_array().unwrap() {
        if p["status"] == "undetermined" {
            assert!(p["std_error"].is_null(), "{p}");
        }
        assert!(p["value"].is_number(), "{p}");
    }
    let curves = std::fs::read_to_string(dir.path().join("curves.csv")).unwrap();
    assert!(!curves.contains("NaN") && !curves.contains("inf"));
}

fn status_of(out: &MarschnerOutcome, name: &str) -> &'static str {
    out.json
        .parameters
        .iter()
        .find(|p| p.name == name)
        .unwrap()
        .status
        .as_str()
}

fn warned(out: &MarschnerOutcome, name: &str) -> bool {
    out.json.warnings.iter().any(|w| w.starts_with(name))
}

#[test]
fn one_incidence_in_plane_scan() {
    // One incidence (θ_i = 20°, φ_i = 0) and a longitudinal scan in the incidence plane (φ_r = 0):
    // φ and φ_h never change, so the azimuthal shapes (glint width, eccentricity) are invisible.
    let angles = (0..61)
        .map(|j| Angles::from_degrees(20.0, 0.0, -60.0 + 2.0 * j as f64, 0.0))
        .collect();
    let out = fit_angles(angles, EffectsChoice::All);
    eprintln!("{}", summary(&out, None));
    assert_eq!(out.json.status.as_str(), "converged");
    // The glint's azimuthal width cannot show at a single azimuth: it must be named.
    assert!(
        ["k_g", "w_c_deg"].iter().any(|n| warned(&out, n)),
        "{:#?}",
        out.json.warnings
    );
    for p in out
        .json
        .parameters
        .iter()
        .filter(|p| p.status.as_str() == "undetermined" || p.status.as_str() == "at_bound")
    {
        assert!(
            warned(&out, &p.name),
            "{} {} but not warned",
            p.name,
            p.status
        );
    }
    assert_clean(&out);
}

#[test]
fn no_glint_region_with_every_effect_forced() {
    // |φ| ≥ 100°: beyond every caustic azimuth (φ_c ≤ 41° for η* ≥ 1.34, a ≥ 0.85) by more
    // than 2 w_c for MODEL.md's w_c; |θ_h| < 15° keeps the R lobe dominant, so the glint's
    // far Gaussian tail (TRT's longitudinal lobe is twice as wide) is not seen in log space.
    let angles = support::fit::random_sphere(3000, 5)
        .into_iter()
        .filter(|a| {
            let phi = (a.phi_r - a.phi_i + std::f64::consts::PI)
                .rem_euclid(2.0 * std::f64::consts::PI)
                - std::f64::consts::PI;
            let th = 0.5 * (a.theta_i + a.theta_r);
            phi.abs() >= 100f64.to_radians() && th.abs() < 15f64.to_radians()
        })
        .collect();
    let out = fit_angles(angles, EffectsChoice::All);
    eprintln!("{}", summary(&out, None));
    assert_eq!(out.json.status.as_str(), "converged");
    for n in ["k_g", "w_c_deg"] {
        // Either status says it (undetermined / at_bound) or a "poorly determined" warning does;
        // in both cases the warning must give the geometric reason.
        assert!(
            out.json
                .warnings
                .iter()
                .any(|w| w.starts_with(n) && w.contains("glint")),
            "{n}: {:#?}",
            out.json.warnings
        );
    }
    assert_clean(&out);
}

#[test]
fn no_glint_region_under_auto_effects() {
    // 100° ≤ |φ| ≤ 130°, |θ_h| < 15°: no caustic in reach; auto must switch the glints off.
    let angles: Vec<Angles> = support::fit::random_sphere(6000, 9)
        .into_iter()
        .filter(|a| {
            let phi = (a.phi_r - a.phi_i + std::f64::consts::PI)
                .rem_euclid(2.0 * std::f64::consts::PI)
                - std::f64::consts::PI;
            let th = 0.5 * (a.theta_i + a.theta_r);
            (100f64.to_radians()..=130f64.to_radians()).contains(&phi.abs())
                && th.abs() < 15f64.to_radians()
        })
        .collect();
    let out = fit_angles(angles, EffectsChoice::Auto);
    eprintln!("{}", summary(&out, None));
    assert_eq!(out.json.status.as_str(), "converged");
    assert!(!out.json.model.effects.glints, "glints should be off");
    for n in ["k_g", "w_c_deg"] {
        assert_eq!(status_of(&out, n), "fixed");
        assert!(
            warned(&out, n),
            "{n} not fitted must be said: {:#?}",
            out.json.warnings
        );
    }
    assert_clean(&out);
}

#[test]
fn cancelled_fit_returns_the_best_so_far_as_interrupted() {
    use std::sync::atomic::AtomicBool;
    use std::sync::Arc;
    let truth = support::fit::random_params(5, 1);
    let data = support::fit::data(&truth, &support::fit::azimuthal_scans(), 0.02, 5);
    let opts = FitOptions {
        // Set before the start: every run stops at its first iteration boundary.
        cancel: Some(Arc::new(AtomicBool::new(true))),
        ..FitOptions::default()
    };
    let out = fit(&data, "cancelled", Default::default(), &opts).expect("fit returns");
    assert_eq!(out.json.status.as_str(), "interrupted");
    assert_clean(&out);
    // Small: the full curves are cheap, so they are kept.
    assert_eq!(out.json.options.curves, hairfit::files::CurvesMode::Full);
}

#[test]
fn a_large_interrupted_fit_writes_the_summary_curves_and_says_so() {
    use std::sync::atomic::AtomicBool;
    use std::sync::Arc;
    let truth = support::fit::random_params(6, 3);
    // Just over the threshold in rows (samples × 3 channels).
    let n = hairfit::fit::INTERRUPTED_FULL_CURVES_ROWS / 3 + 1000;
    let data = support::fit::data(&truth, &support::fit::random_sphere(n, 6), 0.02, 6);
    let opts = FitOptions {
        cancel: Some(Arc::new(AtomicBool::new(true))),
        ..FitOptions::default()
    };
    let out = fit(&data, "cancelled", Default::default(), &opts).expect("fit returns");
    assert_eq!(out.json.status.as_str(), "interrupted");
    assert_eq!(out.json.options.curves, hairfit::files::CurvesMode::Summary);
    assert!(
        out.json
            .warnings
            .iter()
            .any(|w| w.starts_with("interrupted: curves.csv holds the summary rows")),
        "{:?}",
        out.json.warnings
    );
}

#[test]
fn constant_phi_h_switches_eccentricity_off_under_auto_effects() {
    // One incidence plane (φ_i = φ_r = 0): φ_h never changes, so eccentricity is not fitted.
    let angles = (0..61)
        .flat_map(|j| {
            [10.0, 30.0].map(|ti| Angles::from_degrees(ti, 0.0, -60.0 + 2.0 * j as f64, 0.0))
        })
        .collect();
    let out = fit_angles(angles, EffectsChoice::Auto);
    assert!(!out.json.model.effects.eccentricity);
    assert_eq!(status_of(&out, "eccentricity"), "fixed");
    let reasons = &out.json.options.effects_reasons;
    assert!(
        reasons.iter().any(|r| r.starts_with("eccentricity off")),
        "{reasons:?}"
    );
    assert!(warned(&out, "eccentricity"));
    assert_clean(&out);
}
