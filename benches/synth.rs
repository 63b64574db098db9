//! Samples per second of `synthesize` (rig + model + noise, in memory) and of the noise alone.

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use hairfit::families::marschner::fit::synthetic::synthesize_rig;
use hairfit::families::marschner::params::ParamFile;
use hairfit::families::marschner::params::ParameterFile as _;
use hairfit::families::marschner::ModelConfig;
use hairfit::geometry::Measurement;
use hairfit::synth::{Noise, Rig};

const N: usize = 10_000;

fn bench(c: &mut Criterion) {
    let params = ParamFile::from_json_str(
        r#"{"sigma_a": [0.2, 0.4, 0.8], "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2,
            "w_c_deg": 15, "eccentricity": 0.9}"#,
        "bench",
    )
    .unwrap()
    .to_params();
    let rig = Rig::parse(&format!("sphere:n={N}")).unwrap();
    let noise = Noise::parse("photon:1000+relative:0.02+floor:1e-4+outliers:0.01").unwrap();
    let config = ModelConfig::default();
    let mut g = c.benchmark_group("synth");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("synthesize_sphere_rgb_all_noise", |b| {
        b.iter(|| {
            synthesize_rig(
                &params,
                &config,
                &rig,
                &noise,
                &[1.0; 3],
                Measurement::S,
                black_box(7),
            )
            .unwrap()
        })
    });
    let clean: Vec<f64> = (0..3 * N).map(|j| 0.01 + (j % 100) as f64 * 0.02).collect();
    g.bench_function("noise_only_rgb_all_terms", |b| {
        b.iter(|| noise.apply(black_box(&clean), 3, 7))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
