//! Evaluations per second of S for each root mode and effect set, and of the Jacobian.
//! Each iteration evaluates one batch of `BATCH` angle sets, so throughput = BATCH / time.

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use hairfit::families::marschner::fit::forward::MarschnerForward;
use hairfit::families::marschner::params::ParameterFile as _;
use hairfit::families::marschner::{
    scattering, scattering_batch, scattering_jacobian, scattering_lanes, scattering_lanes_on,
    Effects, LaneKernel, Lobes, ModelConfig, ParamName, Params, RootMode, StaticJacobian,
};
use hairfit::fit::Forward;
use hairfit::geometry::{Angles, Measurement};

const BATCH: usize = 1024;

/// MODEL.md's known-values parameter set, as shipped in `data/true_1ch.json`.
fn params() -> Params<f64> {
    hairfit::families::marschner::params::ParamFile::load("data/true_1ch.json")
        .expect("data/true_1ch.json is shipped with the crate")
        .to_params()
}

/// The ledger's seeded spread over the whole domain (θ in (−80°, 80°), φ any): the same
/// directions the cost ledger times, so the two agree.
fn angle_set() -> Vec<Angles> {
    hairfit::cost::representative_angles(BATCH, 0x9E37_79B9)
}

fn effect_sets() -> Vec<(&'static str, Effects)> {
    let lobes = |r, tt, trt| Lobes { r, tt, trt };
    let plain = |l| Effects {
        lobes: l,
        glints: false,
        eccentricity: false,
    };
    vec![
        ("R", plain(lobes(true, false, false))),
        ("R+TT", plain(lobes(true, true, false))),
        ("all-lobes", plain(lobes(true, true, true))),
        ("all+glints+ecc", Effects::default()),
    ]
}

fn bench_model(c: &mut Criterion) {
    let p = params();
    let angles = angle_set();
    let mut group = c.benchmark_group("scattering");
    group.throughput(Throughput::Elements(BATCH as u64));
    for mode in [RootMode::Cubic, RootMode::Exact] {
        for (name, effects) in effect_sets() {
            let config = ModelConfig { mode, effects };
            group.bench_with_input(
                BenchmarkId::new(mode.to_string(), name),
                &config,
                |b, cfg| {
                    let mut out = [0.0];
                    b.iter(|| {
                        let mut acc = 0.0;
                        for a in &angles {
                            scattering(black_box(&p), cfg, a, &mut out);
                            acc += out[0];
                        }
                        acc
                    })
                },
            );
        }
    }
    group.finish();

    let mut group = c.benchmark_group("jacobian");
    group.throughput(Throughput::Elements(BATCH as u64));
    let which = [
        ParamName::Eta,
        ParamName::SigmaA(0),
        ParamName::AlphaR,
        ParamName::BetaR,
        ParamName::KG,
        ParamName::WC,
        ParamName::Eccentricity,
    ];
    for mode in [RootMode::Cubic, RootMode::Exact] {
        let config = ModelConfig {
            mode,
            effects: Effects::default(),
        };
        group.bench_with_input(
            BenchmarkId::new(mode.to_string(), "static 7 params"),
            &config,
            |b, cfg| {
                let mut sj = StaticJacobian::<7>::new(&p, &which);
                let (mut v, mut j) = ([0.0], [[0.0; 7]]);
                b.iter(|| {
                    let mut acc = 0.0;
                    for a in &angles {
                        sj.eval(cfg, a, &mut v, &mut j);
                        acc += j[0][0];
                    }
                    acc
                })
            },
        );
        group.bench_with_input(
            BenchmarkId::new(mode.to_string(), "dyn 7 params"),
            &config,
            |b, cfg| {
                b.iter(|| {
                    let mut acc = 0.0;
                    for a in &angles {
                        acc += scattering_jacobian(black_box(&p), cfg, a, &which).0[0];
                    }
                    acc
                })
            },
        );
    }
    group.finish();
}

/// The fit's passes over a batch of 3-channel samples: values (cost, `hairfit eval`) and the
/// compressed exact gradients of the default free set (linearisation; σ_a in one dual slot).
fn bench_batch(c: &mut Criterion) {
    let mut p = params();
    p.sigma_a = vec![0.2, 0.4, 0.8];
    let angles = angle_set();
    let fwd = MarschnerForward {
        config: ModelConfig::default(),
        measurement: Measurement::S,
    };
    let mut group = c.benchmark_group("batch 3 channels");
    group.throughput(Throughput::Elements(BATCH as u64));
    let mut out = vec![0.0; BATCH * 3];
    group.bench_function("values", |b| {
        b.iter(|| {
            fwd.values(black_box(&p), &angles, &mut out);
            out[0]
        })
    });
    let shared = [
        ParamName::Eta,
        ParamName::AlphaR,
        ParamName::BetaR,
        ParamName::KG,
        ParamName::WC,
    ];
    let local: Vec<_> = (0..3).map(|c| Some(ParamName::SigmaA(c))).collect();
    let mut grad = vec![0.0; BATCH * 3 * (shared.len() + 1)];
    group.bench_function("gradients 5 shared + sigma_a", |b| {
        b.iter(|| {
            fwd.gradients_compressed(black_box(&p), &shared, &local, &angles, &mut out, &mut grad);
            grad[0]
        })
    });
    group.finish();
}

/// `hairfit eval`'s f64 path: the batch on each lane kernel this CPU runs (`Wide`: wide's SSE2
/// halves, any x86-64 CPU; `Avx2`: eight lanes in two AVX registers; `Avx512`: eight in one;
/// eval picks the last listed) against the scalar batch, all effects, cubic mode, 1 and 3
/// channels. "picked lanes" below is the kernel eval picks, per effect set.
fn bench_lanes(c: &mut Criterion) {
    let angles = angle_set();
    let config = ModelConfig::default();
    let mut group = c.benchmark_group("lanes");
    group.throughput(Throughput::Elements(BATCH as u64));
    for channels in [vec![0.4], vec![0.2, 0.4, 0.8]] {
        let mut p = params();
        p.sigma_a = channels;
        let nc = p.sigma_a.len();
        let mut out = vec![0.0; BATCH * nc];
        group.bench_function(format!("scalar batch, {nc} ch"), |b| {
            b.iter(|| {
                scattering_batch(black_box(&p), &config, &angles, &mut out);
                out[0]
            })
        });
        for kernel in LaneKernel::on_this_cpu() {
            group.bench_function(format!("{kernel:?} lanes, {nc} ch"), |b| {
                b.iter(|| {
                    scattering_lanes_on(kernel, black_box(&p), &config, &angles, &mut out);
                    out[0]
                })
            });
        }
    }
    let mut p = params();
    p.sigma_a = vec![0.4];
    let mut out = vec![0.0; BATCH];
    let mut sets = effect_sets();
    let all = Effects::default();
    sets.push((
        "all+glints",
        Effects {
            eccentricity: false,
            ..all
        },
    ));
    sets.push((
        "all+ecc",
        Effects {
            glints: false,
            ..all
        },
    ));
    for (name, effects) in sets {
        let config = ModelConfig {
            mode: RootMode::Cubic,
            effects,
        };
        group.bench_function(format!("picked lanes, {name}"), |b| {
            b.iter(|| {
                scattering_lanes(black_box(&p), &config, &angles, &mut out);
                out[0]
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_model, bench_batch, bench_lanes);
criterion_main!(benches);
