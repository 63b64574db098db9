//! Noise models: statistics match their definitions, draws are seeded and reproducible, terms
//! combine without disturbing each other, and bad specs get clear errors.

use hairfit::synth::{Noise, OUTLIER_FACTOR};

/// Clean values spanning four decades, one channel.
fn clean(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| 10f64.powf(-2.0 + 4.0 * (i % 97) as f64 / 96.0))
        .collect()
}

fn mean_std(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var.sqrt())
}

#[test]
fn relative_noise_has_the_requested_relative_spread() {
    let n = 10_000;
    let y = clean(n);
    let noisy = Noise::parse("relative:0.02").unwrap().apply(&y, 1, 1);
    let ratios: Vec<f64> = noisy
        .values
        .iter()
        .zip(&y)
        .map(|(v, c)| v / c - 1.0)
        .collect();
    let (mean, std) = mean_std(&ratios);
    // y/ŷ − 1 ~ N(0, 0.02²): the sample std of n = 10k draws has relative standard error
    // 1/sqrt(2(n−1)) = 0.71%, so a 5-standard-error band is ±3.5% (tighter than 10%, and still
    // fails by chance < 1e-6); the mean's standard error is 0.02/sqrt(n) = 2e-4.
    assert!((std / 0.02 - 1.0).abs() < 0.035, "std {std}");
    assert!(mean.abs() < 5.0 * 0.02 / (n as f64).sqrt(), "mean {mean}");
    // σ is exactly r·ŷ.
    let sigma = noisy.sigma.unwrap();
    for (s, c) in sigma.iter().zip(&y) {
        assert_eq!(*s, 0.02 * c);
    }
    assert!(noisy.outliers.is_empty());
}

#[test]
fn photon_noise_is_poisson_counts() {
    let n = 20_000;
    let counts_at_one = 500.0;
    // Constant ŷ = 0.1: mean count λ = 50.
    let y = vec![0.1; n];
    let noisy = Noise::parse("photon:500").unwrap().apply(&y, 1, 4);
    let counts: Vec<f64> = noisy.values.iter().map(|v| v * counts_at_one).collect();
    for c in &counts {
        // v = k/N, so v·N is k up to one rounding of the division and the product.
        assert!((c - c.round()).abs() < 1e-9 && *c >= 0.0, "{c}");
    }
    let (mean, std) = mean_std(&counts);
    // Poisson(50): mean 50 with s.e. sqrt(50/n) = 0.05; variance 50 with s.e. ≈ 50·sqrt(2/n)
    // (+ the excess-kurtosis term 1/λ, negligible) = 0.5. Five standard errors each.
    assert!((mean - 50.0).abs() < 0.25, "mean {mean}");
    assert!((std * std - 50.0).abs() < 2.5, "var {}", std * std);
    // σ = sqrt(ŷ/N).
    assert_eq!(noisy.sigma.unwrap()[0], (0.1f64 / 500.0).sqrt());
}

#[test]
fn floor_noise_is_additive_and_value_independent() {
    let n = 10_000;
    let y = clean(n);
    let noisy = Noise::parse("floor:1e-3").unwrap().apply(&y, 1, 9);
    let diffs: Vec<f64> = noisy.values.iter().zip(&y).map(|(v, c)| v - c).collect();
    let (mean, std) = mean_std(&diffs);
    // Same 5-standard-error bands as for relative noise.
    assert!((std / 1e-3 - 1.0).abs() < 0.035, "std {std}");
    assert!(mean.abs() < 5.0 * 1e-3 / (n as f64).sqrt());
    assert!(noisy.sigma.unwrap().iter().all(|&s| s == 1e-3));
}

#[test]
fn outlier_fraction_is_within_binomial_bounds_and_factors_in_range() {
    let n = 10_000;
    let y = clean(n);
    let p = 0.01;
    let noisy = Noise::parse("outliers:0.01").unwrap().apply(&y, 1, 12);
    // Binomial(n, p): mean 100, s.d. sqrt(n p (1−p)) = 9.95; ±5 s.d.
    let k = noisy.outliers.len() as f64;
    let sd = (n as f64 * p * (1.0 - p)).sqrt();
    assert!((k - n as f64 * p).abs() < 5.0 * sd, "{k} outliers");
    // Outliers are scaled by a factor in [3, 10); everything else is untouched, bit for bit.
    for (i, (v, c)) in noisy.values.iter().zip(&y).enumerate() {
        if noisy.outliers.binary_search(&i).is_ok() {
            // (ŷ·f)/ŷ recovers f to within an ulp or two; 1e-12 covers that and nothing more.
            let f = v / c;
            assert!(
                f > OUTLIER_FACTOR.0 - 1e-12 && f < OUTLIER_FACTOR.1 + 1e-12,
                "{f}"
            );
        } else {
            assert_eq!(v, c);
        }
    }
    // Outliers alone imply no σ.
    assert!(noisy.sigma.is_none());
}

#[test]
fn an_outlier_hits_every_channel_of_its_sample() {
    let n = 2_000;
    let y: Vec<f64> = (0..3 * n).map(|j| 1.0 + j as f64).collect();
    let noisy = Noise::parse("outliers:0.2").unwrap().apply(&y, 3, 5);
    assert!(!noisy.outliers.is_empty());
    for &i in &noisy.outliers {
        let f: Vec<f64> = (0..3)
            .map(|c| noisy.values[3 * i + c] / y[3 * i + c])
            .collect();
        // One factor per sample: the three ratios agree to rounding (1 ulp-ish).
        assert!((f[0] - f[1]).abs() < 1e-14 * f[0] && (f[0] - f[2]).abs() < 1e-14 * f[0]);
    }
}

#[test]
fn terms_combine_without_changing_each_others_draws() {
    let y = clean(5_000);
    let base = Noise::parse("relative:0.02").unwrap().apply(&y, 1, 8);
    let both = Noise::parse("relative:0.02+outliers:0.05")
        .unwrap()
        .apply(&y, 1, 8);
    assert!(!both.outliers.is_empty());
    for i in 0..y.len() {
        if both.outliers.binary_search(&i).is_err() {
            assert_eq!(base.values[i], both.values[i]);
        }
    }
    assert_eq!(base.sigma, both.sigma);
    // σ of a combination adds in quadrature.
    let combo = Noise::parse("photon:100+relative:0.1+floor:0.01").unwrap();
    let expected = (2.0f64 / 100.0 + (0.1f64 * 2.0).powi(2) + 0.01f64.powi(2)).sqrt();
    assert_eq!(combo.sigma(2.0), expected);
}

#[test]
fn same_seed_same_values_different_seed_different_values() {
    let y = clean(1_000);
    let noise = Noise::parse("photon:1000+relative:0.01+floor:1e-4+outliers:0.05").unwrap();
    let a = noise.apply(&y, 1, 77);
    let b = noise.apply(&y, 1, 77);
    let c = noise.apply(&y, 1, 78);
    assert_eq!(a, b);
    assert_ne!(a.values, c.values);
    assert_ne!(a.outliers, c.outliers);
}

#[test]
fn none_leaves_values_untouched() {
    let y = clean(100);
    let noise = Noise::parse("none").unwrap();
    assert!(noise.is_none());
    let out = noise.apply(&y, 1, 3);
    assert_eq!(out.values, y);
    assert!(out.sigma.is_none() && out.outliers.is_empty());
}

#[test]
fn canonical_form_round_trips() {
    let noise = Noise::parse("outliers:0.01 + relative:0.02").unwrap();
    assert_eq!(noise.to_string(), "relative:0.02+outliers:0.01");
    assert_eq!(Noise::parse(&noise.to_string()).unwrap(), noise);
    assert_eq!(Noise::default().to_string(), "none");
}

#[test]
fn bad_noise_specs_get_clear_errors() {
    let cases = [
        ("gaussian:0.1", "unknown noise `gaussian`"),
        ("relative", "not KIND:VALUE"),
        ("relative:-0.1", "must be > 0"),
        ("relative:0", "must be > 0"),
        ("photon:abc", "`abc` is not a finite number"),
        ("outliers:1.5", "in (0, 1]"),
        ("floor:NaN", "not a finite number"),
        ("relative:0.1+relative:0.2", "appears twice"),
        ("", "not KIND:VALUE"),
    ];
    for (spec, expected) in cases {
        let msg = Noise::parse(spec).unwrap_err().to_string();
        assert!(msg.contains(expected), "{spec}: {msg}");
        assert!(msg.starts_with("--noise"), "{msg}");
    }
}
