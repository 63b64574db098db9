//! Load throughput: a generated 10-million-row header CSV (one channel, sigma column), loaded
//! end to end (parse, validate, duplicate check). Reports time per load and rows/s.

use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode, Throughput};
use hairfit::data::{load, LoadOptions};

const ROWS: u64 = 10_000_000;

/// Write `rows` distinct, valid rows shaped like real data: integer incident angles, half-degree
/// outgoing angles, radiance with 6 significant digits.
fn generate(path: &Path, rows: u64) {
    let mut w = BufWriter::with_capacity(1 << 20, std::fs::File::create(path).unwrap());
    writeln!(w, "# generated for the load benchmark").unwrap();
    writeln!(w, "theta_i,phi_i,theta_r,phi_r,radiance,sigma").unwrap();
    let mut h: u64 = 0x9E37_79B9_7F4A_7C15;
    for i in 0..rows {
        h ^= h << 13;
        h ^= h >> 7;
        h ^= h << 17;
        let theta_i = (i % 161) as i64 - 80;
        let theta_r = ((i / 161) % 100) as i64 - 50;
        let phi_r = (i / 16_100) as i64 - 311;
        writeln!(
            w,
            "{theta_i},0,{theta_r}.5,{phi_r}.25,{}.{:05}e-2,0.0{}",
            1 + h % 9,
            (h >> 8) % 100_000,
            1 + (h >> 40) % 9
        )
        .unwrap();
    }
    w.flush().unwrap();
}

fn bench_load(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ten_million.csv");
    generate(&path, ROWS);
    let options = LoadOptions::default();
    let mut group = c.benchmark_group("load");
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(30))
        .throughput(Throughput::Elements(ROWS));
    group.bench_function("csv_10M_rows", |b| {
        b.iter(|| {
            let (ds, report) = load(&path, &options).unwrap();
            assert_eq!(report.accepted, ROWS);
            ds.len()
        })
    });
    group.finish();
}

criterion_group!(benches, bench_load);
criterion_main!(benches);
