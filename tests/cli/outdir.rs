//! Output directories through the binary: a run locks its `--out` (a second run fails fast and
//! names the holder), publishes its files as one set (never mixed with another run's, nothing
//! stale left beside them), refuses directories that are not hairfit results unless `--force`,
//! and never replaces its own input.

#![cfg(unix)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use crate::support::hard::cli::shipped;
use crate::support::hard::*;

fn fit_args<'a>(data: &'a Path, out: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut a = vec!["fit", cli::s(data), "--out", out, "--no-progress"];
    a.extend(extra);
    a
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Staging directories of a run still in `parent`.
fn staging_dirs(parent: &Path) -> Vec<String> {
    names(parent)
        .into_iter()
        .filter(|n| n.contains("hairfit-stage"))
        .collect()
}

/// Channels of a published fit, read three ways: fit.json, params.json and curves.csv must
/// agree (files of two runs mixed would not).
fn channels_of_set(dir: &Path) -> usize {
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("fit.json")).unwrap()).unwrap();
    let in_fit = fit["data"]["channels"].as_array().unwrap().len();
    let params: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("params.json")).unwrap()).unwrap();
    let in_params = params["sigma_a"].as_array().map_or(1, |a| a.len());
    let mut in_curves: Vec<String> = std::fs::read_to_string(dir.join("curves.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(2).unwrap().to_string())
        .collect();
    in_curves.sort();
    in_curves.dedup();
    assert_eq!(
        (in_fit, in_params, in_curves.len()),
        (in_fit, in_fit, in_fit),
        "fit.json, params.json and curves.csv of {} come from different runs",
        dir.display()
    );
    in_fit
}

/// Wait (≤ 20 s) until a run has a staging directory in `parent`: it holds the lock.
fn wait_for_staging(parent: &Path) {
    let t0 = Instant::now();
    while staging_dirs(parent).is_empty() {
        assert!(
            t0.elapsed() < Duration::from_secs(20),
            "no run started staging"
        );
        std::thread::sleep(Duration::from_millis(1));
    }
}

#[test]
fn a_second_fit_into_a_locked_out_fails_fast_naming_the_holder() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("fit");
    let (rgb, one) = (shipped("azimuthal_rgb.csv"), shipped("sphere_1ch.csv"));
    let out_s = out.to_str().unwrap();
    // Many starts make the first run last seconds, so the second surely starts during it.
    let first = spawn_hairfit(&fit_args(&rgb, out_s, &["--starts", "400"]), &[]);
    wait_for_staging(tmp.path());
    let second = run_hairfit(&fit_args(&one, out_s, &[]), &[], Duration::from_secs(60));
    assert_eq!(second.status.code(), Some(1), "{}", second.stderr);
    assert!(
        second
            .stderr
            .contains("another hairfit run is writing there")
            && second.stderr.contains(&format!("pid {}", first.id())),
        "{}",
        second.stderr
    );
    // Fails fast: it does not wait for the first run, let alone load or fit.
    assert!(second.wall < Duration::from_secs(2), "{:?}", second.wall);
    let first = wait_with_deadline(first, Duration::from_secs(300), "first fit");
    assert!(first.status.success(), "{}", first.stderr);
    assert_eq!(channels_of_set(&out), 3, "the set is the first (RGB) run's");
    check_fit_dir(&out, "after the lock");
    assert!(staging_dirs(tmp.path()).is_empty());
}

#[test]
fn concurrent_fits_into_one_out_never_mix() {
    // The case, uncoordinated: four runs of two different data sets at once. Each either
    // publishes a whole set or fails on the lock; the final set is one run's.
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("fit");
    let out_s = out.to_str().unwrap().to_string();
    let data = [shipped("azimuthal_rgb.csv"), shipped("sphere_1ch.csv")];
    let children: Vec<_> = (0..4)
        .map(|i| spawn_hairfit(&fit_args(&data[i % 2], &out_s, &[]), &[]))
        .collect();
    let mut published = 0;
    for (i, c) in children.into_iter().enumerate() {
        let f = wait_with_deadline(c, Duration::from_secs(300), &format!("run {i}"));
        if f.status.success() {
            published += 1;
        } else {
            assert!(
                f.stderr.contains("another hairfit run is writing there"),
                "run {i} failed otherwise: {}",
                f.stderr
            );
        }
    }
    assert!(published >= 1, "no run published");
    channels_of_set(&out);
    check_fit_dir(&out, "after concurrent runs");
    assert!(staging_dirs(tmp.path()).is_empty());
}

#[test]
fn a_new_fit_removes_the_stale_figures_of_an_earlier_one() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("fit");
    let out_s = out.to_str().unwrap();
    let rgb = shipped("azimuthal_rgb.csv");
    let f = run_hairfit(&fit_args(&rgb, out_s, &[]), &[], Duration::from_secs(120));
    assert!(f.status.success(), "{}", f.stderr);
    // An azimuthal RGB fit draws curves and polar figures; a sphere fit draws neither.
    for stale in ["curves.png", "polar.png"] {
        assert!(
            out.join(stale).is_file(),
            "{stale} not drawn: test is vacuous"
        );
    }
    let one = shipped("sphere_1ch.csv");
    let f = run_hairfit(&fit_args(&one, out_s, &[]), &[], Duration::from_secs(120));
    assert!(f.status.success(), "{}", f.stderr);
    for stale in ["curves.png", "curves.svg", "polar.png", "polar.svg"] {
        assert!(
            !out.join(stale).exists(),
            "stale {stale} left: {:?}",
            names(&out)
        );
    }
    assert_eq!(channels_of_set(&out), 1);
    // Nothing beside the set: the lock went with the run.
    assert_eq!(names(tmp.path()), ["fit"]);
}

#[test]
fn the_current_directory_and_foreign_directories_are_refused_without_force() {
    let tmp = tempfile::tempdir().unwrap();
    let one = shipped("sphere_1ch.csv");
    // `--out .`: refused even with --force (the run would replace the user's working directory).
    std::fs::write(tmp.path().join("index.html"), "mine").unwrap();
    for force in [false, true] {
        let mut cmd = cli::hairfit_command(&fit_args(&one, ".", &[]));
        cmd.current_dir(tmp.path());
        if force {
            cmd.arg("--force");
        }
        let o = cli::run_within(cmd, cli::DEFAULT_LIMIT).0;
        let err = cli::stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains("current directory"), "{err}");
    }
    assert_eq!(
        std::fs::read_to_string(tmp.path().join("index.html")).unwrap(),
        "mine"
    );

    // A directory of the user's files: refused, named, untouched; --force writes the result
    // there and keeps them, but refuses to overwrite one of them.
    let mine = tmp.path().join("mine");
    std::fs::create_dir(&mine).unwrap();
    std::fs::write(mine.join("params.json"), "hand-written").unwrap();
    let mine_s = mine.to_str().unwrap();
    let f = run_hairfit(&fit_args(&one, mine_s, &[]), &[], Duration::from_secs(60));
    assert_eq!(f.status.code(), Some(1), "{}", f.stderr);
    assert!(
        f.stderr.contains("not a hairfit result") && f.stderr.contains("params.json"),
        "{}",
        f.stderr
    );
    assert!(f.stderr.contains("--force"), "{}", f.stderr);
    assert_eq!(names(&mine), ["params.json"]);
    let forced = fit_args(&one, mine_s, &["--force"]);
    let f = run_hairfit(&forced, &[], Duration::from_secs(120));
    assert_eq!(f.status.code(), Some(1), "{}", f.stderr);
    assert!(
        f.stderr.contains("not written by hairfit") && f.stderr.contains("params.json"),
        "{}",
        f.stderr
    );
    assert_eq!(names(&mine), ["params.json"]);
    std::fs::rename(mine.join("params.json"), mine.join("notes.txt")).unwrap();
    let f = run_hairfit(&forced, &[], Duration::from_secs(120));
    assert!(f.status.success(), "{}", f.stderr);
    check_fit_dir(&mine, "forced");
    assert_eq!(
        std::fs::read_to_string(mine.join("notes.txt")).unwrap(),
        "hand-written"
    );
    // Once it holds a hairfit result, later runs replace it without --force.
    let f = run_hairfit(&fit_args(&one, mine_s, &[]), &[], Duration::from_secs(120));
    assert!(f.status.success(), "{}", f.stderr);
}

#[test]
fn the_input_is_never_replaced_even_with_force() {
    // The case: the data file is named curves.csv inside the output directory.
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("work");
    std::fs::create_dir(&out).unwrap();
    let input = out.join("curves.csv");
    std::fs::copy(shipped("sphere_1ch.csv"), &input).unwrap();
    let before = std::fs::read(&input).unwrap();
    for extra in [&[][..], &["--force"][..]] {
        let f = run_hairfit(
            &fit_args(&input, out.to_str().unwrap(), extra),
            &[],
            Duration::from_secs(60),
        );
        assert_eq!(f.status.code(), Some(1), "{extra:?}: {}", f.stderr);
        assert!(std::fs::read(&input).unwrap() == before, "{extra:?}");
        if !extra.is_empty() {
            assert!(f.stderr.contains("is inside it"), "{}", f.stderr);
        }
    }
    assert_eq!(names(&out), ["curves.csv"]);
}

#[test]
fn report_redraws_its_figures_and_keeps_the_fit() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("fit");
    let out_s = out.to_str().unwrap();
    let f = run_hairfit(
        &fit_args(&shipped("azimuthal_rgb.csv"), out_s, &[]),
        &[],
        Duration::from_secs(120),
    );
    assert!(f.status.success(), "{}", f.stderr);
    let fit_json = std::fs::read(out.join("fit.json")).unwrap();
    // A figure an earlier hairfit drew (its marker lists it), and the user's notes folder.
    std::fs::write(out.join("stale.png"), "an old figure").unwrap();
    let marker = std::fs::read_to_string(out.join(".hairfit")).unwrap();
    std::fs::write(out.join(".hairfit"), marker + "name: stale.png\n").unwrap();
    std::fs::create_dir(out.join("notes")).unwrap();
    std::fs::write(out.join("notes/lab.txt"), "mine").unwrap();
    let f = run_hairfit(
        &["report", out_s, "--linear"],
        &[],
        Duration::from_secs(120),
    );
    assert!(f.status.success(), "{}", f.stderr);
    assert!(!out.join("stale.png").exists());
    assert_eq!(
        std::fs::read_to_string(out.join("notes/lab.txt")).unwrap(),
        "mine",
        "report dropped the user's folder"
    );
    assert!(out.join("index.html").is_file() && out.join("polar.png").is_file());
    assert_eq!(std::fs::read(out.join("fit.json")).unwrap(), fit_json);
    check_fit_dir(&out, "after report");
    // A mistyped directory is "no such file", and leaves no lock file behind.
    let f = run_hairfit(
        &["report", tmp.path().join("fti").to_str().unwrap()],
        &[],
        Duration::from_secs(60),
    );
    assert_eq!(f.status.code(), Some(1));
    assert!(f.stderr.contains("No such file"), "{}", f.stderr);
    assert!(!tmp.path().join(".fti.hairfit-lock").exists());
}

#[test]
fn a_second_sigint_removes_the_staging_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("fit");
    let rgb = shipped("azimuthal_rgb.csv");
    let child = spawn_hairfit(
        &fit_args(
            &rgb,
            out.to_str().unwrap(),
            &["--starts", "2000", "--polish-iters", "3000"],
        ),
        &[],
    );
    wait_for_staging(tmp.path());
    std::thread::sleep(Duration::from_millis(300));
    let kill = |sig: &str| {
        let ok = Command::new("kill")
            .args([sig, &child.id().to_string()])
            .status()
            .unwrap()
            .success();
        assert!(ok, "kill {sig}");
    };
    kill("-INT");
    // Two SIGINTs sent while the process is not scheduled merge into one, so the second is
    // repeated until the process is gone (its best-so-far write takes ~200 ms; every further
    // SIGINT is a "second" one).
    let stat = format!("/proc/{}/stat", child.id());
    for _ in 0..100 {
        std::thread::sleep(Duration::from_millis(20));
        let running = std::fs::read_to_string(&stat).is_ok_and(|s| {
            s.rsplit(')')
                .next()
                .is_some_and(|r| !r.trim_start().starts_with('Z'))
        });
        if !running {
            break;
        }
        kill("-INT");
    }
    let f = wait_with_deadline(child, Duration::from_secs(60), "twice interrupted fit");
    assert_eq!(f.status.code(), Some(130), "{:?} {}", f.status, f.stderr);
    assert!(
        staging_dirs(tmp.path()).is_empty(),
        "staging left: {:?}",
        names(tmp.path())
    );
    assert!(!out.exists(), "nothing was published");
}

/// Where `fit`'s batch items go: each item directory is its own locked set.
#[test]
fn batch_items_are_published_as_sets() {
    let tmp = tempfile::tempdir().unwrap();
    let manifest = tmp.path().join("m.csv");
    std::fs::write(
        &manifest,
        format!(
            "name,data\nrgb,{}\none,{}\n",
            shipped("azimuthal_rgb.csv").display(),
            shipped("sphere_1ch.csv").display()
        ),
    )
    .unwrap();
    let out = tmp.path().join("runs");
    // The batch's own directory (a folder of the user's files is refused whole)...
    let first = tmp.path().join("first.csv");
    std::fs::write(
        &first,
        format!(
            "name,data\nrgb,{}\n",
            shipped("azimuthal_rgb.csv").display()
        ),
    )
    .unwrap();
    let f = run_hairfit(
        &[
            "batch",
            first.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        &[],
        Duration::from_secs(300),
    );
    assert_eq!(f.status.code(), Some(0), "{}", f.stderr);
    // ...where a foreign item directory is refused (the others still run), as `fit` would.
    std::fs::create_dir_all(out.join("one")).unwrap();
    std::fs::write(out.join("one/notes.txt"), "mine").unwrap();
    let f = run_hairfit(
        &[
            "batch",
            manifest.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        &[],
        Duration::from_secs(300),
    );
    assert_eq!(f.status.code(), Some(1), "{}", f.stderr);
    assert!(f.stderr.contains("not a hairfit result"), "{}", f.stderr);
    assert_eq!(channels_of_set(&out.join("rgb")), 3);
    assert!(out.join("rgb/index.html").is_file());
    assert_eq!(names(&out.join("one")), ["notes.txt"]);
    let leftovers: Vec<PathBuf> = staging_dirs(&out).into_iter().map(PathBuf::from).collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// `demo --out /proc/nope` named the lock file beside it ("/proc/.nope.hairfit-lock: No such
/// file or directory"), which the user never asked for. An --out that cannot be written names
/// --out, what could not be created and what to do; nothing is left behind.
#[cfg(target_os = "linux")]
#[test]
fn an_unwritable_out_names_out_and_what_to_do() {
    let data = shipped("sphere_1ch.csv");
    for args in [
        vec!["demo", "--out", "/proc/nope", "--no-progress"],
        fit_args(&data, "/proc/nope", &[]),
        fit_args(&data, "/proc/hairfit-nope/deeper", &[]),
    ] {
        let f = run_hairfit(&args, &[], Duration::from_secs(60));
        assert_eq!(f.status.code(), Some(1), "{args:?}: {}", f.stderr);
        let out = args[args.iter().position(|a| *a == "--out").unwrap() + 1];
        assert!(
            f.stderr
                .starts_with(&format!("hairfit: error: --out {out}: cannot write there"))
                && f.stderr.contains("could not be created")
                && f.stderr
                    .contains("choose an --out in a directory you can write to"),
            "{args:?}: {}",
            f.stderr
        );
    }
}

/// `--out latest` where `latest` links to a run's directory: the set is published into the
/// directory the link names and the link stays (the swap used to replace the link itself with
/// the new set, leaving the linked directory as it was), for a fit and for a report redrawn
/// through the link.
#[test]
fn an_out_that_is_a_link_publishes_into_the_linked_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let real = tmp.path().join("run-1");
    std::fs::create_dir(&real).unwrap();
    let link = tmp.path().join("latest");
    std::os::unix::fs::symlink("run-1", &link).unwrap();
    let link_s = link.to_str().unwrap();
    let f = run_hairfit(
        &fit_args(&shipped("azimuthal_rgb.csv"), link_s, &[]),
        &[],
        Duration::from_secs(120),
    );
    assert!(f.status.success(), "{}", f.stderr);
    let is_link = |p: &Path| {
        std::fs::symlink_metadata(p)
            .unwrap()
            .file_type()
            .is_symlink()
    };
    assert!(is_link(&link), "the link was replaced");
    check_fit_dir(&real, "fit through a link");
    let f = run_hairfit(
        &["report", link_s, "--linear"],
        &[],
        Duration::from_secs(120),
    );
    assert!(f.status.success(), "{}", f.stderr);
    assert!(is_link(&link), "report replaced the link");
    check_fit_dir(&real, "report through a link");
    assert_eq!(names(tmp.path()), ["latest", "run-1"]);
}
