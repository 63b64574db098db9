//! Outlier kinds of the synthesizer (issue 10): spikes with a chosen range, dropouts (near-zero
//! readings), sign glitches (negative readings) and baseline offsets; the canonical noise spec
//! round-trips; bad combinations get clear errors; and through the binary, a fit of data with
//! each kind under the default l2 loss ends `poor_fit` with the robust-loss suggestion.

use crate::support::cli;

use hairfit::synth::{Noise, OutlierKind, OUTLIER_FACTOR};

/// Clean values spanning four decades, one channel.
fn clean(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| 10f64.powf(-2.0 + 4.0 * (i % 97) as f64 / 96.0))
        .collect()
}

fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn each_kind_corrupts_its_outliers_as_documented_and_leaves_the_rest_alone() {
    let n = 5_000;
    let y = clean(n);
    let m = median(&y);
    for (spec, check) in [
        ("outliers:0.05+outlier_range:5..50", "spike"),
        ("outliers:0.05+outlier_kind:dropout", "dropout"),
        ("outliers:0.05+outlier_kind:sign", "sign"),
        (
            "outliers:0.05+outlier_kind:offset+outlier_range:2..3",
            "offset",
        ),
    ] {
        let noisy = Noise::parse(spec).unwrap().apply(&y, 1, 21);
        // Binomial(5000, 0.05): 250 ± 15.4; five standard deviations.
        let k = noisy.outliers.len() as f64;
        assert!((k - 250.0).abs() < 5.0 * 15.4, "{spec}: {k} outliers");
        for (i, (v, c)) in noisy.values.iter().zip(&y).enumerate() {
            if noisy.outliers.binary_search(&i).is_err() {
                assert_eq!(v, c, "{spec}: sample {i} is not an outlier");
                continue;
            }
            // Ratios recover the drawn factor to an ulp or two: 1e-12 relative.
            let ok = match check {
                "spike" => (5.0 - 1e-12..50.0 + 1e-12).contains(&(v / c)),
                "dropout" => (0.0..0.01 + 1e-12).contains(&(v / c)),
                "sign" => (v / c + 1.0).abs() < 1e-12,
                _ => {
                    let shift = (v - c).abs() / m;
                    (2.0 - 1e-9..3.0 + 1e-9).contains(&shift)
                }
            };
            assert!(ok, "{spec}: sample {i}: clean {c}, noisy {v}");
        }
    }
}

#[test]
fn offsets_go_both_ways_and_mixed_uses_every_kind() {
    let y = clean(20_000);
    let noisy = Noise::parse("outliers:0.1+outlier_kind:offset")
        .unwrap()
        .apply(&y, 1, 3);
    let up = noisy
        .outliers
        .iter()
        .filter(|&&i| noisy.values[i] > y[i])
        .count();
    let n = noisy.outliers.len();
    // A fair coin per outlier: n/2 ± 5 sd (sd = sqrt(n)/2).
    assert!(
        (up as f64 - n as f64 / 2.0).abs() < 2.5 * (n as f64).sqrt(),
        "{up} of {n} up"
    );
    let mixed = Noise::parse("outliers:0.2+outlier_kind:mixed")
        .unwrap()
        .apply(&y, 1, 3);
    let (mut spike, mut dropout, mut sign, mut offset) = (0, 0, 0, 0);
    for &i in &mixed.outliers {
        let r = mixed.values[i] / y[i];
        if (r + 1.0).abs() < 1e-12 {
            sign += 1;
        } else if (0.0..0.01 + 1e-12).contains(&r) {
            dropout += 1;
        } else if (OUTLIER_FACTOR.0 - 1e-12..OUTLIER_FACTOR.1 + 1e-12).contains(&r) {
            spike += 1;
        } else {
            offset += 1;
        }
    }
    // About 1000 of each; an offset can land in the spike range by chance, so ±40%.
    for (name, k) in [
        ("spike", spike),
        ("dropout", dropout),
        ("sign", sign),
        ("offset", offset),
    ] {
        assert!(
            (600..1400).contains(&k),
            "{name}: {k} of {}",
            mixed.outliers.len()
        );
    }
}

#[test]
fn the_default_kind_keeps_the_old_draws_and_the_spec_round_trips() {
    let y = clean(3_000);
    let old = Noise::parse("relative:0.02+outliers:0.05").unwrap();
    assert_eq!(old.outlier_kind, OutlierKind::Spike);
    // The canonical spec of the default is unchanged (shipped truth files hold it).
    assert_eq!(old.to_string(), "relative:0.02+outliers:0.05");
    let explicit = Noise::parse("relative:0.02+outliers:0.05+outlier_range:3..10").unwrap();
    assert_eq!(old.apply(&y, 1, 7), explicit.apply(&y, 1, 7));
    for spec in [
        "outliers:0.1+outlier_kind:dropout",
        "relative:0.02+outliers:0.1+outlier_kind:mixed+outlier_range:5..50",
        "outliers:0.1+outlier_kind:offset+outlier_range:0.5..2",
    ] {
        let n = Noise::parse(spec).unwrap();
        assert_eq!(n.to_string(), spec);
        assert_eq!(Noise::parse(&n.to_string()).unwrap(), n);
    }
    let via_options = Noise::parse("outliers:0.1")
        .unwrap()
        .with_outlier_options(Some(OutlierKind::Dropout), Some((0.0, 0.001)))
        .unwrap();
    assert_eq!(
        via_options.to_string(),
        "outliers:0.1+outlier_kind:dropout+outlier_range:0..0.001"
    );
}

#[test]
fn bad_outlier_options_are_refused_with_the_rule() {
    let e = |spec: &str| Noise::parse(spec).unwrap_err().to_string();
    assert!(e("relative:0.1+outlier_kind:dropout").contains("add `outliers:P`"));
    assert!(
        e("outliers:0.1+outlier_kind:drop").contains("use spike, dropout, sign, offset or mixed")
    );
    assert!(e("outliers:0.1+outlier_range:0.5..2").contains("1 <= LO <= HI"));
    assert!(e("outliers:0.1+outlier_kind:dropout+outlier_range:0..2").contains("HI < 1"));
    assert!(e("outliers:0.1+outlier_range:5to50").contains("not LO..HI"));
    let twice = Noise::parse("outliers:0.1+outlier_kind:sign")
        .unwrap()
        .with_outlier_options(Some(OutlierKind::Dropout), None)
        .unwrap_err()
        .to_string();
    assert!(twice.contains("both given"), "{twice}");
}

/// Each kind through the binary: synth with --outlier-kind, fit with the default l2 loss; the
/// verdict is poor_fit and the suggestion is the robust loss, with its evidence.
#[test]
fn each_kind_is_caught_by_the_verdict_and_gets_the_robust_loss_suggestion() {
    let tmp = tempfile::tempdir().unwrap();
    for (kind, range) in [
        ("spike", Some("5..50")),
        ("dropout", None),
        ("sign", None),
        ("offset", None),
        ("mixed", None),
    ] {
        let csv = tmp.path().join(format!("{kind}.csv"));
        let mut args = vec![
            "synth",
            "--params",
            "data/true_1ch.json",
            "--rig",
            "azimuthal:incidences=15,30,45:steps=60",
            "--noise",
            "relative:0.02+outliers:0.05",
            "--seed",
            "9",
            "--outlier-kind",
            kind,
            "--output",
            cli::s(&csv),
        ];
        if let Some(r) = range {
            args.extend(["--outlier-range", r]);
        }
        cli::hairfit_ok(&args);
        let truth = std::fs::read_to_string(csv.with_extension("truth.json")).unwrap();
        if kind != "spike" {
            assert!(truth.contains(&format!("outlier_kind:{kind}")), "{truth}");
        }
        let out_dir = tmp.path().join(format!("fit_{kind}"));
        let out = cli::hairfit_ok(&[
            "fit",
            cli::s(&csv),
            "--out",
            cli::s(&out_dir),
            "--intervals",
            "linear",
            "--starts",
            "8",
        ]);
        let text = cli::stdout(&out);
        assert!(text.starts_with("verdict: poor_fit"), "{kind}: {text}");
        assert!(text.contains("try: --loss cauchy"), "{kind}: {text}");
    }
}
