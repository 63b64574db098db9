//! Large-data passes of the fit: the chunked cost and the accumulated linearisation (per-channel
//! QR, never the dense Jacobian) at 100k samples × 3 channels and 2000 samples × 100 channels
//! (σ_a free per channel), against the dense Jacobian they replace; the covariance by channel
//! blocks against the dense one.
//!
//! `cargo bench --bench large`. Whole-command figures (1M × 3, 10M × 1, 100 channels, eval) are
//! measured with `/usr/bin/time -v hairfit …` (README, Performance).

use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use hairfit::families::marschner::fit::forward::MarschnerForward;
use hairfit::families::marschner::fit::synthetic::synthesize;
use hairfit::families::marschner::parameters::fitted_parameters;
use hairfit::families::marschner::parameters::reference_params;
use hairfit::families::marschner::{Effects, ModelConfig};
use hairfit::fit::design::SplitMix64;
use hairfit::fit::{Evaluator, Loss, Space};
use hairfit::geometry::{Angles, Measurement};

/// `n` random direction pairs (|θ| < 80°).
fn directions(n: usize) -> Vec<Angles> {
    let mut rng = SplitMix64::new(3);
    (0..n)
        .map(|_| {
            let mut deg = |span: f64| (rng.uniform() - 0.5) * span;
            Angles::from_degrees(deg(160.0), deg(360.0), deg(160.0), deg(360.0))
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let fwd = MarschnerForward {
        config: ModelConfig::default(),
        measurement: Measurement::S,
    };
    let mut group = c.benchmark_group("large");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    for (samples, nc) in [(100_000, 3), (2000, 100)] {
        let mut truth = hairfit::families::marschner::demo::demo_truth();
        truth.sigma_a = (0..nc).map(|c| 0.2 + 0.6 * c as f64 / nc as f64).collect();
        let data = synthesize(
            &truth,
            &fwd.config,
            &directions(samples),
            &vec![1.5; nc],
            0.02,
            7,
        );
        let free = fitted_parameters(&Effects::default(), nc, true);
        let (ev, _) = Evaluator::new(
            &fwd,
            &data,
            Space::Log,
            Loss::L2,
            1.0,
            reference_params(nc),
            free,
        )
        .expect("positive data");
        let x: Vec<f64> = ev.free.iter().map(|&n| truth.get(n)).collect();
        let u = ev.internal(&x);
        let id = format!("{samples}x{nc}");
        group.bench_function(format!("cost {id}"), |b| {
            b.iter(|| ev.cost_internal(&u, None))
        });
        group.bench_function(format!("linearize {id}"), |b| {
            b.iter(|| ev.linearize_internal(&u, None, None))
        });
        group.bench_function(format!("dense jacobian {id}"), |b| {
            b.iter(|| ev.eval_internal(&u, true).n_cols)
        });
        // Standard errors from the linearisation: by channel blocks (Schur complement onto the
        // shared parameters, linear in channels) against the dense SVD (cubic in channels).
        let lin = ev
            .linearize_internal(&u, None, None)
            .expect("no cancel flag");
        let ss = lin.rhs().norm_squared();
        let dof = lin.rows - lin.system.ncols;
        group.bench_function(format!("covariance by blocks {id}"), |b| {
            b.iter(|| {
                hairfit::lm::block_covariance(&lin.system, ss, dof, hairfit::lm::DEFAULT_RCOND)
            })
        });
        group.bench_function(format!("covariance dense {id}"), |b| {
            b.iter(|| hairfit::lm::covariance(&lin.matrix(), ss, dof))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
