//! `hairfit batch` through the binary, the rules a newcomer tripped over: its --out follows
//! `hairfit fit`'s rules and merge never replaces a user's file; --strict; failed items exit 1,
//! run again and show their error in the merge; a changed data file runs again, another current
//! directory does not; the manifest is checked whole, with line and column, before anything runs.

use crate::support::cli;

use cli::{shipped, write};
use std::path::Path;
use std::process::Output;

/// The binary on one rayon thread, in `cwd`.
fn run_in(cwd: &Path, args: &[&str]) -> Output {
    let mut c = cli::hairfit_command(args);
    c.env("RAYON_NUM_THREADS", "1").current_dir(cwd);
    cli::run_within(c, cli::DEFAULT_LIMIT).0
}

fn code(out: &Output) -> Option<i32> {
    out.status.code()
}

/// A one-item manifest of a quick fit, data beside it.
fn quick_manifest(dir: &Path) -> std::path::PathBuf {
    std::fs::copy(shipped("sphere_1ch.csv"), dir.join("sphere.csv")).unwrap();
    write(
        dir,
        "m.csv",
        "name,data,starts,no-progress\nfib,sphere.csv,2,true\n",
    )
}

/// `data/sphere_1ch.csv` with every radiance 0: a log-space fit is impossible (an error before
/// any result), a linear one ends with the verdict `failed`.
fn zero_data(dir: &Path) {
    let text = std::fs::read_to_string(shipped("sphere_1ch.csv")).unwrap();
    let mut out = String::new();
    let mut header: Option<Vec<String>> = None;
    for line in text.lines() {
        if line.starts_with('#') {
            out += line;
        } else if header.is_none() {
            header = Some(line.split(',').map(str::to_string).collect());
            out += line;
        } else {
            let col = header
                .as_ref()
                .unwrap()
                .iter()
                .position(|h| h == "radiance")
                .unwrap();
            let mut cells: Vec<&str> = line.split(',').collect();
            cells[col] = "0";
            out += &cells.join(",");
        }
        out += "\n";
    }
    write(dir, "zero.csv", out);
}

#[test]
fn out_dot_files_and_user_folders_are_refused_and_merge_keeps_user_files() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    quick_manifest(dir);
    write(dir, "index.html", "<p>home</p>");
    for args in [
        &["batch", "m.csv", "--out", "."][..],
        &["batch", "m.csv", "--out", ".", "--merge"],
    ] {
        let r = run_in(dir, args);
        cli::assert_fails_with(&r, &["--out .", "current directory"]);
    }
    assert_eq!(
        std::fs::read_to_string(dir.join("index.html")).unwrap(),
        "<p>home</p>"
    );

    // A folder of the user's own files, for a run and for a merge.
    std::fs::create_dir(dir.join("userdir")).unwrap();
    write(&dir.join("userdir"), "summary.csv", "mine");
    for args in [
        &["batch", "m.csv", "--out", "userdir"][..],
        &["batch", "m.csv", "--out", "userdir", "--merge"],
    ] {
        let r = run_in(dir, args);
        cli::assert_fails_with(&r, &["--out userdir", "summary.csv", "did not write"]);
    }
    assert_eq!(
        std::fs::read_to_string(dir.join("userdir/summary.csv")).unwrap(),
        "mine"
    );

    // A regular file as --out: refused up front, naming --out.
    write(dir, "afile", "x");
    let r = run_in(dir, &["batch", "m.csv", "--out", "afile"]);
    cli::assert_fails_with(&r, &["--out afile", "is a file"]);

    // A batch's own directory: a page the user put there later is not replaced by merge.
    cli::succeeded(run_in(dir, &["batch", "m.csv", "--out", "b"]), &["batch"]);
    write(&dir.join("b"), "index.html", "<p>my notes</p>");
    let r = run_in(dir, &["batch", "m.csv", "--out", "b", "--merge"]);
    cli::assert_fails_with(&r, &["index.html", "not written by"]);
    assert_eq!(
        std::fs::read_to_string(dir.join("b/index.html")).unwrap(),
        "<p>my notes</p>"
    );
    // Its own files it replaces, again and again.
    std::fs::remove_file(dir.join("b/index.html")).unwrap();
    for _ in 0..2 {
        cli::succeeded(
            run_in(dir, &["batch", "m.csv", "--out", "b", "--merge"]),
            &["merge"],
        );
    }
}

#[test]
fn strict_exits_3_for_runs_reruns_and_merges_and_is_not_a_column() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // The shipped RGB scan leaves a parameter undetermined (its verdict, not an error).
    std::fs::copy(shipped("azimuthal_rgb.csv"), dir.join("rgb.csv")).unwrap();
    write(dir, "m.csv", "name,data,no-progress\nrgb,rgb.csv,true\n");
    let first = run_in(dir, &["batch", "m.csv", "--out", "o", "--strict"]);
    assert_eq!(code(&first), Some(3), "{}", cli::stderr(&first));
    assert!(cli::stderr(&first).contains("undetermined"));
    let again = run_in(dir, &["batch", "m.csv", "--out", "o", "--strict"]);
    assert!(cli::stderr(&again).contains("rgb: skipped"));
    assert_eq!(code(&again), Some(3), "a skipped item keeps its verdict");
    let r = run_in(
        dir,
        &["batch", "m.csv", "--out", "o", "--merge", "--strict"],
    );
    assert_eq!(code(&r), Some(3), "{}", cli::stderr(&r));
    assert!(cli::stderr(&r).contains("rgb"));
    // Without --strict an undetermined verdict is a usable result.
    cli::succeeded(run_in(dir, &["batch", "m.csv", "--out", "o"]), &["batch"]);
    cli::succeeded(
        run_in(dir, &["batch", "m.csv", "--out", "o", "--merge"]),
        &["merge"],
    );

    write(dir, "s.csv", "name,data,strict\nrgb,rgb.csv,true\n");
    let r = run_in(dir, &["batch", "s.csv", "--out", "o2"]);
    cli::assert_fails_with(&r, &["s.csv:1:3:", "hairfit batch --strict"]);
    assert!(!dir.join("o2").exists(), "nothing ran");
}

#[test]
fn failed_items_exit_1_run_again_and_merge_shows_their_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    quick_manifest(dir);
    zero_data(dir);
    write(
        dir,
        "f.csv",
        "name,data,space,starts,no-progress\n\
         lin,zero.csv,linear,2,true\n\
         log,zero.csv,,2,true\n\
         fib,sphere.csv,,2,true\n",
    );
    let first = run_in(dir, &["batch", "f.csv", "--out", "o"]);
    let err = cli::stderr(&first);
    assert_eq!(code(&first), Some(1), "{err}");
    // `lin` has a result (verdict failed), `log` none: the summary line counts both.
    assert!(
        err.contains("3 items, 2 fitted, 0 skipped (already finished), 2 failed"),
        "{err}"
    );
    assert!(err.contains("2 items failed: lin, log"), "{err}");
    // The log-space error names the manifest column to change.
    assert!(err.contains("column `space`"), "{err}");

    // Failed items are not finished: a re-run fits them again (and still exits 1).
    let again = run_in(dir, &["batch", "f.csv", "--out", "o"]);
    let err = cli::stderr(&again);
    assert_eq!(code(&again), Some(1), "{err}");
    assert!(err.contains("fib: skipped"), "{err}");
    assert!(
        !err.contains("lin: skipped") && !err.contains("log: skipped"),
        "{err}"
    );

    // Merge writes the table and the page, names the failed items with their errors, exits 1.
    let merged = run_in(dir, &["batch", "f.csv", "--out", "o", "--merge"]);
    let err = cli::stderr(&merged);
    assert_eq!(code(&merged), Some(1), "{err}");
    assert!(
        err.contains("failed: lin") && err.contains("log (channel"),
        "{err}"
    );
    assert!(!err.contains("missing"), "{err}");
    let mut table = csv::Reader::from_path(dir.join("o/summary.csv")).unwrap();
    let header = table.headers().unwrap().clone();
    let at = |name: &str| header.iter().position(|h| h == name).unwrap();
    let rows: Vec<csv::StringRecord> = table.records().map(|r| r.unwrap()).collect();
    assert_eq!(&rows[0][at("verdict")], "failed");
    assert_eq!(&rows[1][at("status")], "failed");
    assert!(rows[1][at("error")].contains("log-space fit is impossible"));
    assert_eq!(&rows[2][at("model")], "marschner");
    // `data` is the manifest's own text for every item.
    for r in &rows[..2] {
        assert_eq!(&r[at("data")], "zero.csv");
    }
    let html = std::fs::read_to_string(dir.join("o/index.html")).unwrap();
    assert!(
        html.contains("log-space fit is impossible"),
        "the page shows the error"
    );
}

#[test]
fn a_changed_data_file_runs_again_another_cwd_does_not_and_force_reruns() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    quick_manifest(dir);
    std::fs::create_dir(dir.join("sub")).unwrap();
    cli::succeeded(run_in(dir, &["batch", "m.csv", "--out", "o"]), &["batch"]);

    // The same manifest and output, named from another directory: the same fit, skipped.
    let r = run_in(&dir.join("sub"), &["batch", "../m.csv", "--out", "../o"]);
    assert!(
        cli::stderr(&r).contains("fib: skipped"),
        "{}",
        cli::stderr(&r)
    );

    // The data file re-measured at the same path (other size and time): fitted again.
    let mut text = std::fs::read_to_string(dir.join("sphere.csv")).unwrap();
    text += "# re-measured\n";
    std::fs::write(dir.join("sphere.csv"), text).unwrap();
    let r = run_in(dir, &["batch", "m.csv", "--out", "o"]);
    assert!(cli::stderr(&r).contains("1 fitted"), "{}", cli::stderr(&r));
    let r = run_in(dir, &["batch", "m.csv", "--out", "o"]);
    assert!(
        cli::stderr(&r).contains("fib: skipped"),
        "{}",
        cli::stderr(&r)
    );

    // --force fits every item again.
    let r = run_in(dir, &["batch", "m.csv", "--out", "o", "--force"]);
    assert!(cli::stderr(&r).contains("1 fitted"), "{}", cli::stderr(&r));

    // A deleted output of a finished item (params.json, the report, curves.csv) brings it back.
    for name in ["params.json", "index.html", "curves.csv"] {
        std::fs::remove_file(dir.join("o/fib").join(name)).unwrap();
        let r = run_in(dir, &["batch", "m.csv", "--out", "o"]);
        assert!(
            cli::stderr(&r).contains("1 fitted"),
            "{name}: {}",
            cli::stderr(&r)
        );
        assert!(dir.join("o/fib").join(name).is_file(), "{name} is back");
    }
}

#[test]
fn the_whole_manifest_is_checked_first_with_line_and_column() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    quick_manifest(dir);
    let cases: [(&str, &str, &[&str]); 8] = [
        // A good item first: nothing may run before the bad one is found.
        (
            "r.csv",
            "name,data\nfib,sphere.csv\nindex.html,sphere.csv\n",
            &["r.csv:3:1:", "reserved"],
        ),
        (
            "s.csv",
            "name,data\nSummary.CSV,sphere.csv\n",
            &["s.csv:2:1:", "reserved"],
        ),
        (
            "f.csv",
            "name,data,fix\nfib,sphere.csv,\nb,sphere.csv,etaa=1.5\n",
            &["f.csv:3:3:", "unknown parameter `etaa`"],
        ),
        (
            "g.csv",
            "name,data,fix\nb,sphere.csv,eta=abc\n",
            &["g.csv:2:3:", "`abc` is not a number"],
        ),
        (
            "l.csv",
            "name,data,lobes\nb,sphere.csv,R;TT\n",
            &["l.csv:2:3:", "\"R,TT\""],
        ),
        (
            "h.csv",
            "name,data,los\nb,sphere.csv,cauchy\n",
            &["h.csv:1:3:", "`los`"],
        ),
        (
            "j.json",
            r#"[{"name": "a", "data": "sphere.csv"}, {"name": "b", "data": "sphere.csv", "los": 1}]"#,
            &["j.json: item 2, key `los`: not a `hairfit fit` option"],
        ),
        (
            "k.json",
            r#"[{"name": "a", "data": "sphere.csv"}, {"name": "A", "data": "sphere.csv"}]"#,
            &["k.json: item 2, key `name`", "already used by item 1"],
        ),
    ];
    for (file, text, needles) in cases {
        write(dir, file, text);
        let r = run_in(dir, &["batch", file, "--out", "o"]);
        cli::assert_fails_with(&r, needles);
        assert!(!dir.join("o").exists(), "{file}: nothing ran");
    }
}

/// The lock message names its holder only when it knows it.
#[test]
fn a_held_lock_without_a_holder_says_so_plainly() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    quick_manifest(dir);
    std::fs::create_dir(dir.join("o")).unwrap();
    let lock_path = dir.join("o/.fib.hairfit-lock");
    let lock = std::fs::File::create(&lock_path).unwrap();
    lock.lock().unwrap();
    let r = run_in(dir, &["batch", "m.csv", "--out", "o"]);
    let err = cli::stderr(&r);
    assert_eq!(code(&r), Some(1), "{err}");
    assert!(
        err.contains("another hairfit run is writing there;"),
        "{err}"
    );
    assert!(!err.contains("()"), "{err}");
    drop(lock);
}

/// A `fix` of `sigma_a[5]` on 3-channel data was found only when that item ran, after the
/// items before it had been fitted. The channels of a CSV's header (or a scan's `columns`)
/// are known without loading the data, so such a fix is now an error at its manifest line
/// and column before any item of the shard runs. A JSON dataset's channels need the whole
/// file: its item still finds out when it runs.
#[test]
fn a_fix_naming_a_channel_the_data_lack_is_found_before_any_item_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    quick_manifest(dir);
    std::fs::copy(shipped("longitudinal_rgb.csv"), dir.join("rgb.csv")).unwrap();
    write(
        dir,
        "c.csv",
        "name,data,starts,fix\nfib,sphere.csv,2,\nrgb,rgb.csv,2,eta=1.5;sigma_a[5]=0.3\n",
    );
    let r = run_in(dir, &["batch", "c.csv", "--out", "o"]);
    cli::assert_fails_with(
        &r,
        &[
            "c.csv:3:4:",
            "`sigma_a[5]` names a channel the data do not have",
            "3 channels",
            "item `rgb`: its data rgb.csv has the channels r, g, b",
        ],
    );
    assert!(!dir.join("o").exists(), "nothing ran");
    // Within the data's channels the same manifest passes the check (and runs).
    write(
        dir,
        "c.csv",
        "name,data,starts,intervals,fix,no-progress\nrgb,rgb.csv,2,linear,sigma_a[2]=0.8,true\n",
    );
    let r = run_in(dir, &["batch", "c.csv", "--out", "o"]);
    assert_eq!(code(&r), Some(0), "{}", cli::stderr(&r));
}

/// Issue 27: every family runs in a batch. A `terms` cell is checked with its item's `model`
/// (the family's own terms), and a family's option on an item of another family is refused
/// with the line and column, naming the families it belongs to.
#[test]
fn items_of_table_families_take_their_own_terms() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(shipped("sphere_1ch.csv"), dir.path().join("sphere.csv")).unwrap();
    write(
        dir.path(),
        "m.csv",
        "name,data,model,terms,starts,no-progress\n\
         kk,sphere.csv,kajiya-kay,\"diffuse,specular\",2,true\n\
         fb,sphere.csv,frostbite,\"R,TT,TRT\",2,true\n",
    );
    let out = run_in(dir.path(), &["batch", "m.csv", "--out", "b"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(code(&out).is_some(), "{err}");
    assert!(!err.contains("m.csv:"), "a manifest error: {err}");
    for item in ["kk", "fb"] {
        let fit = std::fs::read_to_string(dir.path().join("b").join(item).join("fit.json"))
            .unwrap_or_else(|e| panic!("{item}: {e}; {err}"));
        assert!(fit.contains("\"terms\""), "{item}: {fit}");
    }
    write(
        dir.path(),
        "bad.csv",
        "name,data,terms\nm,sphere.csv,\"R,TT\"\n",
    );
    let out = run_in(dir.path(), &["batch", "bad.csv", "--out", "c"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.csv:2:") && err.contains("not --model marschner"),
        "{err}"
    );
}
