//! Unit tests of the output-set protocol (src/outdir.rs).

use super::*;

fn write(set: &OutputSet, name: &str, text: &str) {
    std::fs::write(set.staging().join(name), text).unwrap();
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn a_new_set_replaces_the_old_one_whole() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("fit");
    let set = OutputSet::begin(&out, "test", false, &[]).unwrap();
    write(&set, "fit.json", "1");
    write(&set, "polar.png", "old figure");
    set.publish().unwrap();
    let set = OutputSet::begin(&out, "test", false, &[]).unwrap();
    // Until publish, readers see the old set.
    write(&set, "fit.json", "2");
    assert_eq!(std::fs::read_to_string(out.join("fit.json")).unwrap(), "1");
    set.publish().unwrap();
    assert_eq!(std::fs::read_to_string(out.join("fit.json")).unwrap(), "2");
    assert_eq!(
        names(&out),
        [MARKER, "fit.json"],
        "the stale figure is gone"
    );
    // Nothing but the result beside it: the lock went with the run.
    assert_eq!(names(tmp.path()), ["fit"]);
}

#[test]
fn an_unpublished_set_leaves_the_old_one_and_no_staging() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("fit");
    let set = OutputSet::begin(&out, "test", false, &[]).unwrap();
    write(&set, "fit.json", "1");
    set.publish().unwrap();
    {
        let set = OutputSet::begin(&out, "test", false, &[]).unwrap();
        write(&set, "fit.json", "half");
    }
    assert_eq!(std::fs::read_to_string(out.join("fit.json")).unwrap(), "1");
    assert_eq!(names(tmp.path()), ["fit"]);
}

#[test]
fn a_second_run_fails_fast_while_the_first_holds_the_lock() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("fit");
    let first = OutputSet::begin(&out, "test", false, &[]).unwrap();
    let e = OutputSet::begin(&out, "test", false, &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("another hairfit run") && e.contains("pid"),
        "{e}"
    );
    drop(first);
    OutputSet::begin(&out, "test", false, &[]).unwrap();
}

#[test]
fn foreign_directories_and_inputs_inside_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("mine");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("params.json"), "hand-written").unwrap();
    let e = OutputSet::begin(&out, "test", false, &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("--force") && e.contains("params.json"), "{e}");
    // --force writes there, but never into a directory holding the run's input.
    let data = out.join("curves.csv");
    std::fs::write(&data, "x").unwrap();
    let e = OutputSet::begin(&out, "test", true, &[&data])
        .unwrap_err()
        .to_string();
    assert!(e.contains("is inside it"), "{e}");
    // ... and keeps what it did not write; a name the new set also writes is refused.
    let set = OutputSet::begin(&out, "test", true, &[]).unwrap();
    set.publish().unwrap();
    assert_eq!(names(&out), [MARKER, "curves.csv", "params.json"]);
    let set = OutputSet::begin(&out, "test", false, &[]).unwrap();
    write(&set, "params.json", "fitted");
    let e = set.publish().unwrap_err().to_string();
    assert!(
        e.contains("not written by hairfit") && e.contains("params.json"),
        "{e}"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("params.json")).unwrap(),
        "hand-written"
    );
}

#[test]
fn a_directory_that_only_looks_like_a_result_is_not_one() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("old");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("fit.json"), r#"{"hairfit_version": "0.1.0"}"#).unwrap();
    let e = OutputSet::begin(&out, "hairfit fit", false, &[]).unwrap_err();
    assert!(e.to_string().contains("--force"), "{e}");
}

#[test]
fn the_users_files_and_folders_are_carried_into_the_new_set() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("fit");
    let set = OutputSet::begin(&out, "hairfit fit", false, &[]).unwrap();
    write(&set, "fit.json", "1");
    set.publish().unwrap();
    std::fs::create_dir(out.join("notes")).unwrap();
    std::fs::write(out.join("notes/a.txt"), "mine").unwrap();
    std::fs::write(out.join("hair.pbrt"), "export").unwrap();
    let set = OutputSet::begin(&out, "hairfit fit", false, &[]).unwrap();
    write(&set, "fit.json", "2");
    set.publish().unwrap();
    assert_eq!(names(&out), [MARKER, "fit.json", "hair.pbrt", "notes"]);
    assert_eq!(
        std::fs::read_to_string(out.join("notes/a.txt")).unwrap(),
        "mine"
    );
    let marker = Marker::read(&out).unwrap().unwrap();
    assert_eq!(marker.names, Some(vec!["fit.json".to_string()]));
}

#[test]
fn the_users_files_inside_a_compare_fit_are_carried_over() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("cmp");
    for run in ["first", "second"] {
        let set = OutputSet::begin(&out, "hairfit compare", false, &[]).unwrap();
        let sub = set.sub_dir("marschner").unwrap();
        std::fs::write(sub.join("fit.json"), run).unwrap();
        set.publish().unwrap();
        if run == "first" {
            std::fs::write(out.join("marschner/notes.txt"), "mine").unwrap();
        }
    }
    assert_eq!(
        names(&out.join("marschner")),
        [MARKER, "fit.json", "notes.txt"]
    );
    let sub = Marker::read(&out.join("marschner")).unwrap().unwrap();
    assert_eq!(sub.kind, Kind::Fit);
}

#[test]
fn sets_of_many_results_are_never_replaced_by_another_kind() {
    let tmp = tempfile::tempdir().unwrap();
    let batch = tmp.path().join("b");
    claim_shared_dir(&batch, "hairfit batch", &[]).unwrap();
    for force in [false, true] {
        for command in ["hairfit fit", "hairfit compare", "hairfit demo"] {
            let e = OutputSet::begin(&batch, command, force, &[]).unwrap_err();
            assert!(e.to_string().contains("batch directory"), "{e}");
        }
    }
    let cmp = tmp.path().join("c");
    OutputSet::begin(&cmp, "hairfit compare", false, &[])
        .unwrap()
        .publish()
        .unwrap();
    let e = OutputSet::begin(&cmp, "hairfit fit", true, &[]).unwrap_err();
    assert!(e.to_string().contains("compare directory"), "{e}");
    let e = claim_shared_dir(&cmp, "hairfit batch", &[]).unwrap_err();
    assert!(e.to_string().contains("compare directory"), "{e}");
}

#[test]
fn stale_staging_directories_and_free_locks_are_removed_by_the_next_run() {
    let tmp = tempfile::tempdir().unwrap();
    // What SIGKILLed runs leave: staging directories (one half-swapped) and lock files.
    for stale in [
        ".fit.hairfit-stage-AbC123",
        ".fit.hairfit-stage-x9Y8z7.old",
        ".other.hairfit-stage-Q1w2E3",
    ] {
        std::fs::create_dir(tmp.path().join(stale)).unwrap();
        std::fs::write(tmp.path().join(stale).join("fit.json"), "half").unwrap();
    }
    std::fs::write(tmp.path().join(".fit.hairfit-lock"), "pid 1").unwrap();
    std::fs::write(tmp.path().join(".gone.hairfit-lock"), "pid 1").unwrap();
    // A live run's lock and staging directory stay.
    let live = tmp.path().join(".live.hairfit-lock");
    let held = File::create(&live).unwrap();
    held.lock().unwrap();
    std::fs::create_dir(tmp.path().join(".live.hairfit-stage-ZZZ999")).unwrap();
    // A user's file that only resembles one stays too.
    std::fs::create_dir(tmp.path().join(".fit.hairfit-stage-not mine")).unwrap();
    let set = OutputSet::begin(&tmp.path().join("fit"), "test", false, &[]).unwrap();
    set.publish().unwrap();
    assert_eq!(
        names(tmp.path()),
        [
            ".fit.hairfit-stage-not mine",
            ".live.hairfit-lock",
            ".live.hairfit-stage-ZZZ999",
            "fit"
        ]
    );
    drop(held);
}

#[test]
fn keep_carries_files_into_the_new_set() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("fit");
    let set = OutputSet::begin(&out, "test", false, &[]).unwrap();
    write(&set, "curves.csv", "data");
    write(&set, "old.png", "figure");
    set.publish().unwrap();
    let set = OutputSet::begin(&out, "test", false, &[]).unwrap();
    set.keep(&["curves.csv"]).unwrap();
    set.publish().unwrap();
    assert_eq!(names(&out), [MARKER, "curves.csv"]);
}

/// The out-of-memory exit may not allocate to learn of a staging directory, so each is listed
/// before it exists; its name is one the next run's cleanup recognises as a stage of its owner;
/// a name taken already is skipped, not reused.
#[test]
fn a_staging_directory_is_listed_before_it_exists_and_named_as_a_stage() {
    let tmp = tempfile::tempdir().unwrap();
    let taken = tmp
        .path()
        .join(format!(".fit.hairfit-stage-p{}n0", std::process::id()));
    std::fs::create_dir(&taken).unwrap();
    let staging = create_staging(tmp.path(), "fit").unwrap();
    assert_ne!(staging, taken);
    assert!(staging.is_dir());
    assert!(IN_FLIGHT.lock().unwrap().contains(&staging));
    assert!(!IN_FLIGHT.lock().unwrap().contains(&taken));
    let name = staging.file_name().unwrap().to_str().unwrap();
    assert_eq!(bookkeeping_owner(name), Some("fit"));
    forget(&IN_FLIGHT, &staging);
}
