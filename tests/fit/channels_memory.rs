//! Peak memory of `hairfit fit` grows linearly in the number of channels (issue 12): each
//! channel's own `σ_a` and scale are eliminated block by block, so nothing of size channels² is
//! allocated (the dense reduced Jacobian and a full covariance were). Measured through the
//! binary: the peak resident set of each fit process, from `wait4`'s resource usage.

use crate::support::cli;

use std::fs::File;
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

/// Channel counts, each four times the last: linear growth quadruples the increment from one
/// count to the next, quadratic growth multiplies it by 16. All above 64 free parameters, so every
/// fit writes the same bounded correlation record (shared parameters plus per-channel rows): a
/// full matrix (and the report's heatmap of it) at the smallest count would add a constant that
/// is not per channel.
const CHANNELS: [usize; 3] = [200, 800, 3200];
/// Samples per dataset (enough rows per channel for a determined fit, few enough for a quick test).
const SAMPLES: usize = 40;

/// Run hairfit with `args` (stdout/stderr to `log`), at most `limit`; its exit success and peak
/// resident set in KiB (`ru_maxrss` of exactly this child, from `wait4`).
// The child is reaped by `wait4` (which also returns its usage), not by `Child::wait`.
#[allow(clippy::zombie_processes)]
fn peak_rss_kib(args: &[&str], log: &Path, limit: Duration) -> (bool, i64) {
    let mut command = cli::hairfit_command(args);
    let out = File::create(log).unwrap();
    command
        .stdin(Stdio::null())
        .stdout(out.try_clone().unwrap())
        .stderr(out);
    let child = command.spawn().expect("the hairfit binary starts");
    let pid = child.id() as libc::pid_t;
    let start = Instant::now();
    loop {
        let mut status = 0;
        // SAFETY: `rusage` is plain data (all-zero is valid); `wait4` writes only into the two
        // out-pointers, which live for the call.
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        let r = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        if r == pid {
            let ok = libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0;
            return (ok, usage.ru_maxrss);
        }
        assert_eq!(r, 0, "wait4 failed for hairfit {args:?}");
        if start.elapsed() > limit {
            // SAFETY: `pid` is our own child, not yet reaped.
            unsafe {
                libc::kill(pid, libc::SIGKILL);
                libc::wait4(pid, &mut status, 0, &mut usage);
            }
            panic!("hairfit {args:?}: still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Synthesize `samples` × `nc` channels into `dir/cNC.csv` (σ_a replicated to every channel).
fn synth(dir: &Path, nc: usize, samples: usize) -> std::path::PathBuf {
    // One σ_a replicated to every channel (synth --channels), the rest as in data/true_rgb.json.
    let params = cli::write(
        dir,
        "params.json",
        r#"{"eta": 1.55, "sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2,
            "w_c_deg": 15, "eccentricity": 0.9}"#,
    );
    let data = dir.join(format!("c{nc}.csv"));
    let (nc_text, rig) = (nc.to_string(), format!("sphere:n={samples}:max=60"));
    cli::hairfit_ok(&[
        "synth",
        "--params",
        cli::s(&params),
        "--channels",
        &nc_text,
        "--rig",
        &rig,
        "--noise",
        "relative:0.05",
        "--seed",
        "5",
        "--output",
        cli::s(&data),
    ]);
    data
}

/// The block path (72 channels: more free parameters than the dense and full-correlation limits) gives the same bits with one
/// thread and with two, for the projected scale (L2) and for explicit scales (robust loss).
#[test]
fn many_channel_fits_are_bit_identical_for_any_thread_count() {
    let dir = std::env::temp_dir().join(format!("hairfit-channels-det-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let data = synth(&dir, 72, 50);
    for loss in ["l2", "cauchy"] {
        let mut reference: Option<(String, Vec<u8>)> = None;
        for threads in ["1", "2"] {
            let out = dir.join(format!("fit-{loss}-{threads}"));
            let mut command = cli::hairfit_command(&[
                "fit",
                cli::s(&data),
                "--out",
                cli::s(&out),
                "--loss",
                loss,
                "--starts",
                "2",
                "--intervals",
                "linear",
                "--no-progress",
            ]);
            command.env("RAYON_NUM_THREADS", threads);
            let (output, _) = cli::run_within(command, cli::DEFAULT_LIMIT);
            cli::succeeded(output, &["fit", loss, threads]);
            let fit: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(out.join("fit.json")).unwrap())
                    .unwrap();
            // Parameters, scales, correlations (the block covariance) and residuals: all results.
            let results = ["parameters", "scale", "correlation", "residuals"]
                .map(|k| fit[k].to_string())
                .join("\n");
            assert!(fit["correlation"]["per_channel"]
                .as_array()
                .is_some_and(|a| a.len() == 72));
            let params = std::fs::read(out.join("params.json")).unwrap();
            match &reference {
                None => reference = Some((results, params)),
                Some((r, p)) => {
                    assert_eq!(
                        r, &results,
                        "{loss}: fit.json results differ between 1 and 2 threads"
                    );
                    assert!(
                        p == &params,
                        "{loss}: params.json differs between 1 and 2 threads"
                    );
                }
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn fit_peak_memory_grows_linearly_in_channels() {
    let dir = std::env::temp_dir().join(format!("hairfit-channels-memory-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut peaks = Vec::new();
    for nc in CHANNELS {
        let data = synth(&dir, nc, SAMPLES);
        let out = dir.join(format!("fit{nc}"));
        let log = dir.join(format!("fit{nc}.log"));
        let args = [
            "fit",
            cli::s(&data),
            "--out",
            cli::s(&out),
            "--intervals",
            "linear",
            // One start: the same stages and buffers at a third of the time of the default.
            "--starts",
            "1",
            "--no-progress",
        ];
        let started = Instant::now();
        let (ok, kib) = peak_rss_kib(&args, &log, cli::DEFAULT_LIMIT);
        eprintln!("{nc} channels: {:.1} s", started.elapsed().as_secs_f64());
        assert!(
            ok,
            "hairfit {args:?} failed:\n{}",
            std::fs::read_to_string(&log).unwrap_or_default()
        );
        peaks.push(kib as f64 / 1024.0);
    }
    std::fs::remove_dir_all(&dir).ok();
    let (d1, d2) = (peaks[1] - peaks[0], peaks[2] - peaks[1]);
    let ratio = d2 / d1;
    let values = (SAMPLES * (CHANNELS[2] - CHANNELS[1])) as f64;
    let per_value = d2 * 1024.0 * 1024.0 / values;
    eprintln!(
        "peak RSS {peaks:.1?} MiB for {CHANNELS:?} channels × {SAMPLES} samples; increments \
         {d1:.1} and {d2:.1} MiB (ratio {ratio:.2}; linear 4, quadratic 16); {per_value:.0} B per \
         added value"
    );
    // The increment from 800 to 3200 channels is 4× the one from 200 to 800 for linear growth and
    // 16× for quadratic; 8 (the geometric middle) separates them with a factor-2 margin for the
    // allocator's and the thread pool's noise (a few MiB against increments of 10–35 MiB;
    // measured 3.3).
    assert!(
        d1 > 0.0,
        "peak did not grow from 200 to 800 channels: {peaks:?}"
    );
    assert!(
        ratio < 8.0,
        "peak memory grows faster than linearly: {peaks:?} MiB"
    );
    // Absolute bound: the data is 8 bytes a value; the fit keeps a few copies (values, weights,
    // model, residuals, curves: ~360 B per value measured) but nothing per channel pair; the
    // dense reduced Jacobian of the standard errors alone (channels·8 rows × 2·channels columns)
    // was ~10 KiB per value at 3200 channels × 40 samples.
    assert!(
        per_value < 1024.0,
        "{per_value:.0} bytes per value: {peaks:?} MiB"
    );
}
