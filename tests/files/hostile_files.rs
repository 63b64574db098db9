//! Issue 38's hostile cases, run as a user runs them (the binary): a directory is hairfit's only
//! by its marker, the user's files in it survive every run, a batch or compare directory is never
//! replaced by one fit, exports never go into a result nor publish half a pair, a full disk
//! leaves the previous set whole, nothing of a killed run lingers after the next, a FIFO never
//! blocks a read, and the parameter-file messages say what to type.

#![cfg(unix)]

use crate::support::cli;

use std::path::Path;
use std::process::Command;

use cli::{hairfit, hairfit_ok, s, shipped, snapshot, stderr, write};

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn fit(data: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["fit", s(data), "--out", s(out), "--no-progress"];
    args.extend(extra);
    hairfit(&args)
}

fn fit_ok(data: &Path, out: &Path) {
    let o = fit(data, out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
}

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

/// The issue's first case: a hand-made directory holding a `cost.json` that mentions
/// `"hairfit_version"` (or a copied fit.json) was replaced whole, the user's thesis with it.
#[test]
fn a_directory_that_only_looks_like_a_result_is_refused_and_force_keeps_its_files() {
    let tmp = tempfile::tempdir().unwrap();
    let one = shipped("sphere_1ch.csv");
    for lookalike in ["cost.json", "fit.json"] {
        let dir = tmp.path().join(lookalike);
        std::fs::create_dir(&dir).unwrap();
        write(&dir, lookalike, "\"hairfit_version\"");
        write(&dir, "thesis.tex", "x");
        std::fs::create_dir(dir.join("chapters")).unwrap();
        write(&dir.join("chapters"), "one.tex", "y");
        let before = snapshot(&dir);
        let o = fit(&one, &dir, &[]);
        cli::assert_fails_with(&o, &["not a hairfit result", "thesis.tex", "--force"]);
        assert_eq!(snapshot(&dir), before, "{lookalike}: refused, untouched");
        // --force writes the result there and keeps what hairfit did not write; a name the
        // result also writes (fit.json) is refused rather than overwritten.
        let o = fit(&one, &dir, &["--force"]);
        if lookalike == "fit.json" {
            cli::assert_fails_with(&o, &["not written by hairfit", "fit.json"]);
            assert_eq!(snapshot(&dir), before);
            continue;
        }
        assert!(o.status.success(), "{}", stderr(&o));
        for (name, bytes) in &before {
            assert_eq!(&std::fs::read(dir.join(name)).unwrap(), bytes, "{name}");
        }
        assert!(dir.join("index.html").is_file() && dir.join(".hairfit").is_file());
    }
}

/// A batch directory given as --out to fit, compare or demo was replaced by one fit: every
/// item, summary.csv and .batch/ gone. Refused, even with --force; and the reverse.
#[test]
fn a_batch_or_compare_directory_is_never_replaced_by_another_command() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::copy(shipped("sphere_1ch.csv"), dir.join("sphere.csv")).unwrap();
    write(
        dir,
        "m.csv",
        "name,data,starts,no-progress\nfib,sphere.csv,2,true\n",
    );
    let batch = dir.join("b");
    hairfit_ok(&["batch", s(&dir.join("m.csv")), "--out", s(&batch)]);
    hairfit_ok(&[
        "batch",
        s(&dir.join("m.csv")),
        "--out",
        s(&batch),
        "--merge",
    ]);
    let before = snapshot(&batch);
    let data = dir.join("sphere.csv");
    for force in [&[][..], &["--force"][..]] {
        let o = fit(&data, &batch, force);
        cli::assert_fails_with(&o, &["batch directory", "Choose another --out"]);
        let mut demo = vec!["demo", "--out", s(&batch), "--no-progress"];
        demo.extend(force);
        cli::assert_fails_with(&hairfit(&demo), &["batch directory"]);
        let mut cmp = vec!["compare", s(&data), "--out", s(&batch)];
        cmp.extend(force);
        cli::assert_fails_with(&hairfit(&cmp), &["batch directory"]);
    }
    assert_eq!(snapshot(&batch), before);
    // A fit's directory is no batch's --out either.
    let single = dir.join("single");
    fit_ok(&data, &single);
    let before = snapshot(&single);
    let o = hairfit(&["batch", s(&dir.join("m.csv")), "--out", s(&single)]);
    cli::assert_fails_with(&o, &["a fit's directory", "Choose another --out"]);
    assert_eq!(snapshot(&single), before);
}

/// An export inside a fit's directory was deleted by the next fit there, and `--output
/// F/.hairfit` overwrote the fit's own marker: an --output inside a result is refused.
#[test]
fn an_export_into_a_fit_directory_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let f = tmp.path().join("F");
    fit_ok(&shipped("sphere_1ch.csv"), &f);
    let before = snapshot(&f);
    for (to, name) in [
        ("pbrt", "hair.pbrt"),
        ("pbrt", ".hairfit"),
        ("unreal", "timing.json"),
        ("unity", "index.json"),
        ("pbrt", "sub/hair.pbrt"),
    ] {
        let out = f.join(name);
        let o = hairfit(&["export", s(&f), "--to", to, "--output", s(&out)]);
        cli::assert_fails_with(&o, &["--output", "inside", "write the export outside it"]);
        assert_eq!(snapshot(&f), before, "{to} {name}");
    }
}

/// Unreal's .json + .py and Unity's .json + .cs: when the second file cannot be written the
/// first was already replaced (a pair from two fits). Now both are replaced or neither.
#[test]
fn a_two_file_export_replaces_both_files_or_neither() {
    let tmp = tempfile::tempdir().unwrap();
    let a = tmp.path().join("a");
    let b = tmp.path().join("b");
    // Two Karis fits with different roughness: their exports differ.
    for (dir, fix) in [(&a, "roughness=0.3"), (&b, "roughness=0.6")] {
        let o = hairfit(&[
            "demo",
            "--model",
            "karis",
            "--fix",
            fix,
            "--out",
            s(dir),
            "--no-progress",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    for (to, second) in [("unreal", "py"), ("unity", "cs")] {
        let out = tmp.path().join(format!("{to}.json"));
        let script = out.with_extension(second);
        hairfit_ok(&["export", s(&a), "--to", to, "--output", s(&out)]);
        let json_a = std::fs::read(&out).unwrap();
        // The script's place taken by a directory: it cannot be replaced.
        std::fs::remove_file(&script).unwrap();
        std::fs::create_dir(&script).unwrap();
        let o = hairfit(&["export", s(&b), "--to", to, "--output", s(&out)]);
        assert_eq!(o.status.code(), Some(1), "{to}: {}", stderr(&o));
        assert_eq!(
            std::fs::read(&out).unwrap(),
            json_a,
            "{to}: the JSON was replaced"
        );
        assert!(
            names(tmp.path()).iter().all(|n| !n.ends_with(".tmp")),
            "{to}: {:?}",
            names(tmp.path())
        );
    }
}

/// A FIFO in place of a fit's params.json made `export` wait forever; a parameter or data file
/// that is a FIFO is refused at once.
#[test]
fn a_fifo_where_a_file_is_read_is_refused_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let f = tmp.path().join("F");
    fit_ok(&shipped("sphere_1ch.csv"), &f);
    let copy = tmp.path().join("copy");
    std::fs::create_dir(&copy).unwrap();
    for name in ["fit.json", "curves.csv"] {
        std::fs::copy(f.join(name), copy.join(name)).unwrap();
    }
    let fifo = copy.join("params.json");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let (o, took) = cli::hairfit_within(
        std::time::Duration::from_secs(20),
        &["export", s(&copy), "--to", "pbrt"],
    );
    cli::assert_fails_with(&o, &["params.json", "not a regular file"]);
    assert!(took.as_secs() < 10, "{took:?}");
    let angles = write(
        tmp.path(),
        "a.csv",
        "theta_i,phi_i,theta_r,phi_r\n20,0,-15,30\n",
    );
    let (o, _) = cli::hairfit_within(
        std::time::Duration::from_secs(20),
        &["eval", "--params", s(&fifo), "--input", s(&angles)],
    );
    cli::assert_fails_with(&o, &["params.json", "not a regular file"]);
}

/// The issue's parameter-file messages: karis's documented lower roughness is accepted,
/// `"model": "KARIS"` is read as karis (`--model` takes any case), and a UTF-8 byte-order mark
/// is read past, as in data files.
#[test]
fn parameter_files_read_as_the_docs_say() {
    let tmp = tempfile::tempdir().unwrap();
    let angles = write(
        tmp.path(),
        "a.csv",
        "theta_i,phi_i,theta_r,phi_r\n20,0,-15,30\n",
    );
    let eval = |name: &str, text: &str| {
        let params = write(tmp.path(), name, text);
        hairfit(&[
            "eval",
            "--model",
            "karis",
            "--params",
            s(&params),
            "--input",
            s(&angles),
        ])
    };
    let low = r#"{"model": "karis", "base_color": 0.4, "roughness": 0.00392, "specular": 0.5, "scatter": 0}"#;
    let o = eval("low.json", low);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = eval("upper.json", &low.replace("\"karis\"", "\"KARIS\""));
    assert!(o.status.success(), "{}", stderr(&o));
    let o = eval("bom.json", &format!("\u{feff}{low}"));
    assert!(o.status.success(), "{}", stderr(&o));
    // Another family in any case names that family's --model spelling.
    let o = eval("other.json", &low.replace("\"karis\"", "\"CHIANG\""));
    cli::assert_fails_with(&o, &["pass --model chiang"]);
}

/// A fit into a small tmpfs over a finished result: whatever the size (the report, a fit file
/// or the marker failing), the run either publishes a whole new set or exits 1 naming --out
/// and leaves the previous set byte for byte. Needs root to mount; skipped otherwise.
#[test]
fn a_full_disk_leaves_the_previous_set_whole() {
    let tmp = tempfile::tempdir().unwrap();
    let mnt = tmp.path().join("disk");
    std::fs::create_dir(&mnt).unwrap();
    let mount = |size_kib: u64| {
        Command::new("mount")
            .args([
                "-t",
                "tmpfs",
                "-o",
                &format!("size={size_kib}k"),
                "tmpfs",
                s(&mnt),
            ])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    let umount = || {
        let _ = Command::new("umount").arg(&mnt).status();
    };
    if !mount(4096) {
        eprintln!("skipped: cannot mount a tmpfs here (needs root)");
        return;
    }
    let out = mnt.join("F");
    // The set this test makes: its size bounds the sweep.
    fit_ok(&shipped("sphere_1ch.csv"), &out);
    let set_kib = snapshot(&out)
        .iter()
        .map(|(_, b)| b.len() as u64)
        .sum::<u64>()
        / 1024;
    umount();
    let mut failures = 0;
    // From room for the first set only, to room for both: every point of the second run fails
    // somewhere in this range (tmpfs counts whole pages, so steps of 64 KiB hit different files).
    let mut size = set_kib + 64;
    while size < 2 * set_kib + 512 {
        assert!(mount(size), "mount {size}k");
        fit_ok(&shipped("sphere_1ch.csv"), &out);
        let before = snapshot(&out);
        let o = fit(&shipped("azimuthal_rgb.csv"), &out, &[]);
        if o.status.success() {
            assert!(out.join("index.html").is_file(), "{size}k");
        } else {
            failures += 1;
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(1), "{size}k: {err}");
            assert!(
                err.contains(&format!("--out {}", s(&out))),
                "{size}k: {err}"
            );
            assert!(!err.contains("hairfit-stage"), "{size}k: {err}");
            assert!(
                snapshot(&out) == before,
                "{size}k: the previous set changed"
            );
        }
        assert_eq!(leftovers(&mnt), Vec::<String>::new(), "{size}k");
        umount();
        size += 64;
    }
    assert!(failures > 0, "no size made the second run fail");
}

/// What SIGKILLed runs leave beside --out (staging directories, lock files of dead pids) is
/// removed by the next run, and a finished or failed run leaves no lock.
#[test]
fn the_next_run_removes_what_killed_runs_left() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("F");
    let stage = tmp.path().join(".F.hairfit-stage-Ab12Cd");
    std::fs::create_dir(&stage).unwrap();
    write(&stage, "curves.csv", "half");
    write(tmp.path(), ".F.hairfit-lock", "pid 999999, hairfit fit");
    fit_ok(&shipped("sphere_1ch.csv"), &out);
    assert_eq!(names(tmp.path()), ["F"]);
    // A failed run leaves nothing either.
    let o = fit(&tmp.path().join("missing.csv"), &out, &[]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(names(tmp.path()), ["F"]);
}

/// Under a memory cap (`prlimit --as`) on 100,000 samples, fit, eval and compare aborted with
/// exit 134 and a backtrace, leaving a staging directory. Every cap from "cannot start" to
/// "enough" now ends with 0 or 1, an error that says to raise the limit, and nothing left.
#[test]
fn a_memory_cap_is_an_error_never_an_abort() {
    if Command::new("prlimit").arg("--version").output().is_err() {
        eprintln!("skipped: no prlimit");
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("big.csv");
    hairfit_ok(&[
        "synth",
        "--params",
        s(&shipped("example_params.json")),
        "--rig",
        "sphere:n=100000",
        "--output",
        s(&data),
    ]);
    let params = shipped("example_params.json");
    let (ev, fo, co) = (
        tmp.path().join("ev.csv"),
        tmp.path().join("F"),
        tmp.path().join("C"),
    );
    let commands: [(&str, Vec<&str>); 3] = [
        (
            "eval",
            vec![
                "eval",
                "--params",
                s(&params),
                "--input",
                s(&data),
                "--output",
                s(&ev),
            ],
        ),
        (
            "fit",
            vec!["fit", s(&data), "--out", s(&fo), "--no-progress"],
        ),
        (
            "compare",
            vec![
                "compare",
                s(&data),
                "--out",
                s(&co),
                "--models",
                "karis,kajiya-kay",
            ],
        ),
    ];
    // From a cap the binary barely starts under (below ~20 MB it cannot load at all) to one
    // every command fits in.
    for mb in [25, 40, 60, 100, 150, 250, 400] {
        for (what, args) in &commands {
            let mut cmd = Command::new("prlimit");
            cmd.arg(format!("--as={}", mb * 1_000_000))
                .arg(env!("CARGO_BIN_EXE_hairfit"))
                .args(args);
            let (o, _) = cli::run_within(cmd, cli::DEFAULT_LIMIT);
            let err = stderr(&o);
            match o.status.code() {
                Some(0) => {}
                Some(1) => assert!(
                    err.contains("out of memory") || err.contains("cannot start a worker thread"),
                    "{what} under {mb} MB: {err}"
                ),
                other => panic!("{what} under {mb} MB: exit {other:?}: {err}"),
            }
            assert!(
                !err.contains("panicked") && !err.contains("backtrace"),
                "{what}: {err}"
            );
            assert_eq!(
                leftovers(tmp.path()),
                Vec::<String>::new(),
                "{what} under {mb} MB"
            );
        }
    }
}
