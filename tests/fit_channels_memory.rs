//! Peak memory of `hairfit fit` grows linearly in the number of channels (issue 12): each
//! channel's own `σ_a` and scale are eliminated block by block, so nothing of size channels² is
//! allocated (the dense reduced Jacobian and a full covariance were). Measured through the
//! binary: the peak resident set of each fit process, from `wait4`'s resource usage.

#[path = "support/cli.rs"]
mod cli;

use std::fs::File;
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

/// Channel counts, each four times the last: linear growth quadruples the increment from one
/// count to the next, quadratic growth multiplies it by 16.
const CHANNELS: [usize; 3] = [48, 192, 768];
/// Samples per dataset (a few hundred: enough rows per channel for a determined fit).
const SAMPLES: usize = 150;

/// Run hairfit with `args` (stdout/stderr to `log`), at most `limit`; its exit success and peak
/// resident set in KiB (`ru_maxrss` of exactly this child, from `wait4`).
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

#[test]
fn fit_peak_memory_grows_linearly_in_channels() {
    let dir = std::env::temp_dir().join(format!("hairfit-channels-memory-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // One σ_a replicated to every channel (synth --channels), the rest as in data/true_rgb.json.
    let params = cli::write(
        &dir,
        "params.json",
        r#"{"eta": 1.55, "sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2,
            "w_c_deg": 15, "eccentricity": 0.9}"#,
    );
    let rig = format!("sphere:n={SAMPLES}:max=60");
    let mut peaks = Vec::new();
    for nc in CHANNELS {
        let data = dir.join(format!("c{nc}.csv"));
        let nc_text = nc.to_string();
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
        let out = dir.join(format!("fit{nc}"));
        let log = dir.join(format!("fit{nc}.log"));
        let args = [
            "fit",
            cli::s(&data),
            "--out",
            cli::s(&out),
            "--intervals",
            "linear",
            "--no-progress",
        ];
        let (ok, kib) = peak_rss_kib(&args, &log, cli::DEFAULT_LIMIT);
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
    // The increment from 192 to 768 channels is 4× the one from 48 to 192 for linear growth and
    // 16× for quadratic; 8 (the geometric middle) separates them with a factor-2 margin for the
    // allocator's and the thread pool's noise (a few MiB against increments of tens of MiB).
    assert!(d1 > 0.0, "peak did not grow from 48 to 192 channels: {peaks:?}");
    assert!(ratio < 8.0, "peak memory grows faster than linearly: {peaks:?} MiB");
    // Absolute bound: the data is 8 bytes a value; the fit keeps a few copies (values, weights,
    // model, residuals, curves) but nothing per channel pair: under 4 KiB per value is linear
    // with room; the dense path needed ~8·channels·(shared+3) bytes per value (~50 KiB here).
    assert!(per_value < 4096.0, "{per_value:.0} bytes per value: {peaks:?} MiB");
}
