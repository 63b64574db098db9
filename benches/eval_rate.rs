//! The model's own rate on given angles, one thread: what `python/bench_eval.py` compares
//! `hairfit.eval` with. The same parameters, the same angles and the same 256-sample batches
//! `hairfit eval` and `hairfit.eval` use, all effects, cubic mode, the lane kernel eval picks;
//! timed is only the kernel, from angles already in radians into a buffer already allocated.
//!
//! `cargo bench --bench eval_rate -- ANGLES PARAMS.json [RUNS]`: ANGLES holds θ_i, then φ_i,
//! θ_r, φ_r in degrees, each n little-endian f64 (NumPy's `tofile` of the four arrays stacked);
//! prints the RUNS (default 5) wall-clock times and the process's CPU times (seconds) as JSON,
//! `{"wall": [...], "cpu": [...]}` (CPU time is the steadier one on a machine shared with
//! other work).

use std::time::Instant;

use hairfit::families::marschner::params::{ParamFile, ParameterFile as _};
use hairfit::families::marschner::{scattering_lanes, ModelConfig};
use hairfit::geometry::Angles;

/// `hairfit eval`'s rows per batch (src/eval.rs `EVAL_BATCH`).
const EVAL_BATCH: usize = 256;

fn main() {
    // cargo bench passes `--bench`; the rest are ours.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let [angles_path, params_path, rest @ ..] = args.as_slice() else {
        eprintln!("usage: cargo bench --bench eval_rate -- ANGLES PARAMS.json [RUNS]");
        return;
    };
    let runs: usize = rest
        .first()
        .map_or(5, |r| r.parse().expect("RUNS: a count"));
    let bytes = std::fs::read(angles_path).expect("ANGLES: a readable file");
    let values: Vec<f64> = bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect();
    let n = values.len() / 4;
    let column = |k: usize| &values[k * n..(k + 1) * n];
    let (ti, pi, tr, pr) = (column(0), column(1), column(2), column(3));
    let angles: Vec<Angles> = (0..n)
        .map(|i| Angles::from_degrees(ti[i], pi[i], tr[i], pr[i]))
        .collect();
    let params = ParamFile::load(params_path)
        .expect("PARAMS.json: a Marschner parameter file")
        .to_params();
    let config = ModelConfig::default();
    let nc = params.sigma_a.len();
    let eval_into = |out: &mut [f64]| {
        for (a, o) in angles
            .chunks(EVAL_BATCH)
            .zip(out.chunks_mut(EVAL_BATCH * nc))
        {
            scattering_lanes(&params, &config, a, o);
        }
    };
    // "wall"/"cpu": the kernel alone, into a buffer already written (warm pages);
    // "fresh_wall"/"fresh_cpu": into a new buffer each run, as any caller that gets a result
    // back (hairfit.eval's new array, a Vec) pays: the first write of each page faults it in.
    let mut out = vec![0.0; n * nc];
    let (mut wall, mut cpu) = (Vec::with_capacity(runs), Vec::with_capacity(runs));
    let (mut fresh_wall, mut fresh_cpu) = (Vec::with_capacity(runs), Vec::with_capacity(runs));
    // The first run warms the buffer and the caches up.
    for run in 0..=runs {
        let (start, start_cpu) = (Instant::now(), cpu_seconds());
        eval_into(&mut out);
        if run > 0 {
            wall.push(start.elapsed().as_secs_f64());
            cpu.push(cpu_seconds() - start_cpu);
        }
        std::hint::black_box(&out);
        let (start, start_cpu) = (Instant::now(), cpu_seconds());
        // Zeroed memory of this size comes from the allocator as untouched zero pages (calloc),
        // so as with a new NumPy array the evaluation's first writes fault them in.
        let mut fresh = vec![0.0; n * nc];
        eval_into(&mut fresh);
        std::hint::black_box(&fresh);
        if run > 0 {
            fresh_wall.push(start.elapsed().as_secs_f64());
            fresh_cpu.push(cpu_seconds() - start_cpu);
        }
    }
    println!(
        "{{\"wall\": {wall:?}, \"cpu\": {cpu:?}, \"fresh_wall\": {fresh_wall:?}, \
         \"fresh_cpu\": {fresh_cpu:?}}}"
    );
}

/// The CPU time this process has used (`CLOCK_PROCESS_CPUTIME_ID`, what Python's
/// `time.process_time` reads).
fn cpu_seconds() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec for the call to fill.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_PROCESS_CPUTIME_ID)");
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}
