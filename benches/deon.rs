//! d'Eon 2011 (`--model deon`) evaluations per second against Marschner: S with every term at a
//! narrow, the default and a wide detector (their node counts 128, 48, 48), without the residual,
//! and the fit's three-channel Jacobian in six dual directions. Throughput counts samples (one S
//! per channel) on the cost ledger's seeded directions.

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use hairfit::families::deon::DEon;
use hairfit::families::marschner::params::ParameterFile as _;
use hairfit::families::marschner::scattering as marschner_s;
use hairfit::families::table::{zero_terms, TableFamily, TableParams, TermSet};
use hairfit::geometry::Angles;
use nalgebra::{Const, U1};
use num_dual::{Derivative, DualVec64};

/// `nc` channels of the table's defaults with β_N = `beta_n_deg`.
fn deon_params(nc: usize, beta_n_deg: f64) -> TableParams<f64> {
    let mut p = TableParams::defaults(DEon::PARAMETERS, nc);
    let k = DEon::PARAMETERS
        .iter()
        .position(|f| f.name == "beta_n_deg")
        .unwrap();
    p.values[k][0] = beta_n_deg.to_radians();
    p
}

fn bench_deon(c: &mut Criterion) {
    let angles: Vec<Angles> = hairfit::cost::representative_angles(512, 0x9E37_79B9);
    let marschner = hairfit::families::marschner::params::ParamFile::load("data/true_1ch.json")
        .expect("data/true_1ch.json is shipped with the crate")
        .to_params();
    let mut group = c.benchmark_group("per_sample");
    group.sample_size(10);
    group.throughput(Throughput::Elements(angles.len() as u64));
    group.bench_function("marschner_default", |b| {
        let config = hairfit::families::marschner::ModelConfig::default();
        b.iter(|| {
            let mut out = [0.0];
            for a in &angles {
                marschner_s(black_box(&marschner), &config, a, &mut out);
            }
            out
        })
    });
    let cases = [
        ("deon_all_terms/beta_n_5deg", 5.0, TermSet::all(4)),
        ("deon_all_terms/beta_n_15deg", 15.0, TermSet::all(4)),
        ("deon_all_terms/beta_n_40deg", 40.0, TermSet::all(4)),
        ("deon_r_tt_trt/beta_n_15deg", 15.0, TermSet(0b0111)),
    ];
    for (name, beta_n, on) in cases {
        let p = deon_params(1, beta_n);
        group.bench_function(name, |b| {
            let mut out = zero_terms::<f64>(1);
            b.iter(|| {
                let mut sum = 0.0;
                for a in &angles {
                    out[0] = [0.0; 6];
                    DEon::scatter(black_box(&p), a, on, &mut out);
                    sum += out[0].iter().sum::<f64>();
                }
                sum
            })
        });
    }
    // The fit's forward pass: three channels, σ_a × 3, β_R, β_N, α as dual directions.
    let p = deon_params(3, 15.0);
    let mut pd = p.map(|&x| DualVec64::<Const<6>>::from_re(x));
    let seeds = [(1, 0), (1, 1), (1, 2), (2, 0), (3, 0), (4, 0)];
    for (j, (k, ch)) in seeds.into_iter().enumerate() {
        let d = Derivative::derivative_generic(Const::<6>, U1, j);
        pd.values[k][ch] = DualVec64::new(p.values[k][ch], d);
    }
    group.bench_function("deon_jacobian6_3ch/beta_n_15deg", |b| {
        let mut out = zero_terms::<DualVec64<Const<6>>>(3);
        b.iter(|| {
            let mut sum = 0.0;
            for a in &angles {
                hairfit::families::table::clear_terms(&mut out);
                DEon::scatter(black_box(&pd), a, TermSet::all(4), &mut out);
                sum += out[0][0].re;
            }
            sum
        })
    });
    group.finish();
}

criterion_group!(benches, bench_deon);
criterion_main!(benches);
