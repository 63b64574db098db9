//! The frostbite family's evaluation rate on one thread, beside Marschner's on the same
//! directions (the cost ledger's seeded spread): S for one and three channels, and S with its
//! exact Jacobian in the six inputs a three-channel fit varies.

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use hairfit::families::frostbite::{
    Frostbite, BASE_COLOR, CUTICLE_ANGLE, RADIAL_SMOOTHNESS, SMOOTHNESS,
};
use hairfit::families::marschner::params::ParameterFile as _;
use hairfit::families::marschner::{scattering as marschner_s, ModelConfig};
use hairfit::families::table::fit::{TableForward, TableParam};
use hairfit::families::table::{DynTable, Table, TableParams, TermSet};
use hairfit::fit::problem::Forward;
use hairfit::geometry::{Angles, Measurement};

const N: usize = 4096;

fn params(nc: usize) -> TableParams<f64> {
    TableParams {
        values: vec![
            [0.2, 0.45, 0.7][..nc].to_vec(),
            vec![0.85],
            vec![0.7],
            vec![3f64.to_radians()],
            vec![1.55],
        ],
        n_channels: nc,
    }
}

fn bench(c: &mut Criterion) {
    let angles: Vec<Angles> = hairfit::cost::representative_angles(N, 0x9E37_79B9);
    let table = Table::<Frostbite>::NEW;
    let on = TermSet::all(3);
    let mut g = c.benchmark_group("frostbite");
    g.throughput(Throughput::Elements(N as u64));
    for nc in [1, 3] {
        let p = params(nc);
        let mut out = vec![0.0; N * nc];
        g.bench_function(format!("S/{nc}ch"), |b| {
            b.iter(|| table.eval_batch(black_box(&p), on, &angles, &mut out))
        });
    }
    let p = params(3);
    let forward = TableForward::<Frostbite>::new(on, Measurement::S);
    let mut free: Vec<TableParam<Frostbite>> = (0..3)
        .map(|c| TableParam::new((BASE_COLOR, Some(c))))
        .collect();
    free.extend([SMOOTHNESS, RADIAL_SMOOTHNESS, CUTICLE_ANGLE].map(|k| TableParam::new((k, None))));
    let (mut out, mut grad) = (vec![0.0; N * 3], vec![0.0; N * 3 * free.len()]);
    g.bench_function("S+jacobian/3ch/6free", |b| {
        b.iter(|| forward.gradients(black_box(&p), &free, &angles, &mut out, &mut grad))
    });
    let marschner = hairfit::families::marschner::params::ParamFile::load("data/true_1ch.json")
        .expect("data/true_1ch.json is shipped with the crate")
        .to_params();
    let config = ModelConfig::default();
    let mut one = [0.0];
    g.bench_function("marschner/S/1ch", |b| {
        b.iter(|| {
            for a in &angles {
                marschner_s(black_box(&marschner), &config, a, &mut one);
            }
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
