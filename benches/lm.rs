//! Speed of the LM solver on NIST StRD problems of increasing size and difficulty.

use criterion::{criterion_group, criterion_main, Criterion};

#[path = "../tests/support/lm.rs"]
mod lm;
#[path = "../tests/support/nist.rs"]
mod nist;

use nist::{data_dir, run_all, solve, NistProblem};

fn bench_nist(c: &mut Criterion) {
    for (name, start) in [
        ("Misra1a", 1),
        ("Thurber", 1),
        ("MGH10", 1),
        ("Bennett5", 1),
    ] {
        let p = NistProblem::load(&data_dir().join(format!("{name}.dat"))).unwrap();
        c.bench_function(&format!("lm {name} start {start}"), |b| {
            b.iter(|| solve(&p, start).unwrap())
        });
    }
    c.bench_function("lm all 54 NIST StRD pairs", |b| {
        b.iter(|| run_all().unwrap())
    });
}

criterion_group!(benches, bench_nist);
criterion_main!(benches);
