//! The plotted report on scattered directions (every sample its own incidence, as from a
//! sphere rig or photographs) must stay linear in the number of samples: `hairfit fit` draws it
//! after every fit, so a quadratic step there is a hang after the results are written.

use std::sync::mpsc;
use std::time::{Duration, Instant};

use hairfit::fit::design::SplitMix64;
use hairfit::slices::{find_slices, Sample};

/// `n` samples, each with its own incidence.
fn scattered(n: u64) -> Vec<Sample> {
    let mut rng = SplitMix64::new(8);
    let mut u = |lo: f64, hi: f64| lo + (hi - lo) * rng.uniform();
    (0..n)
        .map(|id| Sample {
            id,
            angles: [
                u(-60.0, 60.0),
                u(0.0, 360.0),
                u(-60.0, 60.0),
                u(-180.0, 180.0),
            ],
            rows: vec![id as usize],
        })
        .collect()
}

/// Seconds `find_slices` takes on `samples` (with a hang guard), and its counts.
fn timed_find_slices(samples: Vec<Sample>) -> (f64, usize, usize) {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let t0 = Instant::now();
        let (slices, scattered) = find_slices(&samples);
        let _ = tx.send((t0.elapsed().as_secs_f64(), slices.len(), scattered.len()));
    });
    rx.recv_timeout(Duration::from_secs(900))
        .expect("find_slices did not finish within 900 s: a quadratic step")
}

#[test]
fn slices_of_scattered_samples_are_found_in_linear_time() {
    // Judged by growth, not wall time, so a loaded machine cannot fail it: ten times the samples
    // cost ~10–12× for linear or n log n work, 100× for a per-incidence pass over all samples
    // (measured 13 s at 1e6 when it was quadratic). 40× separates the two with room for the
    // machine's load changing by 3× between the two runs.
    let (t_small, _, _) = timed_find_slices(scattered(100_000));
    let (t_large, n_slices, n_scattered) = timed_find_slices(scattered(1_000_000));
    let ratio = t_large / t_small.max(1e-3);
    assert!(
        ratio < 40.0,
        "find_slices: 1e5 samples {t_small:.2} s, 1e6 {t_large:.2} s: {ratio:.0}× for 10× the samples"
    );
    // No two samples share an incidence, so none forms a slice: all are scattered points.
    assert_eq!(n_slices + n_scattered.min(1), 1, "{n_slices} slices");
    assert_eq!(n_scattered, 1_000_000);
}

/// A fit hands its report the verdict's scan slices instead of the report searching curves.csv's
/// samples again (a sort of every sample): they must be exactly the slices that search finds, on
/// scans (slices and leftover samples) and on scattered directions (no slice at all). Summary
/// curves hold a subset of the samples, numbered apart from the data's, and hand none.
#[test]
fn a_fit_hands_its_report_the_slices_the_report_would_find() {
    use crate::support;
    use hairfit::families::marschner::fit::fit;
    use hairfit::files::CurvesMode;
    use hairfit::fit::FitOptions;
    use hairfit::slices::samples_of;

    let truth = support::fit::random_params(5, 1);
    let mut scans = support::fit::azimuthal_scans();
    // Two stray directions, in no slice.
    scans.extend(support::fit::random_sphere(2, 9));
    for (angles, has_slices) in [(scans, true), (support::fit::random_sphere(400, 2), false)] {
        let data = support::fit::data(&truth, &angles, 0.02, 5);
        let out = fit(&data, "slices", Default::default(), &FitOptions::default()).unwrap();
        assert_eq!(out.json.options.curves, CurvesMode::Full);
        let given = out
            .curve_slices
            .as_deref()
            .expect("full curves carry their slices");
        assert_eq!(given, &find_slices(&samples_of(&out.curves)));
        assert_eq!(!given.0.is_empty(), has_slices, "{} slices", given.0.len());
        assert!(!given.1.is_empty(), "the stray samples are in no slice");
    }
    let data = support::fit::data(&truth, &support::fit::azimuthal_scans(), 0.02, 5);
    let options = FitOptions {
        curves: Some(CurvesMode::Summary),
        ..FitOptions::default()
    };
    let out = fit(&data, "summary", Default::default(), &options).unwrap();
    assert_eq!(out.json.options.curves, CurvesMode::Summary);
    assert!(out.curve_slices.is_none());
}
