//! Smoke test of `hairfit cost --quick`: the ledger runs end to end, writes its four files and
//! its numbers say what they must (the reference has error 0, AD and central differences agree,
//! the cubic approximation costs accuracy, a fit on clean-ish synthetic data recovers the truth).

use hairfit::cost::{run_cost, CostOptions, CostRow};

fn find<'a>(rows: &'a [CostRow], section: &str, setting: &str) -> &'a CostRow {
    rows.iter()
        .find(|r| r.section == section && r.setting.starts_with(setting))
        .unwrap_or_else(|| panic!("no row {section}/{setting}"))
}

#[test]
fn quick_ledger_runs_and_its_numbers_make_sense() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cost");
    let ledger = run_cost(
        &out,
        &CostOptions {
            quick: true,
            ..CostOptions::default()
        },
    )
    .unwrap();
    for f in ["cost.csv", "cost.json", "cost.svg", "cost.png"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let rows = &ledger.rows;
    // 2 root modes × 5 effect sets, AD + FD, and the fit variants.
    assert_eq!(rows.iter().filter(|r| r.section == "model").count(), 10);
    assert_eq!(rows.iter().filter(|r| r.section == "jacobian").count(), 2);
    assert!(rows.iter().filter(|r| r.section == "fit").count() >= 4);
    assert!(rows.iter().all(|r| r.time_s > 0.0 && r.time_s.is_finite()));

    // The reference (exact roots, every effect) against itself: exactly 0, so on the front.
    let reference = find(rows, "model", "exact +eccentricity");
    assert_eq!(reference.error_max, 0.0);
    assert!(reference.pareto);
    // Cubic roots with every effect: MODEL.md's known values differ from exact by up to ~13 %
    // (1.5925e-2 vs 1.8277e-2), so the RMS error is clearly nonzero but well below 1.
    let cubic = find(rows, "model", "cubic +eccentricity");
    assert!(cubic.error_rms > 1e-3 && cubic.error_rms < 0.5, "{cubic:?}");
    // R alone misses TT/TRT, which dominate somewhere: its worst relative error is ~1.
    assert!(find(rows, "model", "cubic R").error_max > 0.9);

    // Central differences with a cbrt(eps)-sized step agree with exact AD to ~1e-9 relative;
    // 1e-5 leaves room for stiff columns without letting a wrong Jacobian through.
    let fd = find(rows, "jacobian", "central differences");
    assert!(fd.error_max < 1e-5, "{fd:?}");

    // A fit on the demo data (2 % noise, 7020 residuals) recovers every free parameter to a
    // small fraction of its typical range; 5 % would already be a visibly wrong fit.
    for r in rows.iter().filter(|r| r.section == "fit") {
        assert!(r.error_max < 0.05, "{r:?}");
    }

    // The CSV has one row per ledger row and the SVG is well-formed.
    let mut csv = csv::Reader::from_path(out.join("cost.csv")).unwrap();
    assert_eq!(csv.records().count(), rows.len());
    let svg = std::fs::read_to_string(out.join("cost.svg")).unwrap();
    roxmltree::Document::parse(&svg).unwrap();
    assert!(svg.contains("Pareto"));
}
