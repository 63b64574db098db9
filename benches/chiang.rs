//! Chiang 2016 evaluations per second against Marschner, the width-node knob's accuracy–time
//! trade-off, and the (θ_r, φ) cache on a measurement rig. Throughput counts samples (one S per
//! channel, one channel). Accuracy (relative error vs a 4096-node reference) is printed once at
//! start-up, outside the timed loops.

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use hairfit::families::chiang::{
    batch_jacobian_static, scattering as chiang_s, scattering_batch, ChiangEffects, ChiangModel,
    ChiangParamName, ChiangParams,
};
use hairfit::families::marschner::params::ParameterFile as _;
use hairfit::families::marschner::{scattering as marschner_s, Effects, Lobes, ModelConfig};
use hairfit::geometry::Angles;

const NODE_COUNTS: [usize; 5] = [256, 512, 768, 1024, 2048];

/// CHIANG.md known-values set A.
fn chiang_params() -> ChiangParams<f64> {
    ChiangParams {
        eta: 1.55,
        sigma_a: vec![0.4],
        beta_m: 0.3,
        beta_n: 0.3,
        alpha: 2f64.to_radians(),
    }
}

fn marschner_params() -> hairfit::families::marschner::Params<f64> {
    hairfit::families::marschner::params::ParamFile::load("data/true_1ch.json")
        .expect("data/true_1ch.json is shipped with the crate")
        .to_params()
}

/// The ledger's seeded spread over the whole domain (θ in (−80°, 80°), φ any): the same
/// directions the cost ledger times, so the two agree.
fn random_angles(n: usize) -> Vec<Angles> {
    hairfit::cost::representative_angles(n, 0x9E37_79B9)
}

/// A goniometer rig: 5 incidences × 13 exit inclinations × 36 azimuths (φ_i = 0).
fn rig() -> Vec<Angles> {
    let mut a = Vec::new();
    for ti in [-60.0, -30.0, 0.0, 30.0, 60.0] {
        for k in 0..13 {
            let tr = -72.0 + 12.0 * k as f64;
            for j in 0..36 {
                a.push(Angles::from_degrees(ti, 0.0, tr, -180.0 + 10.0 * j as f64));
            }
        }
    }
    a
}

fn model(nodes: usize) -> ChiangModel {
    ChiangModel::new(ChiangEffects::default(), nodes).unwrap()
}

/// Narrow lobes (β_m = β_n = 0.05): the hardest case for the width rule.
fn narrow_params() -> ChiangParams<f64> {
    ChiangParams {
        beta_m: 0.05,
        beta_n: 0.05,
        ..chiang_params()
    }
}

fn chiang_values(p: &ChiangParams<f64>, nodes: usize, angles: &[Angles]) -> Vec<f64> {
    let mut out = vec![0.0; angles.len()];
    scattering_batch(p, &model(nodes), angles, &mut out);
    out
}

/// Worst and median relative error per node count vs 4096 nodes, on both sample sets, for the
/// benchmarked parameters (set A, β = 0.3) and for narrow lobes (β = 0.05).
fn print_accuracy(random: &[Angles], rig: &[Angles]) {
    for (set, p) in [
        ("beta=0.3", chiang_params()),
        ("beta=0.05", narrow_params()),
    ] {
        for (name, angles) in [("random", random), ("rig", rig)] {
            let reference = chiang_values(&p, 4096, angles);
            for n in NODE_COUNTS {
                let mut errs: Vec<f64> = chiang_values(&p, n, angles)
                    .iter()
                    .zip(&reference)
                    .map(|(v, r)| (v - r).abs() / r.abs())
                    .collect();
                errs.sort_by(f64::total_cmp);
                eprintln!(
                    "accuracy {set:9} {name:6} {n:4} nodes: worst rel. error {:.2e}, median {:.2e}",
                    errs[errs.len() - 1],
                    errs[errs.len() / 2]
                );
            }
        }
    }
}

fn bench_chiang(c: &mut Criterion) {
    let random = random_angles(128);
    let rig = rig();
    print_accuracy(&random, &rig);
    let cp = chiang_params();
    let mp = marschner_params();

    // Per-sample cost, no shared exit directions: Marschner vs Chiang at each node count.
    let mut group = c.benchmark_group("per_sample");
    group.sample_size(10);
    group.throughput(Throughput::Elements(random.len() as u64));
    for (name, effects) in [
        (
            "marschner_all_lobes",
            Effects {
                lobes: Lobes::default(),
                glints: false,
                eccentricity: false,
            },
        ),
        ("marschner_all_effects", Effects::default()),
    ] {
        let config = ModelConfig {
            effects,
            ..ModelConfig::default()
        };
        group.bench_function(name, |b| {
            let mut out = [0.0];
            b.iter(|| {
                for a in &random {
                    marschner_s(&mp, &config, black_box(a), &mut out);
                }
                black_box(out[0])
            })
        });
    }
    for n in NODE_COUNTS {
        let m = model(n);
        group.bench_with_input(BenchmarkId::new("chiang_nodes", n), &m, |b, m| {
            let mut out = [0.0];
            b.iter(|| {
                for a in &random {
                    chiang_s(&cp, m, black_box(a), &mut out);
                }
                black_box(out[0])
            })
        });
    }
    group.finish();

    // The rig: 2340 samples, 13 × 19 distinct (θ_r, |φ|) keys.
    let mut group = c.benchmark_group("rig_5x13x36");
    group.sample_size(10);
    group.throughput(Throughput::Elements(rig.len() as u64));
    let config = ModelConfig::default();
    group.bench_function("marschner_all_effects", |b| {
        let mut out = [0.0];
        b.iter(|| {
            for a in &rig {
                marschner_s(&mp, &config, black_box(a), &mut out);
            }
            black_box(out[0])
        })
    });
    for n in [512, 1024, 2048] {
        let m = model(n);
        group.bench_with_input(BenchmarkId::new("chiang_cached", n), &m, |b, m| {
            let mut out = vec![0.0; rig.len()];
            b.iter(|| {
                scattering_batch(&cp, m, black_box(&rig), &mut out);
                black_box(out[0])
            })
        });
    }
    let m = model(1024);
    group.bench_function("chiang_uncached/1024", |b| {
        let mut out = [0.0];
        b.iter(|| {
            for a in &rig {
                chiang_s(&cp, &m, black_box(a), &mut out);
            }
            black_box(out[0])
        })
    });
    // Values and the 5-parameter Jacobian (η, σ_a, β_m, β_n, α) as a fit needs them.
    let which = [
        ChiangParamName::Eta,
        ChiangParamName::SigmaA(0),
        ChiangParamName::BetaM,
        ChiangParamName::BetaN,
        ChiangParamName::Alpha,
    ];
    group.bench_function("chiang_cached_jacobian5/1024", |b| {
        let mut values = vec![0.0; rig.len()];
        let mut jac = vec![[0.0; 5]; rig.len()];
        b.iter(|| {
            batch_jacobian_static(&cp, &m, black_box(&rig), &which, &mut values, &mut jac);
            black_box(jac[0][0])
        })
    });
    group.finish();
}

criterion_group!(benches, bench_chiang);
criterion_main!(benches);
