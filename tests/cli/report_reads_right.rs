//! What a reader of `hairfit demo`'s and a robust fit's outputs sees: intervals whose ends differ,
//! one number format for values and errors (console and index.html), a convergence legend that
//! agrees with the stage table, both reduced χ² values labelled, no negative Δχ² printed, an SE
//! far from its profile interval explained, and demo data within a camera's dynamic range.

use crate::support::cli;

use cli::{hairfit_ok, s, shipped, stderr, stdout};

/// Every `[a, b]` whose ends are numbers, in `text`.
fn intervals(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for piece in text.split('[').skip(1) {
        let Some(inner) = piece.split(']').next() else {
            continue;
        };
        let ends: Vec<&str> = inner.split(", ").collect();
        if ends.len() == 2 && ends.iter().all(|e| e.parse::<f64>().is_ok()) {
            out.push((ends[0].to_string(), ends[1].to_string()));
        }
    }
    out
}

#[test]
fn the_demo_report_reads_right() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("demo");
    let out = hairfit_ok(&["demo", "--no-progress", "--out", s(&out_dir)]);
    let console = stdout(&out) + &stderr(&out);
    let html = std::fs::read_to_string(out_dir.join("index.html")).unwrap();

    // Interval ends differ (they read "[7.500, 7.500]" at four significant digits).
    for text in [&console, &html] {
        let found = intervals(text);
        assert!(found.len() >= 8, "intervals found: {found:?}");
        for (a, b) in found {
            assert_ne!(a, b, "an interval reads [{a}, {b}]");
        }
    }
    // One format for standard errors: every "± e" in the summary is a plain decimal (the demo's
    // errors are 1e-4…1e-2, which fixed decimals show), never a mix with `4.45e-4`.
    let errors: Vec<&str> = console
        .split("± ")
        .skip(1)
        .map(|r| r.split_whitespace().next().unwrap())
        .collect();
    assert!(errors.len() >= 11, "{errors:?}");
    assert!(errors.iter().all(|e| !e.contains('e')), "{errors:?}");
    // The residuals line reads like the report: the demo's rms and reduced χ² are near 1, which
    // four significant digits show plainly ("1.0014e0" read as an exponent to a newcomer).
    let residuals = console
        .lines()
        .find(|l| l.starts_with("residuals ("))
        .expect("a residuals line");
    let numbers: Vec<&str> = residuals
        .split_whitespace()
        .filter(|w| w.starts_with(|c: char| c.is_ascii_digit()))
        .collect();
    assert!(numbers.len() >= 3, "{residuals}");
    assert!(numbers.iter().all(|n| !n.contains('e')), "{residuals}");

    // The convergence legend counts what the stage table counts.
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("fit.json")).unwrap()).unwrap();
    let svg = std::fs::read_to_string(out_dir.join("convergence.svg")).unwrap();
    for stage in fit["trace"].as_array().unwrap() {
        let (name, n) = (
            stage["stage"].as_str().unwrap(),
            stage["iterations"].as_u64().unwrap(),
        );
        let drawn = stage["history"].as_array().unwrap().len() as u64;
        let label = if n > drawn {
            format!("of {n} in all")
        } else if n == 1 {
            format!("{name} (1 iteration)")
        } else {
            format!("{name} ({n} iterations)")
        };
        assert!(svg.contains(&label), "convergence.svg lacks `{label}`");
    }
    assert!(!svg.contains("1 iterations"));

    // The demo camera: every value carries the noise floor in its sigma, and the brightest
    // value over the smallest sigma stays within ~1e5, a 16-bit sensor's range at most (the
    // old demo's values reached down to 1e-26, 26 decades below the peak).
    let data = std::fs::read_to_string(out_dir.join("data.csv")).unwrap();
    let rows: Vec<Vec<f64>> = data
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("theta"))
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    let peak = rows
        .iter()
        .flat_map(|r| r[4..7].to_vec())
        .fold(0.0, f64::max);
    let min_sigma = rows
        .iter()
        .flat_map(|r| r[7..10].to_vec())
        .fold(f64::INFINITY, f64::min);
    assert!(min_sigma >= 3e-4 * 0.999, "smallest sigma {min_sigma}");
    assert!(peak / min_sigma < 1e5, "dynamic range {}", peak / min_sigma);

    // Under l2 both χ² values agree; each is labelled.
    assert!(console.contains("reduced chi2 of the normalised residuals"));
    assert!(console.contains("reduced chi2 (l2 cost / dof)"));
    assert!(html.contains("reduced χ² (l2 cost / dof)"));
}

#[test]
fn a_robust_fit_explains_its_se_and_never_prints_a_negative_dchi2() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("c");
    let data = shipped("azimuthal_1ch_noisy.csv");
    let out = hairfit_ok(&[
        "fit",
        s(&data),
        "--loss",
        "cauchy",
        "--no-progress",
        "--out",
        s(&out_dir),
    ]);
    let console = stdout(&out) + &stderr(&out);
    let html = std::fs::read_to_string(out_dir.join("index.html")).unwrap();
    for text in [&console, &html] {
        assert!(!text.contains("Δχ² = -"), "a negative Δχ² is printed");
        // k_g ± 0.55 beside a 68% interval 25× narrower: the difference is explained.
        assert!(
            text.contains("k_g: its standard error") && text.contains("read the profile interval"),
            "no explanation of k_g's SE"
        );
    }
    // Two reduced χ² values (0.93 and 1.16 here), each saying which it is.
    assert!(console.contains("reduced chi2 of the normalised residuals 0.9"));
    assert!(console.contains("reduced chi2 of the cauchy cost"));
    assert!(html.contains("reduced χ² of the cauchy cost"));
}
