//! A write the system refuses part-way — a file-size limit (`ulimit -f`) or a full disk — is an
//! error that names the file and changes nothing: what `--out`/`--output` held stays byte for
//! byte, and no staging directory, lock or temporary file is left. Temporary files a killed run
//! left beside an output are removed by the next write of that output.

use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::support::cli;
use cli::{hairfit_command, hairfit_ok, run_within, s, shipped, snapshot, stderr, DEFAULT_LIMIT};

/// `hairfit ARGS` under a file-size limit of `bytes`: a write past it fails with EFBIG.
fn hairfit_with_file_limit(bytes: u64, args: &[&str]) -> std::process::Output {
    let mut command = hairfit_command(args);
    // SAFETY: only setrlimit runs between fork and exec; it allocates nothing.
    unsafe {
        command.pre_exec(move || {
            let limit = libc::rlimit {
                rlim_cur: bytes,
                rlim_max: bytes,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &limit) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    run_within(command, DEFAULT_LIMIT).0
}

/// Names in `dir` that only a run in progress may leave: staging directories, locks, temporaries.
fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".hairfit-") || n.starts_with(".hairfit-"))
        .collect()
}

fn fitted(dir: &Path) -> PathBuf {
    let fit = dir.join("F");
    hairfit_ok(&["fit", s(&shipped("sphere_1ch.csv")), "--out", s(&fit)]);
    fit
}

#[test]
fn a_file_size_limit_while_the_report_is_drawn_leaves_the_previous_result() {
    let tmp = tempfile::tempdir().unwrap();
    let fit = fitted(tmp.path());
    let before = snapshot(&fit);
    // 60 kB: fit.json and params.json fit under it, the report's PNGs do not.
    let out = hairfit_with_file_limit(
        60_000,
        &["demo", "--out", s(&fit), "--force", "--starts", "2"],
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("File too large"), "{err}");
    assert!(err.contains(s(&fit)), "the error names --out: {err}");
    assert_eq!(snapshot(&fit), before, "the previous result changed");
    assert!(
        leftovers(tmp.path()).is_empty(),
        "{:?}",
        leftovers(tmp.path())
    );
}

#[test]
fn a_two_file_export_under_a_file_size_limit_replaces_neither_file() {
    let tmp = tempfile::tempdir().unwrap();
    let fit = fitted(tmp.path());
    let exports = tmp.path().join("exports");
    let json = exports.join("hair.json");
    hairfit_ok(&["export", s(&fit), "--to", "unreal", "--output", s(&json)]);
    let before = snapshot(&exports);
    let sizes: Vec<u64> = ["hair.json", "hair.py"]
        .map(|n| std::fs::metadata(exports.join(n)).unwrap().len())
        .to_vec();
    // Between the two files' sizes: the first is written in full, the second is cut, so the
    // pair must be refused as a whole.
    let limit = (sizes[0].min(sizes[1]) + sizes[0].max(sizes[1])) / 2;
    assert!(sizes[0] != sizes[1], "{sizes:?}");
    let out = hairfit_with_file_limit(
        limit,
        &["export", s(&fit), "--to", "unreal", "--output", s(&json)],
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("File too large") && err.contains("none of"),
        "{err}"
    );
    assert_eq!(snapshot(&exports), before, "an exported file changed");
}

#[test]
fn temporaries_a_dead_run_left_are_removed_by_the_next_write() {
    let tmp = tempfile::tempdir().unwrap();
    let fit = fitted(tmp.path());
    let exports = tmp.path().join("exports");
    std::fs::create_dir(&exports).unwrap();
    // No process has a pid above the kernel's maximum (at most 2^22): this one is dead.
    let dead = exports.join(".hairfit-hair.pbrt-4194305-0.tmp");
    std::fs::write(&dead, "half a file").unwrap();
    // This test's own pid is alive: a run in progress keeps its temporary.
    let live = exports.join(format!(".hairfit-hair.pbrt-{}-0.tmp", std::process::id()));
    std::fs::write(&live, "being written").unwrap();
    // Another output's temporary is not this write's business.
    let other = exports.join(".hairfit-other.pbrt-4194305-0.tmp");
    std::fs::write(&other, "not mine").unwrap();
    let pbrt = exports.join("hair.pbrt");
    hairfit_ok(&["export", s(&fit), "--to", "pbrt", "--output", s(&pbrt)]);
    assert!(pbrt.is_file());
    assert!(!dead.exists(), "the dead run's temporary is still there");
    assert!(live.exists() && other.exists());
}

/// `script` run as root of a new user and mount namespace with a 3 MB tmpfs at `mount`, or
/// `None` where this system refuses such namespaces (then the file-size tests above stand in).
fn in_small_tmpfs(mount: &Path, script: &str) -> Option<std::process::Output> {
    let mut command = Command::new("unshare");
    command.args([
        "-rm",
        "sh",
        "-c",
        &format!(
            "mount -t tmpfs -o size=3m tmpfs '{}' || exit 97; {script}",
            mount.display()
        ),
    ]);
    let out = run_within(command, DEFAULT_LIMIT).0;
    if out.status.code() == Some(97) || stderr(&out).contains("unshare:") {
        eprintln!(
            "skipped: no tmpfs in a user namespace here: {}",
            stderr(&out)
        );
        return None;
    }
    Some(out)
}

#[test]
fn a_disk_that_fills_at_any_file_of_the_set_leaves_the_previous_result() {
    let tmp = tempfile::tempdir().unwrap();
    let mount = tmp.path().join("disk");
    std::fs::create_dir(&mount).unwrap();
    let bin = env!("CARGO_BIN_EXE_hairfit");
    let data = shipped("sphere_1ch.csv");
    // A fit (about 1 MB) in a 3 MB tmpfs; then fits over it with a filler file leaving from 8
    // pages more than a new set needs down to 8 pages less, one page (4 kB) at a time, so the
    // disk fills at each of the set's last files in turn (timing.json, index.html, the PNGs).
    // Every trial must end whole: exit 0 and the marker lists exactly the files there, or exit
    // 1 and the set byte for byte as before. The tmpfs dies with the namespace, so the script
    // prints what the test checks.
    let script = format!(
        r#"cd {m} || exit 98
        sums() {{ (cd F && find . -type f | sort | xargs md5sum); }}
        '{bin}' fit '{data}' --out F --starts 3 >/dev/null 2>&1 || exit 98
        need=$(du -sk F | cut -f1); avail=$(df -k . | tail -1 | awk '{{print $4}}')
        for k in $(seq 0 4 64); do
            rm -f filler; head -c $(( (avail - need - 32 + k) * 1024 )) /dev/zero > filler 2>/dev/null
            before=$(sums)
            '{bin}' fit '{data}' --out F --starts 3 >/dev/null 2>{err}; code=$?
            listed=$(sed -n 's/^name: //p' F/.hairfit | sort | tr '\n' ' ')
            present=$(ls F | sort | tr '\n' ' ')
            if [ $code = 1 ] && [ "$(sums)" = "$before" ]; then state=unchanged
            elif [ $code = 0 ] && [ -n "$listed" ] && [ "$listed" = "$present" ]; then state=complete
            else state=BROKEN; fi
            echo "trial $k exit=$code state=$state left=$(ls -A | grep -c hairfit-) $(grep -o '[^ ]*: No space left' {err})"
        done"#,
        m = mount.display(),
        data = data.display(),
        err = tmp.path().join("err").display(),
    );
    let Some(out) = in_small_tmpfs(&mount, &script) else {
        return;
    };
    let text = format!("{}{}", cli::stdout(&out), stderr(&out));
    let trials: Vec<&str> = text.lines().filter(|l| l.starts_with("trial ")).collect();
    assert_eq!(trials.len(), 17, "{text}");
    for t in &trials {
        assert!(
            t.contains("state=unchanged") || t.contains("state=complete"),
            "a set not whole: {t}\n{text}"
        );
        assert!(
            t.contains("left=0"),
            "a staging directory or lock left: {t}"
        );
        assert!(
            t.contains("exit=0") || t.contains("No space left"),
            "exit 1 without the disk's error: {t}"
        );
    }
    // The sweep really crossed the boundary: some trials published, and the disk filled at
    // more than one of the set's files.
    let failing: std::collections::BTreeSet<&str> = trials
        .iter()
        .filter_map(|t| t.split_whitespace().find(|w| w.starts_with("F/")))
        .collect();
    assert!(trials.iter().any(|t| t.contains("exit=0")), "{text}");
    assert!(
        failing.len() >= 2,
        "the disk filled only at {failing:?}: {text}"
    );
}
