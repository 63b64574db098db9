//! Load throughput: a generated 10-million-row header CSV (one channel, sigma column), loaded
//! end to end (parse, validate, duplicate check). Reports time per load and rows/s.
//!
//! Eval throughput on one thread: a 1-million-row angles CSV through `eval_stream` into a sink,
//! with the real model (3 channels) and with a trivial stand-in model, so the second number is
//! the CSV reading, number parsing and formatting alone (what is left to the model is the
//! difference). The I/O alone also on angles written to full precision (17 significant digits,
//! as a program printing its f64s writes them): each digit costs parse time.

use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode, Throughput};
use hairfit::data::{load, LoadOptions};
use hairfit::eval::{eval_stream, eval_stream_with, output_columns, EvalRequest};
use hairfit::families::{FamilyModel, FamilyParams, ModelFamily};
use hairfit::geometry::Angles;

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

const EVAL_ROWS: u64 = 1_000_000;

/// Angles rows like a measured file: six decimals (or, `full_precision`, the shortest text that
/// round-trips, mostly 16–17 significant digits), every angle in range.
fn generate_angles(path: &Path, rows: u64, full_precision: bool) {
    let mut w = BufWriter::with_capacity(1 << 20, std::fs::File::create(path).unwrap());
    writeln!(w, "theta_i,phi_i,theta_r,phi_r").unwrap();
    let mut h: u64 = 0x2545_F491_4F6C_DD1D;
    let mut next = |range: f64| {
        h ^= h << 13;
        h ^= h >> 7;
        h ^= h << 17;
        ((h >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * range
    };
    for _ in 0..rows {
        let (ti, pi, tr, pr) = (next(160.0), next(360.0), next(160.0), next(360.0));
        if full_precision {
            writeln!(w, "{ti},{pi},{tr},{pr}").unwrap();
        } else {
            writeln!(w, "{ti:.6},{pi:.6},{tr:.6},{pr:.6}").unwrap();
        }
    }
    w.flush().unwrap();
}

fn bench_eval(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("angles.csv");
    generate_angles(&path, EVAL_ROWS, false);
    let full_path = dir.path().join("angles_full_precision.csv");
    generate_angles(&full_path, EVAL_ROWS, true);
    let params_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/true_rgb.json");
    let file = FamilyParams::load(&params_path, ModelFamily::Marschner).unwrap();
    let request = EvalRequest {
        output_columns: output_columns(file.n_channels(), file.sigma_a_is_scalar()),
        model: FamilyModel::new(&file, &Default::default()),
        params: file,
        angles: None,
    };
    let n_channels = request.model.n_channels();
    // Values with as many digits as the model's, at the cost of a multiply-add.
    let stand_in = move |angles: &[Angles], out: &mut [f64]| {
        for (a, row) in angles.iter().zip(out.chunks_mut(n_channels)) {
            for (c, v) in row.iter_mut().enumerate() {
                *v = 0.1 + (a.theta_i * 0.37 + a.phi_r * 0.011) * (1.0 + c as f64).abs();
                *v = v.abs();
            }
        }
    };
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    // CPU time per run as well: on a shared machine wall time says more about the other
    // processes than about this code.
    for (what, with_model, path) in [
        ("3 channels", true, &path),
        ("I/O only", false, &path),
        ("I/O only, 17-digit angles", false, &full_path),
    ] {
        let runs = 3;
        let before = cpu_seconds();
        for _ in 0..runs {
            one_thread.install(|| {
                let input = std::fs::File::open(path).unwrap();
                let sink = &mut std::io::sink();
                if with_model {
                    eval_stream(input, path, sink, &request).unwrap();
                } else {
                    eval_stream_with(input, path, sink, &request, &stand_in).unwrap();
                }
            })
        }
        let per_run = (cpu_seconds() - before) / runs as f64;
        println!(
            "eval one thread, {what}: {per_run:.3} s CPU per {EVAL_ROWS} rows = {:.2} M rows/s",
            EVAL_ROWS as f64 / per_run / 1e6
        );
    }
    let mut group = c.benchmark_group("eval_one_thread");
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(20))
        .throughput(Throughput::Elements(EVAL_ROWS));
    group.bench_function("csv_1M_rows_3_channels", |b| {
        b.iter(|| {
            one_thread.install(|| {
                let input = std::fs::File::open(&path).unwrap();
                eval_stream(input, &path, &mut std::io::sink(), &request)
                    .unwrap()
                    .rows
            })
        })
    });
    group.bench_function("csv_1M_rows_io_only", |b| {
        b.iter(|| {
            one_thread.install(|| {
                let input = std::fs::File::open(&path).unwrap();
                eval_stream_with(input, &path, &mut std::io::sink(), &request, &stand_in)
                    .unwrap()
                    .rows
            })
        })
    });
    group.finish();
}

/// User + system CPU seconds of this process so far (Linux `/proc/self/stat`, 100 ticks/s).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after_name = stat.rsplit(')').next().unwrap_or("");
    // Fields after the name start at field 3; utime and stime are fields 14 and 15.
    let fields: Vec<&str> = after_name.split_whitespace().collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|f| f.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0
}

criterion_group!(benches, bench_load, bench_eval);
criterion_main!(benches);
