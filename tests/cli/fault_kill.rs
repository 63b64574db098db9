//! SIGKILL at random moments of fit, compare, batch and report: the published directory is
//! always a whole set (the old one or the new one: every name its marker lists is there and
//! its fit.json reads), and after the next run no staging directory or lock is left beside it
//! or inside it. Each command is killed 20 times (`cargo test --release --test cli fault_kill::
//! -- --nocapture` prints how many kills landed while the command ran).

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
/// each listed marked sub-directory is whole too, and a fit's fit.json parses, holds the
/// parameters its params.json holds (one run wrote both) and sits beside its page.
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
        let read = |name: &str| -> serde_json::Value {
            let text = std::fs::read_to_string(dir.join(name)).unwrap();
            serde_json::from_str(&text)
                .unwrap_or_else(|e| panic!("{what}: {}/{name}: {e}", dir.display()))
        };
        assert_eq!(
            read("fit.json")["params"],
            read("params.json"),
            "{what}: {} mixes two runs",
            dir.display()
        );
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
/// True when the kill landed (the command had not ended).
fn kill_after(args: &[&str], after: Duration) -> bool {
    let mut child = cli::hairfit_command(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while t0.elapsed() < after {
        if child.try_wait().unwrap().is_some() {
            return false;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let landed = child.kill().is_ok();
    let status = child.wait().unwrap();
    // A command that ended just before the kill exits normally.
    landed && status.code().is_none()
}

/// Run `args` to completion once (timing it), then `repeats` times killed at moments across
/// that time, checking `published` after each; then once more to completion, after which
/// nothing of the killed runs is left in `root`. Returns how many kills landed mid-run.
fn kill_repeatedly(root: &Path, args: &[&str], published: &[PathBuf], repeats: usize) -> usize {
    let t0 = Instant::now();
    hairfit_ok(args);
    // A little past the run's time, so some kills land while it publishes or after it ended.
    let span = t0.elapsed().mul_f64(1.2);
    let mut landed = 0;
    for i in 0..repeats {
        landed += usize::from(kill_after(args, moment(i, span)));
        for dir in published {
            assert_whole(dir, &format!("{} after kill {i}", args[0]));
        }
    }
    hairfit_ok(args);
    assert_eq!(leftovers(root), Vec::<String>::new(), "{}", args[0]);
    for dir in published {
        assert_whole(dir, &format!("{} after the next run", args[0]));
    }
    eprintln!(
        "{}: {repeats} kills over {span:?}, {landed} while it ran; every set whole, nothing left",
        args[0]
    );
    landed
}

fn all_commands(repeats: usize) {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let rgb = shipped("azimuthal_rgb.csv");
    let fit = root.join("F");
    let fit_args = ["fit", s(&rgb), "--out", s(&fit), "--no-progress"];
    let mut landed = kill_repeatedly(root, &fit_args, std::slice::from_ref(&fit), repeats);

    let report_args = ["report", s(&fit), "--linear"];
    landed += kill_repeatedly(root, &report_args, std::slice::from_ref(&fit), repeats);

    let cmp = root.join("C");
    let cmp_args = [
        "compare",
        s(&rgb),
        "--out",
        s(&cmp),
        "--models",
        "karis,kajiya-kay",
    ];
    landed += kill_repeatedly(root, &cmp_args, std::slice::from_ref(&cmp), repeats);

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
    landed += kill_repeatedly(root, &batch_args, &items, repeats);
    // The moments spread over 1.2 times each run: most kills must land inside it, or the
    // suite would test finished runs only.
    assert!(
        landed * 2 > 4 * repeats,
        "only {landed} of {} kills landed",
        4 * repeats
    );
}

/// 20 kills of each command: about 9 s on the 2-core machine (each run is a fraction of a
/// second), so the suite runs the full count by default.
#[test]
fn sigkill_at_random_moments_leaves_a_whole_set_and_no_leftovers() {
    all_commands(20);
}
