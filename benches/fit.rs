//! Fit wall time vs sample count, every effect on, 3 channels, 2% noise, default start design
//! (multi-start on a 2000-sample subsample, polish on all data).
//!
//! `cargo bench --bench fit` runs 1k, 10k and 100k samples with 1 and 2 rayon threads; set
//! `HAIRFIT_BENCH_1M=1` to add 1M.
//! Target (task): 100k samples < 5 s wall on the 2-core machine.

use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use hairfit::families::marschner::fit::fit;
use hairfit::families::marschner::fit::synthetic::synthesize;
use hairfit::families::marschner::{ModelConfig, Params};
use hairfit::fit::design::SplitMix64;
use hairfit::fit::{EffectsChoice, FitOptions};
use hairfit::geometry::Angles;

fn truth() -> Params<f64> {
    Params {
        eta: 1.55,
        sigma_a: vec![0.3, 0.6, 1.1],
        alpha_r: (-7.5f64).to_radians(),
        beta_r: 7.0f64.to_radians(),
        k_g: 1.8,
        w_c: 16f64.to_radians(),
        eccentricity: 0.92,
        delta_eta_prime: 0.3,
        delta_h_m: 0.5,
    }
}

/// `n` random direction pairs on the sphere (|θ| < 85°).
fn sphere(n: usize) -> Vec<Angles> {
    let mut r = SplitMix64::new(42);
    (0..n)
        .map(|_| {
            let mut d = || {
                let t = (2.0 * r.uniform() - 1.0).asin().clamp(-1.48, 1.48);
                (t, (2.0 * r.uniform() - 1.0) * std::f64::consts::PI)
            };
            let (ti, pi) = d();
            let (tr, pr) = d();
            Angles {
                theta_i: ti,
                phi_i: pi,
                theta_r: tr,
                phi_r: pr,
            }
        })
        .collect()
}

fn bench_fit(c: &mut Criterion) {
    let mut sizes = vec![1_000, 10_000, 100_000];
    if std::env::var_os("HAIRFIT_BENCH_1M").is_some() {
        sizes.push(1_000_000);
    }
    let mut g = c.benchmark_group("fit_all_effects");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(20));
    for n in sizes {
        let data = synthesize(
            &truth(),
            &ModelConfig::default(),
            &sphere(n),
            &[2.0, 1.5, 1.0],
            0.02,
            7,
        );
        let opts = FitOptions {
            effects: EffectsChoice::All,
            ..FitOptions::default()
        };
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a rayon pool");
            let id = BenchmarkId::new(format!("{threads}_threads"), n);
            g.bench_with_input(id, &data, |b, d| {
                b.iter(|| {
                    pool.install(|| {
                        let out = fit(d, "bench", Default::default(), &opts).unwrap();
                        assert_eq!(out.json.status.as_str(), "converged");
                        out
                    })
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench_fit);
criterion_main!(benches);
