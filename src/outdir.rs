//! One file past 650 lines because the lock, the marker, staging and publication are one protocol
//! whose promises (never delete a user's file; all or nothing) are read and reviewed together.
//!
//! Output directories published as one set. A run locks its `--out` directory (a second run
//! fails fast and names the holder), writes everything into a staging directory beside it, and
//! publishes by swapping the staging directory in: a reader sees the old set or the new set,
//! never a mix, and nothing of an earlier run lingers beside a new one.
//!
//! A directory is hairfit's only when its marker (`.hairfit`) says so: the marker names the
//! command that wrote the set, its kind (fit, compare, batch, cost) and every name hairfit wrote
//! into it. Anything else in the directory is the user's and is carried over into the new set
//! (or the run refuses); a directory without a marker is refused unless `--force`, a set of one
//! kind never replaces a batch or compare directory nor the reverse, and never one that holds
//! the run's own input. Staging directories and locks left by a killed run are removed by the
//! next run beside them; a finished run leaves neither.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::error::{Error, Result};

/// The file that marks a directory as a hairfit output set (see [`Marker`]).
pub const MARKER: &str = ".hairfit";

/// Staging directories being written right now: a process ending by a signal runs no
/// destructors, so the signal handler removes them through [`remove_in_flight`].
static IN_FLIGHT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Lock files held right now, removed with the staging directories by [`remove_in_flight`].
static LOCKS_HELD: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Remove every staging directory still being written and the locks held (for a signal
/// handler that then exits).
pub fn remove_in_flight() {
    let list = crate::atomic::lock_briefly(&IN_FLIGHT);
    for p in list.iter().flat_map(|l| l.iter()) {
        // The run's other threads may still be creating a file in it (remove_dir_all then
        // fails with "directory not empty"), or, having started an output just before
        // `atomic::stop_writing`, create the directory again behind the removal: remove until
        // it stays gone for 10 ms.
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
    // Still held by this process (it exits next), so no other run has it.
    for p in crate::atomic::lock_briefly(&LOCKS_HELD)
        .iter()
        .flat_map(|l| l.iter())
    {
        let _ = std::fs::remove_file(p);
    }
}

fn forget(list: &Mutex<Vec<PathBuf>>, path: &Path) {
    let mut list = list.lock().unwrap_or_else(|e| e.into_inner());
    list.retain(|p| p != path);
}

/// The kinds of output set: which may replace which.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// One fit with its report (`hairfit fit`, `demo`, `report`, Python's `FitResult.save`).
    Fit,
    /// `hairfit compare`: one fit directory per family and the comparison.
    Compare,
    /// `hairfit batch`: one fit directory per item, written by many runs.
    Batch,
    /// `hairfit cost`.
    Cost,
}

impl Kind {
    fn as_str(self) -> &'static str {
        match self {
            Kind::Fit => "fit",
            Kind::Compare => "compare",
            Kind::Batch => "batch",
            Kind::Cost => "cost",
        }
    }

    fn parse(s: &str) -> Option<Kind> {
        [Kind::Fit, Kind::Compare, Kind::Batch, Kind::Cost]
            .into_iter()
            .find(|k| k.as_str() == s)
    }

    /// The kind a command writes (`hairfit report` keeps the kind of the set it redraws).
    fn of_command(command: &str) -> Kind {
        let word = command.rsplit(' ').next().unwrap_or("");
        match word {
            "compare" => Kind::Compare,
            "batch" => Kind::Batch,
            "cost" => Kind::Cost,
            _ => Kind::Fit,
        }
    }

    /// Sets of these kinds hold many results: nothing of another kind replaces them, and they
    /// replace nothing of another kind, even with `--force`.
    fn holds_many(self) -> bool {
        matches!(self, Kind::Compare | Kind::Batch)
    }
}

/// `DIR/.hairfit`: which command wrote the set, its kind, and the names it wrote. The one type
/// that writes and reads the marker.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// E.g. `hairfit fit`.
    pub command: String,
    pub kind: Kind,
    /// The entries hairfit wrote; `None` for a marker of an older hairfit, which listed none
    /// (its files were hairfit's, and of its directories those with a marker of their own).
    pub names: Option<Vec<String>>,
}

impl Marker {
    /// The marker of `dir`, if it has one (`Ok(None)`: none, or `dir` is absent).
    pub fn read(dir: &Path) -> Result<Option<Marker>> {
        let path = dir.join(MARKER);
        let text = match std::fs::read(&path) {
            Ok(t) => String::from_utf8_lossy(&t).into_owned(),
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
                ) =>
            {
                return Ok(None)
            }
            Err(e) => return Err(Error::io(&path, e)),
        };
        let mut command = String::new();
        let mut kind = None;
        let mut names = None::<Vec<String>>;
        for line in text.lines() {
            if let Some(c) = line.strip_prefix("written by ") {
                command = c.trim().to_string();
            } else if let Some(k) = line.strip_prefix("kind: ") {
                kind = Kind::parse(k.trim());
                names.get_or_insert_with(Vec::new);
            } else if let Some(n) = line.strip_prefix("name: ") {
                names.get_or_insert_with(Vec::new).push(n.to_string());
            }
        }
        Ok(Some(Marker {
            kind: kind.unwrap_or_else(|| Kind::of_command(&command)),
            command,
            names,
        }))
    }

    fn text(&self) -> String {
        let mut s = format!(
            "written by {}\nkind: {}\n",
            self.command,
            self.kind.as_str()
        );
        for n in self.names.iter().flatten() {
            s += &format!("name: {n}\n");
        }
        s
    }

    /// Whether hairfit wrote the entry `name` of `dir` (the directory this marker marks).
    fn owns(&self, dir: &Path, name: &str) -> bool {
        match &self.names {
            Some(names) => names.iter().any(|n| n == name),
            None => {
                let path = dir.join(name);
                match std::fs::symlink_metadata(&path) {
                    Ok(m) if m.is_dir() => path.join(MARKER).exists(),
                    Ok(m) => m.is_file(),
                    Err(_) => false,
                }
            }
        }
    }
}

/// The entries of `dir` hairfit did not write: every one but its bookkeeping when it has no
/// marker. Sorted; empty when `dir` is absent.
fn foreign_entries(dir: &Path, marker: Option<&Marker>) -> Result<Vec<String>> {
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(Error::io(dir, e)),
    };
    let mut names = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if is_hairfit_bookkeeping(&name) || marker.is_some_and(|m| m.owns(dir, &name)) {
            continue;
        }
        names.push(name);
    }
    names.sort();
    Ok(names)
}

/// A few names for a message: `a, b, c, …`.
fn shown(names: &[String]) -> String {
    let mut s = names.iter().take(3).cloned().collect::<Vec<_>>().join(", ");
    if names.len() > 3 {
        s += ", …";
    }
    s
}

/// `path` made absolute and free of `.`/`..` (the part that exists is resolved through links).
fn absolute(path: &Path) -> Result<PathBuf> {
    if path.as_os_str().is_empty() {
        return Err(Error::Other(
            "the output directory is an empty path; name a directory, e.g. fits/NAME".into(),
        ));
    }
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

/// The hairfit output set `path` lies in, if any: the nearest directory above it (or itself)
/// with a marker, and that marker. An export written there would be lost when the set is
/// replaced, or would overwrite one of its files.
pub fn enclosing_set(path: &Path) -> Option<(PathBuf, Marker)> {
    let abs = absolute(path).ok()?;
    let mut dir = abs.parent();
    while let Some(d) = dir {
        if let Ok(Some(m)) = Marker::read(d) {
            return Some((d.to_path_buf(), m));
        }
        dir = d.parent();
    }
    None
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
    name == MARKER || bookkeeping_owner(name).is_some()
}

/// The output directory a lock or staging directory named `name` belongs to:
/// `.NAME.hairfit-lock` and `.NAME.hairfit-stage-XXXXXX[.old]` belong to `NAME`.
fn bookkeeping_owner(name: &str) -> Option<&str> {
    let rest = name.strip_prefix('.')?;
    if let Some(owner) = rest.strip_suffix(".hairfit-lock") {
        return Some(owner);
    }
    let (owner, suffix) = rest.rsplit_once(".hairfit-stage-")?;
    let random = suffix.strip_suffix(".old").unwrap_or(suffix);
    (!random.is_empty() && random.chars().all(|c| c.is_ascii_alphanumeric())).then_some(owner)
}

/// Remove what killed runs left in `parent`: the staging directories of every output
/// directory whose lock no live run holds, and those locks. `held` is the name whose lock this
/// run holds (its stale staging directories go too).
fn heal(parent: &Path, held: Option<&str>) {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    let mut by_owner: std::collections::BTreeMap<String, Vec<PathBuf>> = Default::default();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if let Some(owner) = bookkeeping_owner(&name) {
            let list = by_owner.entry(owner.to_string()).or_default();
            if !name.ends_with(".hairfit-lock") {
                list.push(entry.path());
            }
        }
    }
    for (owner, stale) in by_owner {
        let lock = if held == Some(owner.as_str()) {
            None
        } else {
            match Lock::try_take(&parent.join(format!(".{owner}.hairfit-lock"))) {
                Ok(Some(lock)) => Some(lock),
                // A live run holds it, or it cannot be taken: leave its files alone.
                _ => continue,
            }
        };
        for dir in stale {
            let _ = std::fs::remove_dir_all(&dir);
        }
        drop(lock);
    }
}

/// Claim `dir` for a command that adds to it rather than replacing it (`hairfit batch`: one
/// sub-directory per item, written by concurrent shards): refused as [`check_out_path`] does,
/// when it holds files hairfit did not write (no marker, and none of `legacy`, names an
/// older hairfit wrote there), and when it is a set of another kind. Creates it with its
/// marker, and removes what killed runs left inside it.
pub fn claim_shared_dir(dir: &Path, command: &str, legacy: &[&str]) -> Result<()> {
    let abs = check_out_path(dir, &format!("{command} writes its results into it"))?;
    let kind = Kind::of_command(command);
    match Marker::read(&abs)? {
        Some(m) if m.kind != kind => {
            return Err(other_kind(dir, &m, command));
        }
        Some(_) => {}
        None => {
            let found = foreign_entries(&abs, None)?;
            let ours = found.iter().any(|n| legacy.contains(&n.as_str()));
            if !ours && !found.is_empty() {
                return Err(Error::Other(format!(
                    "--out {}: the directory holds files hairfit did not write ({}); choose a new or empty directory (e.g. fits/batch) so none of them is overwritten",
                    dir.display(),
                    shown(&found),
                )));
            }
        }
    }
    std::fs::create_dir_all(&abs)
        .map_err(|e| unwritable(dir, format!("the directory {}", abs.display()), &e))?;
    let marker = abs.join(MARKER);
    let wanted = Marker {
        command: command.to_string(),
        kind,
        names: None,
    };
    if !marker.exists() {
        std::fs::write(&marker, wanted.text())
            .map_err(|e| unwritable(dir, format!("the file {}", marker.display()), &e))?;
    }
    heal(&abs, None);
    Ok(())
}

/// The refusal of a set of another kind: `found` marks `dir`, `command` would write it.
fn other_kind(dir: &Path, found: &Marker, command: &str) -> Error {
    let what = match found.kind {
        Kind::Batch => {
            "a hairfit batch directory (its items, summary.csv and .batch/ would be lost)"
        }
        Kind::Compare => "a hairfit compare directory (its fits and compare.json would be lost)",
        Kind::Fit => "a fit's directory",
        Kind::Cost => "a hairfit cost directory",
    };
    Error::Other(format!(
        "--out {}: that is {what}, written by {}; {command} does not replace it. Choose another --out, e.g. fits/NAME",
        dir.display(),
        found.command,
    ))
}

/// Hard-link (or copy) `from` to `to`, recursively for a directory; a link is re-created as a
/// link. The original stays where it is until the old set is removed.
fn carry(from: &Path, to: &Path) -> std::io::Result<()> {
    let meta = std::fs::symlink_metadata(from)?;
    if meta.file_type().is_symlink() {
        #[cfg(unix)]
        return std::os::unix::fs::symlink(std::fs::read_link(from)?, to);
        #[cfg(not(unix))]
        return std::fs::copy(from, to).map(|_| ());
    }
    if meta.is_dir() {
        std::fs::create_dir(to)?;
        for entry in std::fs::read_dir(from)? {
            let entry = entry?;
            carry(&entry.path(), &to.join(entry.file_name()))?;
        }
        return Ok(());
    }
    if !meta.is_file() {
        return Err(std::io::Error::other(
            "it is a device, FIFO or socket, which hairfit does not copy",
        ));
    }
    if std::fs::hard_link(from, to).is_err() {
        std::fs::copy(from, to)?;
    }
    Ok(())
}

/// Create a new staging directory `PARENT/.NAME.hairfit-stage-pPIDnN` (alphanumeric, as
/// [`bookkeeping_owner`] reads a stage's suffix), listed in [`IN_FLIGHT`]
/// before it exists: a memory limit's refusal after creating it (the exit path allocates
/// nothing new and removes what is listed) then cannot leave it behind.
fn create_staging(parent: &Path, name: &str) -> std::io::Result<PathBuf> {
    for n in 0u32.. {
        let path = parent.join(format!(".{name}.hairfit-stage-p{}n{n}", std::process::id()));
        IN_FLIGHT
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(path.clone());
        match std::fs::create_dir(&path) {
            Ok(()) => return Ok(path),
            Err(e) => {
                forget(&IN_FLIGHT, &path);
                if e.kind() != std::io::ErrorKind::AlreadyExists {
                    return Err(e);
                }
            }
        }
    }
    unreachable!("a free staging name among 2^32")
}

/// A held lock: `PARENT/.NAME.hairfit-lock`, removed when released (so a finished run leaves
/// none). The OS releases the lock however the process ends, so a dead pid never holds it.
#[derive(Debug)]
struct Lock {
    file: File,
    path: PathBuf,
}

impl Lock {
    /// Take the lock at `path` without waiting: `None` when another run holds it. A lock file
    /// its holder removed after we opened it is no lock: then the one now at `path` is taken.
    fn try_take(path: &Path) -> std::io::Result<Option<Lock>> {
        loop {
            // What registering the lock allocates is allocated before the file can exist, and
            // the list is held meanwhile: a memory limit's refusal between creating the file
            // and registering it would leave it behind (the exit path removes what is listed).
            let held = path.to_path_buf();
            let mut list = LOCKS_HELD.lock().unwrap_or_else(|e| e.into_inner());
            list.reserve(1);
            let file = std::fs::OpenOptions::new()
                .create(true)
                .truncate(false)
                .read(true)
                .write(true)
                .open(path)?;
            match file.try_lock() {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => return Ok(None),
                Err(std::fs::TryLockError::Error(e)) => return Err(e),
            }
            if same_file(&file, path) {
                list.push(held.clone());
                drop(list);
                return Ok(Some(Lock { file, path: held }));
            }
        }
    }
}

/// Whether the open `file` is the one at `path` now.
fn same_file(file: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (file.metadata(), std::fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = (file, path);
        true
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        // Removed while still held: a run that opened it meanwhile finds it gone and retries.
        let _ = std::fs::remove_file(&self.path);
        forget(&LOCKS_HELD, &self.path);
    }
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
    kind: Kind,
    /// The marker of the set replaced, if it had one.
    old: Option<Marker>,
    /// Sub-directories made by [`OutputSet::sub_dir`] (names in the staging directory).
    subs: Mutex<Vec<String>>,
    published: bool,
    /// Held for the life of the run (released last: fields drop after `drop`).
    _lock: Lock,
}

impl OutputSet {
    /// Lock `dir` and open a staging directory beside it for `command` (e.g. `hairfit fit`).
    /// `inputs` are the files the run reads: none may lie inside `dir`, which is replaced.
    pub fn begin(dir: &Path, command: &str, force: bool, inputs: &[&Path]) -> Result<OutputSet> {
        let abs = check_out_path(dir, "the output directory is replaced as a whole")?;
        let (Some(parent), Some(name)) = (abs.parent(), abs.file_name()) else {
            unreachable!("check_out_path refuses the root");
        };
        let name = name.to_string_lossy().into_owned();
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
        let lock = take_lock(parent, &name, dir)?;
        heal(parent, Some(&name));
        let old = Marker::read(&abs)?;
        let kind = match &old {
            Some(m) if command == "hairfit report" => m.kind,
            _ => Kind::of_command(command),
        };
        match &old {
            Some(m) if m.kind != kind && (m.kind.holds_many() || kind.holds_many() || !force) => {
                let mut e = other_kind(dir, m, command).to_string();
                if !m.kind.holds_many() && !kind.holds_many() {
                    e += ", or pass --force to replace it";
                }
                return Err(Error::Other(e));
            }
            Some(_) => {}
            None => {
                let found = foreign_entries(&abs, None)?;
                // A report deletes nothing there: every file is carried over, and a figure
                // of the user's that the report would redraw is refused at publishing.
                if !found.is_empty() && !force && command != "hairfit report" {
                    return Err(Error::Other(format!(
                        "--out {}: the directory holds files that are not a hairfit result ({}), and it has no {MARKER} marker. Choose an empty or new directory, or pass --force to write the result there (those files are kept)",
                        dir.display(),
                        shown(&found),
                    )));
                }
            }
        }
        let staging = create_staging(parent, &name).map_err(|e| {
            let what = format!("a staging directory in {}", parent.display());
            unwritable(dir, what, &e)
        })?;
        // The staged files are synced together in `publish`, before the set becomes visible.
        crate::atomic::defer_sync_under(&staging);
        Ok(OutputSet {
            dir: dir.to_path_buf(),
            target: abs.clone(),
            staging,
            command: command.to_string(),
            kind,
            old,
            subs: Mutex::new(Vec::new()),
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

    /// `e` with the staging directory's path replaced by the `--out` the user typed (a full
    /// disk or a read-only file is reported where the user looks), saying that the previous
    /// set is unchanged.
    pub fn explain(&self, e: Error) -> Error {
        let text = e.to_string();
        let staging = self.staging.display().to_string();
        if !text.contains(&staging) {
            return e;
        }
        Error::Other(format!(
            "--out {}: {}; nothing was published, and what --out held before is unchanged",
            self.dir.display(),
            text.replace(&staging, &self.dir.display().to_string())
        ))
    }

    /// Create the sub-directory `name` of the set (e.g. `hairfit compare`'s `marschner/`)
    /// with a marker of its own (a fit's, so `hairfit report` redraws it). It is published with
    /// the set: it has no lock or staging directory of its own, and so leaves none inside it.
    pub fn sub_dir(&self, name: &str) -> Result<PathBuf> {
        let sub = self.staging.join(name);
        std::fs::create_dir(&sub).map_err(|e| self.explain(Error::io(&sub, e)))?;
        self.subs
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(name.to_string());
        Ok(sub)
    }

    /// Carry `names` of the current set into the new one unchanged (hard links where possible,
    /// so a large `curves.csv` is not copied), e.g. when a report is redrawn.
    pub fn keep(&self, names: &[&str]) -> Result<()> {
        for name in names {
            let (from, to) = (self.target.join(name), self.staging.join(name));
            if std::fs::hard_link(&from, &to).is_err() {
                std::fs::copy(&from, &to).map_err(|e| self.explain(Error::io(&from, e)))?;
            }
        }
        Ok(())
    }

    /// Carry every file hairfit wrote into the current set into the new one except those
    /// `redrawn` names (the run makes them anew, or they are stale): e.g. `hairfit report`
    /// keeps the fit's files and redraws the figures. The user's own files and folders are
    /// carried over by [`OutputSet::publish`].
    pub fn keep_all_but(&self, redrawn: impl Fn(&str) -> bool) -> Result<()> {
        let Some(marker) = &self.old else {
            return Ok(());
        };
        let entries = match std::fs::read_dir(&self.target) {
            Ok(e) => e,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
            Err(e) => return Err(Error::io(&self.dir, e)),
        };
        let mut names = Vec::new();
        for entry in entries {
            let entry = entry.map_err(|e| Error::io(&self.dir, e))?;
            let name = entry.file_name().to_string_lossy().into_owned();
            if name != MARKER
                && !redrawn(&name)
                && entry.path().is_file()
                && marker.owns(&self.target, &name)
            {
                names.push(name);
            }
        }
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        self.keep(&names)
    }

    /// Write the marker of `dir` (the staging directory or a sub-directory of it): the names
    /// now in it are hairfit's.
    fn seal(&self, dir: &Path, kind: Kind) -> Result<()> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .map_err(|e| Error::io(dir, e))?
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n != MARKER)
            .collect();
        names.sort();
        let marker = Marker {
            command: self.command.clone(),
            kind,
            names: Some(names),
        };
        let path = dir.join(MARKER);
        let mut file = File::create(&path).map_err(|e| Error::io(&path, e))?;
        file.write_all(marker.text().as_bytes())
            .map_err(|e| Error::io(&path, e))?;
        // Synced with the set's other files before publication (or now, when not deferred).
        if !crate::atomic::note_deferred(&path) {
            file.sync_all().map_err(|e| Error::io(&path, e))?;
        }
        Ok(())
    }

    /// Carry what the user put into the old set's directory `old` (and into its marked
    /// sub-directories the new set also has) into the new set's `new`.
    fn carry_over(&self, old: &Path, new: &Path, marker: Option<&Marker>) -> Result<()> {
        for name in foreign_entries(old, marker)? {
            let (from, to) = (old.join(&name), new.join(&name));
            if std::fs::symlink_metadata(&to).is_ok() {
                return Err(Error::Other(format!(
                    "--out {}: {} was not written by hairfit, and the new result writes one of that name; move it out of the directory, or choose another --out. Nothing was replaced",
                    self.dir.display(),
                    from.display()
                )));
            }
            carry(&from, &to).map_err(|e| {
                Error::Other(format!(
                    "--out {}: {} was not written by hairfit and could not be carried into the new result ({e}); move it out of the directory, or choose another --out. Nothing was replaced",
                    self.dir.display(),
                    from.display()
                ))
            })?;
        }
        let Some(marker) = marker else {
            return Ok(());
        };
        let entries = std::fs::read_dir(old).map_err(|e| Error::io(old, e))?;
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            let (old_sub, new_sub) = (old.join(&name), new.join(&name));
            if marker.owns(old, &name) && old_sub.is_dir() && new_sub.is_dir() {
                let sub_marker = Marker::read(&old_sub)?;
                if sub_marker.is_some() {
                    self.carry_over(&old_sub, &new_sub, sub_marker.as_ref())?;
                }
            }
        }
        Ok(())
    }

    /// Seal the new set, carry the user's files over from the old one, swap the new set in
    /// place of the old one, then remove the old one.
    pub fn publish(mut self) -> Result<()> {
        let subs = std::mem::take(&mut *self.subs.lock().unwrap_or_else(|e| e.into_inner()));
        for sub in &subs {
            self.seal(&self.staging.join(sub), Kind::Fit)
                .map_err(|e| self.explain(e))?;
        }
        self.seal(&self.staging, self.kind)
            .map_err(|e| self.explain(e))?;
        crate::atomic::sync_deferred(&self.staging).map_err(|e| self.explain(e))?;
        if self.target.is_dir() {
            self.carry_over(&self.target, &self.staging, self.old.as_ref())?;
        }
        let old = swap_in(&self.staging, &self.target).map_err(|e| self.explain(e))?;
        self.published = true;
        forget(&IN_FLIGHT, &self.staging);
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
            forget(&IN_FLIGHT, &self.staging);
        }
        crate::atomic::forget_deferred(&self.staging);
    }
}

/// Take `parent/.NAME.hairfit-lock` without waiting; when another run holds it, say which.
fn take_lock(parent: &Path, name: &str, dir: &Path) -> Result<Lock> {
    let path = parent.join(format!(".{name}.hairfit-lock"));
    let lock = Lock::try_take(&path)
        .map_err(|e| unwritable(dir, format!("the lock file {}", path.display()), &e))?;
    let Some(mut lock) = lock else {
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
    };
    // Who holds it, for the message a second run prints.
    let _ = lock.file.set_len(0);
    let _ = writeln!(
        lock.file,
        "pid {}, {}",
        std::process::id(),
        std::env::args().collect::<Vec<_>>().join(" ")
    );
    Ok(lock)
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
    let mut aside = staging.as_os_str().to_owned();
    aside.push(".old");
    let aside = PathBuf::from(aside);
    std::fs::rename(dir, &aside).map_err(|e| Error::io(dir, e))?;
    if let Err(e) = std::fs::rename(staging, dir) {
        let _ = std::fs::rename(&aside, dir);
        return Err(Error::io(dir, e));
    }
    Ok(Some(aside))
}

#[cfg(test)]
mod tests;
