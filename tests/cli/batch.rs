//! `hairfit batch` through the binary: shards run concurrently give, after `--merge`, exactly
//! the per-item results of one process running the whole manifest and of `hairfit fit` itself;
//! finished items are skipped on a re-run; bad manifests and missing items say so and exit 1.

use crate::support::cli;

use cli::shipped;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The binary on one rayon thread (shards run side by side).
fn bin(args: &[&str]) -> Command {
    let mut c = cli::hairfit_command(args);
    c.env("RAYON_NUM_THREADS", "1");
    c
}

fn run(args: &[&str]) -> Output {
    cli::run_within(bin(args), cli::DEFAULT_LIMIT).0
}

fn ok(args: &[&str]) -> Output {
    cli::succeeded(run(args), args)
}

/// A manifest of three quick fits: one data file beside the manifest (relative path), two
/// shipped ones (absolute), with per-item options.
fn manifest(dir: &Path) -> PathBuf {
    std::fs::copy(shipped("sphere_1ch.csv"), dir.join("sphere.csv")).unwrap();
    let text = format!(
        "name,data,loss,starts,fix,no-progress\n\
         sphere,sphere.csv,cauchy,4,,true\n\
         rgb,{},,4,eta=1.55;eccentricity=0.9,true\n\
         long,{},,3,,true\n",
        shipped("azimuthal_rgb.csv").display(),
        shipped("longitudinal_rgb.csv").display()
    );
    let path = dir.join("items.csv");
    std::fs::write(&path, text).unwrap();
    path
}

fn same_item(a: &Path, b: &Path) {
    // Wall-clock times live in timing.json; everything else must match to the byte.
    for f in ["fit.json", "params.json", "curves.csv"] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f}: {} vs {}",
            a.display(),
            b.display()
        );
    }
}

#[test]
fn concurrent_shards_equal_one_process_and_the_fit_command() {
    let tmp = tempfile::tempdir().unwrap();
    let m = manifest(tmp.path());
    let m = m.to_str().unwrap();
    let (sharded, whole) = (tmp.path().join("sharded"), tmp.path().join("whole"));
    let (sharded_s, whole_s) = (sharded.to_str().unwrap(), whole.to_str().unwrap());

    // Two shards at the same time, as a scheduler would start them.
    let children: Vec<_> = ["0/2", "1/2"]
        .iter()
        .map(|k| {
            bin(&["batch", m, "--out", sharded_s, "--shard", k])
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for c in children {
        let out = c.wait_with_output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    ok(&["batch", m, "--out", whole_s]);
    for name in ["sphere", "rgb", "long"] {
        same_item(&sharded.join(name), &whole.join(name));
    }

    // An item is what `hairfit fit` writes with the same options.
    let direct = tmp.path().join("direct");
    let data = tmp.path().join("sphere.csv");
    ok(&[
        "fit",
        data.to_str().unwrap(),
        "--loss",
        "cauchy",
        "--starts",
        "4",
        "--no-progress",
        "--out",
        direct.to_str().unwrap(),
    ]);
    same_item(&direct, &whole.join("sphere"));

    // Both merges give the same table, one row per item in manifest order.
    ok(&["batch", m, "--out", sharded_s, "--merge"]);
    ok(&["batch", m, "--out", whole_s, "--merge"]);
    let a = std::fs::read_to_string(sharded.join("summary.csv")).unwrap();
    let b = std::fs::read_to_string(whole.join("summary.csv")).unwrap();
    assert_eq!(a, b);
    let names: Vec<&str> = a
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(names, ["sphere", "rgb", "long"]);
    assert!(a
        .lines()
        .next()
        .unwrap()
        .starts_with("name,data,model,status,"));
    let html = std::fs::read_to_string(whole.join("index.html")).unwrap();
    for name in ["sphere", "rgb", "long"] {
        assert!(
            html.contains(&format!("href=\"{name}/index.html\"")),
            "{name}"
        );
        assert!(
            whole.join(name).join("index.html").exists(),
            "{name} report"
        );
    }
}

#[test]
fn finished_items_are_skipped_and_changed_items_rerun() {
    let tmp = tempfile::tempdir().unwrap();
    let m = manifest(tmp.path());
    let out = tmp.path().join("out");
    let (m_s, out_s) = (m.to_str().unwrap(), out.to_str().unwrap());
    ok(&["batch", m_s, "--out", out_s, "--shard", "0/3"]);
    let fit_json = out.join("sphere").join("fit.json");
    let before = std::fs::metadata(&fit_json).unwrap().modified().unwrap();
    let again = ok(&["batch", m_s, "--out", out_s, "--shard", "0/3"]);
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(err.contains("sphere: skipped"), "{err}");
    assert_eq!(
        std::fs::metadata(&fit_json).unwrap().modified().unwrap(),
        before
    );

    // Changing the item's options makes it run again.
    let text = std::fs::read_to_string(&m)
        .unwrap()
        .replace("sphere,sphere.csv,cauchy,4", "sphere,sphere.csv,huber,4");
    std::fs::write(&m, text).unwrap();
    let rerun = ok(&["batch", m_s, "--out", out_s, "--shard", "0/3"]);
    let err = String::from_utf8_lossy(&rerun.stderr);
    assert!(!err.contains("sphere: skipped"), "{err}");

    // Merging before the other shards ran names the missing items and exits 1.
    let merged = run(&["batch", m_s, "--out", out_s, "--merge"]);
    assert_eq!(merged.status.code(), Some(1));
    let err = String::from_utf8_lossy(&merged.stderr);
    assert!(
        err.contains("2 of 3 items") && err.contains("rgb") && err.contains("long"),
        "{err}"
    );
    let table = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    assert!(
        table.contains("rgb,") && table.contains(",missing,"),
        "{table}"
    );
}

#[test]
fn bad_manifests_and_items_say_where_and_exit_1() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let out_s = out.to_str().unwrap();
    let bad = tmp.path().join("bad.csv");
    std::fs::write(&bad, "name,data,los\na,a.csv,cauchy\n").unwrap();
    let r = run(&["batch", bad.to_str().unwrap(), "--out", out_s]);
    assert_eq!(r.status.code(), Some(1));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("bad.csv:1:3") && err.contains("`los`"),
        "{err}"
    );

    // A missing data file fails that item only; the other item is fitted.
    std::fs::copy(shipped("sphere_1ch.csv"), tmp.path().join("s.csv")).unwrap();
    let m = tmp.path().join("m.csv");
    std::fs::write(&m, "name,data,starts\ngone,nothere.csv,2\nok,s.csv,2\n").unwrap();
    let r = run(&["batch", m.to_str().unwrap(), "--out", out_s]);
    assert_eq!(r.status.code(), Some(1));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("gone: FAILED") && err.contains("1 items failed"),
        "{err}"
    );
    assert!(out.join("ok").join("fit.json").exists());

    let r = run(&[
        "batch",
        m.to_str().unwrap(),
        "--out",
        out_s,
        "--shard",
        "2/2",
    ]);
    assert_eq!(r.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&r.stderr).contains("0-based"));
}
