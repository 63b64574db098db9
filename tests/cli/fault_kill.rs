//! SIGKILL at random moments of fit, compare, batch and report: the published directory is
//! always a whole set (the old one or the new one: every name its marker lists is there and
//! its fit.json reads), and after the next run no staging directory or lock is left beside it
//! or inside it. The default run kills each command a few times; the ignored test kills each
//! 20 times (`cargo test --release --test cli fault_kill:: -- --ignored`).

#![cfg(unix)]

use crate::support::cli;

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use cli::{hairfit_ok, s, shipped, write};

/// Lock files or staging directories in `dir` or below.
fn leftovers(dir: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.contains("hairfit-lock") || name.contains("hairfit-stage") {
            found.push(path.display().to_string());
        } else if path.is_dir() && !path.is_symlink() {
            found.extend(leftovers(&path));
        }
    }
    found
}

/// Panics unless `dir` is a whole published set: its marker lists only names that are there,
/// each listed marked sub-directory is whole too, and a fit's fit.json parses beside its page.
fn assert_whole(dir: &Path, what: &str) {
    let marker = std::fs::read_to_string(dir.join(".hairfit"))
        .unwrap_or_else(|e| panic!("{what}: {} has no marker: {e}", dir.display()));
    for name in marker.lines().filter_map(|l| l.strip_prefix("name: ")) {
        let path = dir.join(name);
        assert!(path.exists(), "{what}: {} is missing", path.display());
        if path.join(".hairfit").is_file() {
            assert_whole(&path, what);
        }
    }
    if marker.contains("kind: fit") {
        let text = std::fs::read_to_string(dir.join("fit.json")).unwrap();
        serde_json::from_str::<serde_json::Value>(&text)
            .unwrap_or_else(|e| panic!("{what}: {}/fit.json: {e}", dir.display()));
        assert!(dir.join("index.html").is_file(), "{what}");
    }
}

/// A moment in [0, `span`): a fixed sequence, so a failure repeats.
fn moment(i: usize, span: Duration) -> Duration {
    let mut x = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 29;
    span.mul_f64((x % 1000) as f64 / 1000.0)
}

/// Start `args`, kill it with SIGKILL after `after` (if it is still running), and reap it.
fn kill_after(args: &[&str], after: Duration) {
    let mut child = cli::hairfit_command(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while t0.elapsed() < after {
        if child.try_wait().unwrap().is_some() {
            return;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let _ = child.kill();
    child.wait().unwrap();
}

/// Run `args` to completion once (timing it), then `repeats` times killed at moments across
/// that time, checking `published` after each; then once more to completion, after which
/// nothing of the killed runs is left in `root`.
fn kill_repeatedly(root: &Path, args: &[&str], published: &[PathBuf], repeats: usize) {
    let t0 = Instant::now();
    hairfit_ok(args);
    // A little past the run's time, so some kills land while it publishes or after it ended.
    let span = t0.elapsed().mul_f64(1.2);
    for i in 0..repeats {
        kill_after(args, moment(i, span));
        for dir in published {
            assert_whole(dir, &format!("{} after kill {i}", args[0]));
        }
    }
    hairfit_ok(args);
    assert_eq!(leftovers(root), Vec::<String>::new(), "{}", args[0]);
    for dir in published {
        assert_whole(dir, &format!("{} after the next run", args[0]));
    }
}

fn all_commands(repeats: usize) {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let rgb = shipped("azimuthal_rgb.csv");
    let fit = root.join("F");
    let fit_args = ["fit", s(&rgb), "--out", s(&fit), "--no-progress"];
    kill_repeatedly(root, &fit_args, std::slice::from_ref(&fit), repeats);

    let report_args = ["report", s(&fit), "--linear"];
    kill_repeatedly(root, &report_args, std::slice::from_ref(&fit), repeats);

    let cmp = root.join("C");
    let cmp_args = [
        "compare",
        s(&rgb),
        "--out",
        s(&cmp),
        "--models",
        "karis,kajiya-kay",
    ];
    kill_repeatedly(root, &cmp_args, std::slice::from_ref(&cmp), repeats);

    std::fs::copy(&rgb, root.join("rgb.csv")).unwrap();
    let manifest = write(
        root,
        "m.csv",
        "name,data,starts,no-progress\na,rgb.csv,2,true\nb,rgb.csv,3,true\nc,rgb.csv,4,true\n",
    );
    let batch = root.join("B");
    // --force: every repeat fits again, so kills land inside fits, not only in skips.
    let batch_args = ["batch", s(&manifest), "--out", s(&batch), "--force"];
    let items: Vec<PathBuf> = ["a", "b", "c"].iter().map(|n| batch.join(n)).collect();
    kill_repeatedly(root, &batch_args, &items, repeats);
}

#[test]
fn sigkill_at_random_moments_leaves_a_whole_set_and_no_leftovers() {
    all_commands(3);
}

#[test]
#[ignore = "about two minutes: 20 kills of each command"]
fn sigkill_twenty_times_each() {
    all_commands(20);
}
