//! Output directories published as one set. A run locks its `--out` directory (a second run
//! fails fast and names the holder), writes everything into a staging directory beside it, and
//! publishes by swapping the staging directory in: a reader sees the old set or the new set,
//! never a mix, and nothing of an earlier run lingers beside a new one. A directory that holds
//! something other than a hairfit result is refused unless `--force`, and never one that holds
//! the run's own input.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::error::{Error, Result};

/// The file that marks a directory as a hairfit output set (its content names the command).
pub const MARKER: &str = ".hairfit";

/// Staging directories being written right now: a process ending by a signal runs no
/// destructors, so the signal handler removes them through [`remove_in_flight`].
static IN_FLIGHT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Remove every staging directory still being written (for a signal handler that then exits).
pub fn remove_in_flight() {
    let list = IN_FLIGHT.lock().unwrap_or_else(|e| e.into_inner());
    for p in list.iter() {
        // The run's other threads may still be creating a file in it (remove_dir_all then
        // fails with "directory not empty"), or, having started an output just before
        // `atomic::stop_writing`, create the directory again behind the removal: remove until
        // it stays gone for 10 ms (stopping at the first success left the directory behind once,
        // in a full CI run under load).
        for _ in 0..200 {
            let _ = std::fs::remove_dir_all(p);
            if !p.exists() {
                std::thread::sleep(std::time::Duration::from_millis(10));
                if !p.exists() {
                    break;
                }
            } else {
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
        }
    }
}

fn forget_in_flight(path: &Path) {
    let mut list = IN_FLIGHT.lock().unwrap_or_else(|e| e.into_inner());
    list.retain(|p| p != path);
}

/// An output set being written: files go to [`OutputSet::staging`], then [`OutputSet::publish`].
/// Dropped unpublished (an error), the staging directory is removed and the old set stays.
#[derive(Debug)]
pub struct OutputSet {
    /// `--out` as given, for messages.
    dir: PathBuf,
    /// The directory replaced: `dir` absolute, links resolved (a link to a directory keeps
    /// pointing at the new set; the lock and staging directory sit beside the same place).
    target: PathBuf,
    staging: PathBuf,
    /// What the marker says wrote the set (e.g. `hairfit fit`).
    command: String,
    published: bool,
    /// Held for the life of the run: the OS releases it when the process ends, however it ends.
    _lock: File,
}

/// Whether `dir` may be replaced: absent, empty, or already a hairfit output set.
fn holds_foreign_files(dir: &Path) -> Result<Option<String>> {
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(Error::io(dir, e)),
    };
    let names: Vec<String> = entries
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    if names.is_empty() || names.iter().any(|n| n == MARKER) || is_legacy_result(dir) {
        return Ok(None);
    }
    let mut shown: Vec<&str> = names.iter().map(String::as_str).take(3).collect();
    shown.sort();
    Ok(Some(format!(
        "{}{}",
        shown.join(", "),
        if names.len() > 3 { ", …" } else { "" }
    )))
}

/// A result written before the marker existed: `fit.json`, `cost.json` or `compare.json` by
/// hairfit (a compare directory had markers only in its two fit directories).
fn is_legacy_result(dir: &Path) -> bool {
    ["fit.json", "cost.json", "compare.json"].iter().any(|f| {
        std::fs::read_to_string(dir.join(f)).is_ok_and(|t| t.contains("\"hairfit_version\""))
    })
}

/// `path` made absolute and free of `.`/`..` (the part that exists is resolved through links).
fn absolute(path: &Path) -> Result<PathBuf> {
    let abs = std::path::absolute(path).map_err(|e| Error::io(path, e))?;
    // Resolve the longest existing ancestor, keep the rest as written.
    let mut existing = abs.clone();
    let mut rest = Vec::new();
    while !existing.exists() {
        match (existing.file_name(), existing.parent()) {
            (Some(name), Some(parent)) => {
                rest.push(name.to_os_string());
                existing = parent.to_path_buf();
            }
            _ => break,
        }
    }
    let mut out = existing.canonicalize().unwrap_or(existing);
    for part in rest.into_iter().rev() {
        out.push(part);
    }
    Ok(out)
}

/// `dir` made absolute, or an error naming `--out` when it cannot be an output directory: the
/// file system's root, the current directory or one holding it, or an existing file. `why`
/// says what the command does with the directory.
pub fn check_out_path(dir: &Path, why: &str) -> Result<PathBuf> {
    let abs = absolute(dir)?;
    let refuse = |what: &str| {
        Err(Error::Other(format!(
            "--out {}: {what}, and {why}; name a directory of its own, e.g. fits/NAME",
            dir.display()
        )))
    };
    if abs.parent().is_none() || abs.file_name().is_none() {
        return refuse("that is the file system's root");
    }
    let cwd = std::env::current_dir()
        .ok()
        .and_then(|c| c.canonicalize().ok());
    if cwd.as_ref().is_some_and(|c| c.starts_with(&abs)) {
        return refuse("that is the current directory (or holds it)");
    }
    if std::fs::metadata(&abs).is_ok_and(|m| !m.is_dir()) {
        return refuse("that is a file, not a directory");
    }
    Ok(abs)
}

/// `--out DIR` cannot be written: `what` (the directory, or the lock file or staging
/// directory beside it) could not be created. Names the option and what to do, with the OS's
/// reason.
fn unwritable(dir: &Path, what: String, e: &std::io::Error) -> Error {
    Error::Other(format!(
        "--out {}: cannot write there: {what} could not be created ({e}); choose an --out in \
         a directory you can write to, e.g. fits/NAME",
        dir.display(),
    ))
}

/// Whether `name` is one of the hidden files hairfit keeps beside its outputs (a lock, a
/// staging directory, the marker).
fn is_hairfit_bookkeeping(name: &str) -> bool {
    name == MARKER
        || (name.starts_with('.')
            && (name.ends_with(".hairfit-lock") || name.contains(".hairfit-stage-")))
}

/// Claim `dir` for a command that adds to it rather than replacing it (`hairfit batch`: one
/// sub-directory per item, written by concurrent shards): refused as [`check_out_path`] does,
/// and when it holds files hairfit did not write (no marker, and none of `legacy`, names an
/// older hairfit wrote there). Creates it with its marker.
pub fn claim_shared_dir(dir: &Path, command: &str, legacy: &[&str]) -> Result<()> {
    let abs = check_out_path(dir, &format!("{command} writes its results into it"))?;
    match std::fs::read_dir(&abs) {
        Ok(entries) => {
            let names: Vec<String> = entries
                .filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect();
            let ours = names
                .iter()
                .any(|n| n == MARKER || legacy.contains(&n.as_str()));
            let foreign: Vec<&str> = names
                .iter()
                .map(String::as_str)
                .filter(|n| !is_hairfit_bookkeeping(n))
                .collect();
            if !ours && !foreign.is_empty() {
                let mut shown: Vec<&str> = foreign.iter().copied().take(3).collect();
                shown.sort();
                return Err(Error::Other(format!(
                    "--out {}: the directory holds files hairfit did not write ({}{}); choose a new or empty directory (e.g. fits/batch) so none of them is overwritten",
                    dir.display(),
                    shown.join(", "),
                    if foreign.len() > 3 { ", …" } else { "" }
                )));
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            std::fs::create_dir_all(&abs)
                .map_err(|e| unwritable(dir, format!("the directory {}", abs.display()), &e))?;
        }
        Err(e) => return Err(Error::io(dir, e)),
    }
    let marker = abs.join(MARKER);
    if !marker.exists() {
        std::fs::write(&marker, format!("written by {command}\n"))
            .map_err(|e| unwritable(dir, format!("the file {}", marker.display()), &e))?;
    }
    Ok(())
}

impl OutputSet {
    /// Lock `dir` and open a staging directory beside it for `command` (e.g. `hairfit fit`).
    /// `inputs` are the files the run reads: none may lie inside `dir`, which is replaced whole.
    pub fn begin(dir: &Path, command: &str, force: bool, inputs: &[&Path]) -> Result<OutputSet> {
        let abs = check_out_path(dir, "the output directory is replaced as a whole")?;
        let (Some(parent), Some(name)) = (abs.parent(), abs.file_name()) else {
            unreachable!("check_out_path refuses the root");
        };
        for input in inputs {
            let input_abs = absolute(input)?;
            if input_abs.starts_with(&abs) {
                return Err(Error::Other(format!(
                    "--out {}: the input {} is inside it, and the output directory is replaced as a whole; write the result elsewhere",
                    dir.display(),
                    input.display()
                )));
            }
        }
        std::fs::create_dir_all(parent)
            .map_err(|e| unwritable(dir, format!("the directory {}", parent.display()), &e))?;
        let lock = lock(parent, &name.to_string_lossy(), dir)?;
        if let Some(found) = holds_foreign_files(&abs)? {
            if !force {
                return Err(Error::Other(format!(
                    "--out {}: the directory holds files that are not a hairfit result ({found}); a run replaces the whole directory. Choose an empty or new directory, or pass --force to replace it",
                    dir.display()
                )));
            }
        }
        let staging = tempfile::Builder::new()
            .prefix(&format!(".{}.hairfit-stage-", name.to_string_lossy()))
            .tempdir_in(parent)
            .map_err(|e| {
                let what = format!("a staging directory in {}", parent.display());
                unwritable(dir, what, &e)
            })?
            .keep();
        IN_FLIGHT
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(staging.clone());
        let marker = staging.join(MARKER);
        std::fs::write(&marker, format!("written by {command}\n"))
            .map_err(|e| Error::io(&marker, e))?;
        Ok(OutputSet {
            dir: dir.to_path_buf(),
            target: abs.clone(),
            staging,
            command: command.to_string(),
            published: false,
            _lock: lock,
        })
    }

    /// Where the run writes its files.
    pub fn staging(&self) -> &Path {
        &self.staging
    }

    /// The directory the set is published to.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Create the sub-directory `name` of the set (e.g. `hairfit compare`'s `marschner/`)
    /// with a marker of its own, so it reads as an output set by itself (`hairfit report`
    /// redraws it). It is published with the set: it has no lock or staging directory of its
    /// own, and so leaves none inside the set.
    pub fn sub_dir(&self, name: &str) -> Result<PathBuf> {
        let sub = self.staging.join(name);
        std::fs::create_dir(&sub).map_err(|e| Error::io(&sub, e))?;
        let marker = sub.join(MARKER);
        std::fs::write(&marker, format!("written by {}\n", self.command))
            .map_err(|e| Error::io(&marker, e))?;
        Ok(sub)
    }

    /// Carry `names` of the current set into the new one unchanged (hard links where possible,
    /// so a large `curves.csv` is not copied), e.g. when a report is redrawn.
    pub fn keep(&self, names: &[&str]) -> Result<()> {
        for name in names {
            let (from, to) = (self.target.join(name), self.staging.join(name));
            if std::fs::hard_link(&from, &to).is_err() {
                std::fs::copy(&from, &to).map_err(|e| Error::io(&from, e))?;
            }
        }
        Ok(())
    }

    /// Carry every file of the current set into the new one except those `redrawn` names (the
    /// run makes them anew, or they are stale): e.g. `hairfit report` keeps the fit's files and
    /// redraws the figures.
    pub fn keep_all_but(&self, redrawn: impl Fn(&str) -> bool) -> Result<()> {
        let entries = match std::fs::read_dir(&self.target) {
            Ok(e) => e,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
            Err(e) => return Err(Error::io(&self.dir, e)),
        };
        let mut names = Vec::new();
        for entry in entries {
            let entry = entry.map_err(|e| Error::io(&self.dir, e))?;
            let name = entry.file_name().to_string_lossy().into_owned();
            if name != MARKER && !redrawn(&name) && entry.path().is_file() {
                names.push(name);
            }
        }
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        self.keep(&names)
    }

    /// Swap the staged set in place of the old one, then remove the old one.
    pub fn publish(mut self) -> Result<()> {
        let old = swap_in(&self.staging, &self.target)?;
        self.published = true;
        forget_in_flight(&self.staging);
        if let Some(old) = old {
            let _ = std::fs::remove_dir_all(old);
        }
        Ok(())
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        if !self.published {
            let _ = std::fs::remove_dir_all(&self.staging);
            forget_in_flight(&self.staging);
        }
    }
}

/// Take `parent/.NAME.hairfit-lock` without waiting; when another run holds it, say which.
fn lock(parent: &Path, name: &str, dir: &Path) -> Result<File> {
    let path = parent.join(format!(".{name}.hairfit-lock"));
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .read(true)
        .write(true)
        .open(&path)
        .map_err(|e| unwritable(dir, format!("the lock file {}", path.display()), &e))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            // The holder writes its name just after taking the lock: it may not be there yet.
            let holder = std::fs::read_to_string(&path).unwrap_or_default();
            let holder = match holder.trim() {
                "" => String::new(),
                h => format!(" ({h})"),
            };
            return Err(Error::Other(format!(
                "--out {}: another hairfit run is writing there{holder}; wait for it, or choose another --out",
                dir.display(),
            )));
        }
        Err(std::fs::TryLockError::Error(e)) => return Err(Error::io(&path, e)),
    }
    // Who holds it, for the message a second run prints.
    let _ = file.set_len(0);
    let _ = writeln!(
        file,
        "pid {}, {}",
        std::process::id(),
        std::env::args().collect::<Vec<_>>().join(" ")
    );
    Ok(file)
}

/// Put `staging` at `dir`; returns where the old set now is (to be removed), if there was one.
fn swap_in(staging: &Path, dir: &Path) -> Result<Option<PathBuf>> {
    if std::fs::symlink_metadata(dir).is_err() {
        std::fs::rename(staging, dir).map_err(|e| Error::io(dir, e))?;
        return Ok(None);
    }
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{renameat_with, RenameFlags, CWD};
        if renameat_with(CWD, staging, CWD, dir, RenameFlags::EXCHANGE).is_ok() {
            return Ok(Some(staging.to_path_buf()));
        }
    }
    // No atomic exchange here: two renames, the old set moved aside first.
    let aside = staging.with_extension("old");
    std::fs::rename(dir, &aside).map_err(|e| Error::io(dir, e))?;
    if let Err(e) = std::fs::rename(staging, dir) {
        let _ = std::fs::rename(&aside, dir);
        return Err(Error::io(dir, e));
    }
    Ok(Some(aside))
}

#[cfg(test)]
mod tests {
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
        // Nothing but the result and its hidden lock file beside it.
        assert_eq!(names(tmp.path()), [".fit.hairfit-lock", "fit"]);
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
        assert_eq!(names(tmp.path()), [".fit.hairfit-lock", "fit"]);
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
        // --force replaces it, but never a directory holding the run's input.
        let data = out.join("curves.csv");
        std::fs::write(&data, "x").unwrap();
        let e = OutputSet::begin(&out, "test", true, &[&data])
            .unwrap_err()
            .to_string();
        assert!(e.contains("is inside it"), "{e}");
        let set = OutputSet::begin(&out, "test", true, &[]).unwrap();
        set.publish().unwrap();
        assert_eq!(names(&out), [MARKER]);
    }

    #[test]
    fn a_legacy_result_without_marker_may_be_replaced() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("old");
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("fit.json"), r#"{"hairfit_version": "0.1.0"}"#).unwrap();
        OutputSet::begin(&out, "test", false, &[]).unwrap();
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
}
