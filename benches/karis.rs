//! Karis 2016 (`--model karis`) evaluations per second beside Marschner's, on the cost ledger's
//! seeded spread of directions: S of one and of three channels (R, TT, TRT, the default terms),
//! and the dual-number pass the fit's Jacobian takes (5 free parameters, 3 channels).
//! Throughput counts samples (direction pairs).

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use hairfit::families::karis::Karis;
use hairfit::families::marschner::params::ParameterFile as _;
use hairfit::families::marschner::{scattering_batch as marschner_batch, ModelConfig};
use hairfit::families::table::{DynTable, Table, TableFamily, TableParams};
use hairfit::geometry::Angles;
use nalgebra::{Const, U1};
use num_dual::{Derivative, DualVec64};

fn karis_params(n_channels: usize) -> TableParams<f64> {
    let mut p = TableParams::defaults(Karis::PARAMETERS, n_channels);
    p.values[0] = [0.25, 0.4, 0.55][..n_channels].to_vec();
    p
}

fn bench(c: &mut Criterion) {
    let angles: Vec<Angles> = hairfit::cost::representative_angles(10_000, 0x9E37_79B9);
    let mut g = c.benchmark_group("karis");
    g.throughput(Throughput::Elements(angles.len() as u64));
    let table = Table::<Karis>::NEW;
    for nc in [1, 3] {
        let p = karis_params(nc);
        let on = Karis::default_terms();
        let mut out = vec![0.0; angles.len() * nc];
        g.bench_function(format!("S/{nc}ch"), |b| {
            b.iter(|| table.eval_batch(black_box(&p), on, black_box(&angles), &mut out))
        });
    }
    let p = karis_params(3);
    let mut dual = p.map(|&x| DualVec64::<Const<5>>::from_re(x));
    for (j, (k, ch)) in [(0, 0), (0, 1), (0, 2), (1, 0), (2, 0)]
        .into_iter()
        .enumerate()
    {
        let d = Derivative::derivative_generic(Const::<5>, U1, j);
        dual.values[k][ch] = DualVec64::new(p.values[k][ch], d);
    }
    g.bench_function("S+jacobian(5)/3ch", |b| {
        b.iter(|| {
            let mut terms = hairfit::families::table::zero_terms(3);
            for a in &angles {
                hairfit::families::table::clear_terms(&mut terms);
                Karis::scatter(black_box(&dual), a, Karis::default_terms(), &mut terms);
            }
            terms
        })
    });
    let m = hairfit::families::marschner::params::ParamFile::load("data/true_1ch.json")
        .expect("data/true_1ch.json is shipped with the crate")
        .to_params();
    let config = ModelConfig::default();
    let mut out = vec![0.0; angles.len()];
    g.bench_function("marschner S/1ch", |b| {
        b.iter(|| marschner_batch(black_box(&m), &config, black_box(&angles), &mut out))
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
