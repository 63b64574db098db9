//! Nothing is lost under interruption: SIGINT stops `hairfit fit` at the next iteration, and it
//! still writes a complete fit.json with status and verdict "interrupted" and finite best-so-far
//! parameters, then exits 130 (143 after SIGTERM) so no script mistakes it for a finished fit.
//! Output files are written atomically: a reader polling the output directory never sees a
//! half-written fit.json, and no temporary file is left behind.

#![cfg(unix)]

use std::path::Path;
use std::process::{Child, Command};
use std::time::{Duration, Instant};

use crate::support::hard::*;
use hairfit::demo::{demo_geometry, DEMO_SCALE};
use hairfit::families::marschner::demo::demo_truth;
use hairfit::families::marschner::fit::synthetic::synthesize;
use hairfit::families::marschner::ModelConfig;
use hairfit::fit::design::SplitMix64;
use hairfit::geometry::Angles;

/// ~100k samples × 3 channels: the demo scan repeated with jittered azimuths, 2% noise.
fn big_dataset(path: &Path) {
    let base = demo_geometry();
    let mut rng = SplitMix64::new(5);
    let angles: Vec<Angles> = (0..43)
        .flat_map(|_| base.to_vec())
        .map(|a| Angles {
            phi_r: a.phi_r + (rng.uniform() - 0.5) * 0.1,
            ..a
        })
        .collect();
    let data = synthesize(
        &demo_truth(),
        &ModelConfig::default(),
        &angles,
        &DEMO_SCALE,
        0.02,
        9,
    );
    write_csv(&data, path);
}

/// A deliberately long fit (~30 s or more uninterrupted on 2 cores): 16 starts on all ~100k
/// samples, up to 200 LM iterations each, so a signal at 2.5 s lands mid-fit however fast the
/// polish gets.
const ARGS: [&str; 10] = [
    "--starts",
    "16",
    "--subsample",
    "200000",
    "--start-iters",
    "200",
    "--polish-iters",
    "500",
    "--no-progress",
    "--seed",
];

fn start_fit(data: &Path, out: &Path) -> Child {
    let mut args = vec![
        "fit",
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(ARGS);
    args.push("3");
    spawn_hairfit(&args, &[])
}

/// `kill -INT pid` (std has no signal API; the system `kill` avoids a libc dependency).
fn sigint(child: &Child) {
    let ok = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs")
        .success();
    assert!(ok, "kill -INT failed");
}

/// Poll `dir/fit.json` every few ms until `until`: whenever it exists it must be complete JSON.
fn watch_fit_json(dir: &Path, until: Instant) -> usize {
    let mut seen = 0;
    while Instant::now() < until {
        if let Ok(text) = std::fs::read_to_string(dir.join("fit.json")) {
            serde_json::from_str::<serde_json::Value>(&text)
                .unwrap_or_else(|e| panic!("half-written fit.json seen by a reader: {e}"));
            seen += 1;
        }
        std::thread::sleep(Duration::from_millis(3));
    }
    seen
}

/// SIGINT `delay` after start; returns (exit, wall time from the signal to exit).
fn interrupt_after(data: &Path, out: &Path, delay: Duration) -> (Finished, Duration) {
    let child = start_fit(data, out);
    watch_fit_json(out, Instant::now() + delay);
    sigint(&child);
    let t = Instant::now();
    // 60 s: the fit checks the flag every LM iteration (~0.1 s here) and then writes ~300k
    // curve rows; only a fit that ignores the signal gets near this.
    let f = wait_with_deadline(child, Duration::from_secs(60), "interrupted fit");
    (f, t.elapsed())
}

/// One-minute load average per core (at least 1): how many runnable threads share each core.
fn oversubscription() -> f64 {
    let load: f64 = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0.0);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    (load / cores).max(1.0)
}

#[test]
fn sigint_writes_a_complete_interrupted_fit_and_never_a_partial_file() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("big.csv");
    big_dataset(&data);
    let out = dir.path().join("fit");

    // 1. Interrupted mid-fit (loading takes ~0.3 s, the fit with ARGS ~30 s or more).
    let (f, stop) = interrupt_after(&data, &out, Duration::from_millis(2500));
    // 130 = 128 + SIGINT: `hairfit fit … && publish` must not publish a stopped fit.
    assert_eq!(
        f.status.code(),
        Some(130),
        "interrupted fit should write its best so far and exit 130: {}",
        f.stderr
    );
    let j = check_fit_dir(&out, "interrupted");
    assert_eq!(j["status"], "interrupted", "{}", f.stdout);
    assert_eq!(j["verdict"], "interrupted", "{}", f.stdout);
    assert!(
        f.stdout.starts_with("verdict: interrupted"),
        "the summary starts with the verdict: {}",
        f.stdout
    );
    for p in j["parameters"].as_array().unwrap() {
        assert!(
            p["value"].as_f64().is_some_and(f64::is_finite),
            "best-so-far {p}"
        );
    }
    for s in j["scale"].as_array().unwrap() {
        assert!(
            s["value"]
                .as_f64()
                .is_some_and(|v| v.is_finite() && v > 0.0),
            "scale {s}"
        );
    }
    let rms = j["residuals"]["rms"].as_f64().unwrap();
    assert!(rms.is_finite(), "rms {rms}");
    assert_eq!(j["data"]["n_samples"], 100620);
    eprintln!("SIGINT at 2.5 s: exit {stop:?} later, best-so-far rms {rms}");
    // Stopping is prompt: the running LM iterations finish, one polish initialisation, the
    // covariance and ~300k curve rows. Measured 1.9 s alone, 3.8 s beside the other tests of this
    // file on the shared 2-core machine (7.4–10.9 s before queued multi-start runs were skipped
    // after the signal); 8 s leaves 2× for load from other processes. The passes over the data
    // check the flag per chunk, so the bound scales with how oversubscribed the machine is (a
    // load of 12 on 2 cores gives the fit a sixth of its CPU): wall time, not work, is measured.
    let allowed = Duration::from_secs_f64(8.0 * oversubscription());
    assert!(
        stop < allowed,
        "took {stop:?} to stop after SIGINT (allowed {allowed:?})"
    );
    let first = std::fs::read_to_string(out.join("fit.json")).unwrap();

    // 2. A second run into the same directory, interrupted early (during loading or the first
    // starts): a reader never sees a partial fit.json; after exit it is complete and either the
    // previous one or a new interrupted one; no temporary file is left.
    for delay_ms in [400, 1200] {
        let (f, _) = interrupt_after(&data, &out, Duration::from_millis(delay_ms));
        // SIGINT before the handler is installed kills the process with the default action
        // (no output written); after, the fit exits 130 having written its best so far.
        let by_signal = f.status.code().is_none();
        assert!(
            by_signal || f.status.code() == Some(130),
            "exit {:?}: {}",
            f.status,
            f.stderr
        );
        let j = check_fit_dir(&out, &format!("second run, SIGINT at {delay_ms} ms"));
        let now = std::fs::read_to_string(out.join("fit.json")).unwrap();
        assert!(
            now == first || j["status"] == "interrupted",
            "status {}",
            j["status"]
        );
    }
}

#[test]
fn a_completed_run_replaces_fit_json_atomically_under_a_polling_reader() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("demo.csv");
    let d = synthesize(
        &demo_truth(),
        &ModelConfig::default(),
        &demo_geometry(),
        &DEMO_SCALE,
        0.02,
        2,
    );
    write_csv(&d, &data);
    let out = dir.path().join("fit");
    for run in 0..3 {
        let args = [
            "fit",
            data.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--no-progress",
            "--starts",
            "4",
            "--seed",
            &run.to_string(),
        ];
        let child = spawn_hairfit(&args, &[]);
        let t0 = Instant::now();
        let mut child = Some(child);
        let mut finished = None;
        // Poll the directory while the child runs (and writes).
        while finished.is_none() {
            watch_fit_json(&out, Instant::now() + Duration::from_millis(30));
            if let Some(status) = child.as_mut().unwrap().try_wait().unwrap() {
                finished = Some(status);
            }
            assert!(t0.elapsed() < Duration::from_secs(60), "run {run} hangs");
        }
        let _ = child.take().unwrap().wait_with_output();
        assert!(finished.unwrap().success(), "run {run}");
        let j = check_fit_dir(&out, &format!("run {run}"));
        assert_eq!(j["options"]["seed"], run, "fit.json is the new run's");
    }
}

/// SIGTERM (what `timeout`, batch schedulers and service managers send before SIGKILL) keeps
/// the best so far exactly like Ctrl-C, and exits 143 as the signal would.
#[test]
fn sigterm_also_writes_the_best_so_far() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("big.csv");
    big_dataset(&data);
    let out = dir.path().join("fit");
    let child = start_fit(&data, &out);
    std::thread::sleep(Duration::from_millis(2500));
    let ok = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill runs")
        .success();
    assert!(ok, "kill -TERM failed");
    let f = wait_with_deadline(child, Duration::from_secs(60), "terminated fit");
    // 143 = 128 + SIGTERM, after writing the best so far.
    assert_eq!(
        f.status.code(),
        Some(143),
        "SIGTERM: {:?} {}",
        f.status,
        f.stderr
    );
    let j = check_fit_dir(&out, "terminated");
    assert_eq!(j["status"], "interrupted");
    assert_eq!(j["verdict"], "interrupted");
}

/// Ctrl-C during `hairfit eval --output` must not leave the atomic writer's temporary file (it
/// can be hundreds of MB) nor a partial output behind.
#[test]
fn sigint_during_eval_leaves_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let params = dir.path().join("p.json");
    std::fs::write(
        &params,
        r#"{"sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2, "w_c_deg": 15, "eccentricity": 0.9}"#,
    )
    .unwrap();
    // 3M rows: evaluating and writing them takes a few seconds.
    let input = dir.path().join("angles.csv");
    let mut s = String::from("theta_i,phi_i,theta_r,phi_r\n");
    let mut rng = SplitMix64::new(1);
    for _ in 0..3_000_000 {
        let mut u = |lo: f64, hi: f64| lo + (hi - lo) * rng.uniform();
        s += &format!(
            "{:.4},{:.4},{:.4},{:.4}\n",
            u(-60.0, 60.0),
            u(0.0, 360.0),
            u(-60.0, 60.0),
            u(-180.0, 180.0)
        );
    }
    std::fs::write(&input, s).unwrap();
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let output = out_dir.join("s.csv");
    let child = spawn_hairfit(
        &[
            "eval",
            "--params",
            params.to_str().unwrap(),
            "--input",
            input.to_str().unwrap(),
            "--output",
            output.to_str().unwrap(),
        ],
        &[],
    );
    std::thread::sleep(Duration::from_millis(700));
    sigint(&child);
    let f = wait_with_deadline(child, Duration::from_secs(60), "interrupted eval");
    if f.status.success() {
        // Finished before the signal: the output must then be complete.
        let text = std::fs::read_to_string(&output).unwrap();
        assert_eq!(text.lines().count(), 3_000_001, "complete output");
    } else if output.exists() {
        // The signal landed after the output was committed (renamed into place) and before the
        // process ended: exit 130 with the complete file, never a partial one. Seen once in a
        // full suite run, where the eval finished in about the test's 700 ms.
        let text = std::fs::read_to_string(&output).unwrap();
        assert_eq!(
            text.lines().count(),
            3_000_001,
            "interrupted eval left a partial {}",
            output.display()
        );
    }
    assert_no_temp_files(&out_dir, "interrupted eval");
}

/// A second Ctrl-C means "stop now" (the first one lets the fit write its best so far, which can
/// take a while on large data): the process exits promptly with 130 and leaves no temp file.
#[test]
fn a_second_sigint_exits_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("big.csv");
    big_dataset(&data);
    let out = dir.path().join("fit");
    let child = start_fit(&data, &out);
    std::thread::sleep(Duration::from_millis(2500));
    sigint(&child);
    std::thread::sleep(Duration::from_millis(100));
    sigint(&child);
    let t = std::time::Instant::now();
    let f = wait_with_deadline(child, Duration::from_secs(60), "twice interrupted fit");
    assert_eq!(f.status.code(), Some(130), "{:?} {}", f.status, f.stderr);
    // The exit happens in the signal handler: far below a fit's 1–4 s wind-down.
    assert!(
        t.elapsed() < Duration::from_secs(1),
        "took {:?}",
        t.elapsed()
    );
    if out.exists() {
        assert_no_temp_files(&out, "twice interrupted fit");
    }
}
