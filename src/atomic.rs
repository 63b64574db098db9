//! Atomic file output: results are written to a temporary file beside the target and renamed into
//! place only when complete, so an error or an interruption never leaves a half-written file.
//! A target that is a link is resolved first (the file it names is replaced, the link stays); a
//! device, FIFO or socket (`/dev/null`, a pipe) is written in place, never replaced.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

use crate::error::{Error, Result};

/// Temporary files being written right now: a process ending by a signal runs no destructors,
/// so a signal handler removes them with [`remove_in_flight`] before it exits.
static IN_FLIGHT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Set by a signal handler that is about to remove the partial outputs and exit.
static STOPPING: AtomicBool = AtomicBool::new(false);

/// For a signal handler, before it removes the partial outputs: no output is started from now
/// on. A writer thread starting one would otherwise create its directory (a staging directory
/// just removed) and a file in it again behind the removal.
pub fn stop_writing() {
    STOPPING.store(true, Ordering::SeqCst);
}

/// True once a signal handler has begun removing the partial outputs: it is about to exit with
/// the signal's code, and errors the removal causes elsewhere (a file vanished from under a
/// writer) are its effect, not the run's outcome.
pub fn stopping() -> bool {
    STOPPING.load(Ordering::SeqCst)
}

fn refuse_when_stopping(path: &Path) -> Result<()> {
    if STOPPING.load(Ordering::SeqCst) {
        return Err(Error::Other(format!(
            "{}: not written: the run is being stopped",
            path.display()
        )));
    }
    Ok(())
}

/// Remove every temporary file still being written (for a signal handler that then exits).
pub fn remove_in_flight() {
    let Some(list) = lock_briefly(&IN_FLIGHT) else {
        return;
    };
    for p in list.iter() {
        let _ = std::fs::remove_file(p);
    }
}

/// `m` locked, waiting at most about 100 ms: the thread that ends the run (a signal, an
/// allocation refused) may have interrupted the holder, which then never releases it.
pub fn lock_briefly<T>(m: &Mutex<T>) -> Option<std::sync::MutexGuard<'_, T>> {
    for _ in 0..100 {
        match m.try_lock() {
            Ok(g) => return Some(g),
            Err(std::sync::TryLockError::Poisoned(p)) => return Some(p.into_inner()),
            Err(std::sync::TryLockError::WouldBlock) => {
                std::thread::sleep(std::time::Duration::from_millis(1))
            }
        }
    }
    None
}

/// Registers a temporary file in [`IN_FLIGHT`] for as long as it lives.
struct InFlight(PathBuf);

impl InFlight {
    fn new(path: &Path) -> InFlight {
        let mut list = IN_FLIGHT.lock().unwrap_or_else(|e| e.into_inner());
        list.push(path.to_path_buf());
        InFlight(path.to_path_buf())
    }
}

impl Drop for InFlight {
    fn drop(&mut self) {
        let mut list = IN_FLIGHT.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(i) = list.iter().position(|p| *p == self.0) {
            list.swap_remove(i);
        }
    }
}

/// Where an output is written.
#[derive(Debug, PartialEq, Eq)]
enum Destination {
    /// A regular file, or none yet, at this path (links resolved): replaced by a rename.
    Replace(PathBuf),
    /// A device, FIFO or socket: written in place as a shell's `>` would, since renaming a file
    /// over it would replace `/dev/null` itself, or the pipe a reader waits on.
    InPlace,
}

/// Links followed at most, as the kernel's own limit (ELOOP).
const MAX_LINKS: usize = 40;

fn destination(path: &Path) -> Destination {
    let is_link = |p: &Path| std::fs::symlink_metadata(p).is_ok_and(|m| m.file_type().is_symlink());
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() || m.is_dir() => {
            // A directory is left to fail as before; a linked file is replaced where it lies.
            let resolved = is_link(path).then(|| path.canonicalize().ok()).flatten();
            Destination::Replace(resolved.unwrap_or_else(|| path.to_path_buf()))
        }
        Ok(_) => Destination::InPlace,
        Err(_) => {
            // Nothing there yet, or a dangling link: the link's last target is the new file.
            let mut target = path.to_path_buf();
            for _ in 0..MAX_LINKS {
                if !is_link(&target) {
                    break;
                }
                let Ok(next) = std::fs::read_link(&target) else {
                    break;
                };
                target = match target.parent() {
                    Some(dir) if next.is_relative() => dir.join(next),
                    _ => next,
                };
            }
            Destination::Replace(target)
        }
    }
}

/// True when `path` exists and is not a regular file or a link to one: a device, a FIFO or a
/// socket, written in place (see [`write_atomically`]).
pub fn is_special_file(path: &Path) -> bool {
    destination(path) == Destination::InPlace
}

/// The check of a command that writes a CSV and a companion file beside it (`synth`, `trace`):
/// `--output` must end in `.csv` and be no device, FIFO or socket. `command` and `companion`
/// ("its truth file FILE.truth.json") word the message.
pub fn require_csv_pair(output: &Path, command: &str, companion: &str) -> crate::error::Result<()> {
    let is_csv = output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let why = if !is_csv {
        format!(
            "name the file FILE.csv (the loader picks the format by extension; {companion} goes \
             beside it)"
        )
    } else if is_special_file(output) {
        format!(
            "is a device, FIFO or socket; {command} writes the CSV and {companion} beside each \
             other, so --output names a file"
        )
    } else {
        return Ok(());
    };
    Err(crate::error::Error::Other(format!(
        "--output {}: {why}",
        output.display()
    )))
}

/// An error about the staged temporary `tmp`, worded about the file the user asked for.
pub fn name_target(e: crate::error::Error, tmp: &Path, target: &Path) -> crate::error::Error {
    let text = e.to_string();
    let tmp = tmp.display().to_string();
    if text.contains(&tmp) {
        crate::error::Error::Other(text.replace(&tmp, &target.display().to_string()))
    } else {
        e
    }
}

/// Write `path` atomically: `fill` writes the whole content; on success the temporary file is
/// renamed over `path`, on error it is removed and `path` is left untouched. A `path` that is a
/// link is resolved and the file it names replaced; a device, FIFO or socket (`/dev/null`, a
/// pipe) is written in place, as it cannot be replaced atomically (an error then leaves what was
/// written, as on standard output).
pub fn write_atomically<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> Result<()>,
{
    let target = match destination(path) {
        Destination::Replace(target) => target,
        Destination::InPlace => return write_in_place(path, fill),
    };
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    refuse_when_stopping(path)?;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    refuse_when_stopping(path)?;
    remove_dead_temporaries(&target);
    let mut staged = StagedFiles::new();
    let tmp = staged.stage_resolved(target.clone());
    // Inside an output set's staging directory the set's publication syncs it ([`sync_deferred`]).
    let deferred = is_deferred(&target);
    {
        // The name is this process's alone (its pid and a counter); a file already there is a
        // leftover of a dead process that had the same pid, so it is overwritten.
        let file = std::fs::File::create(&tmp).map_err(|e| Error::io(dir, e))?;
        let mut out = BufWriter::new(&file);
        fill(&mut out)?;
        out.flush().map_err(|e| Error::io(path, e))?;
        drop(out);
        if deferred {
            start_writeback(&file);
        } else {
            file.sync_all().map_err(|e| Error::io(path, e))?;
        }
    }
    staged.publish().map_err(|e| match e {
        Error::Io { source, .. } => Error::io(path, source),
        other => other,
    })?;
    // The set was published (or abandoned) meanwhile: sync here, as without deferral.
    if deferred && !note_deferred(&target) {
        sync_file(&target)?;
    }
    Ok(())
}

/// Output sets' staging directories whose files are synced together when the set is published
/// ([`defer_sync_under`]), each with the files written into it since.
static DEFERRED: Mutex<Vec<(PathBuf, Vec<PathBuf>)>> = Mutex::new(Vec::new());

/// From now on [`write_atomically`] leaves the fsync of files under `dir` (an output set's
/// staging directory, never visible as a result) to [`sync_deferred`], which the set calls
/// before it is published: each fsync waits for the disk (~4 ms here), and a report's dozen
/// files synced one after another cost ~55 ms where syncing them together costs ~6 ms. Every
/// file is still on disk before the set's publishing rename.
pub fn defer_sync_under(dir: &Path) {
    let mut list = DEFERRED.lock().unwrap_or_else(|e| e.into_inner());
    list.push((dir.to_path_buf(), Vec::new()));
}

/// Whether `target` lies under a directory of [`defer_sync_under`].
fn is_deferred(target: &Path) -> bool {
    let list = DEFERRED.lock().unwrap_or_else(|e| e.into_inner());
    list.iter().any(|(dir, _)| target.starts_with(dir))
}

/// Record `target` (written, not synced) for its set's [`sync_deferred`]; false when no
/// directory of [`defer_sync_under`] holds it any more.
pub(crate) fn note_deferred(target: &Path) -> bool {
    let mut list = DEFERRED.lock().unwrap_or_else(|e| e.into_inner());
    match list.iter_mut().find(|(dir, _)| target.starts_with(dir)) {
        Some((_, files)) => {
            files.push(target.to_path_buf());
            true
        }
        None => false,
    }
}

/// Start writing a file whose fsync is deferred to its set's publication back to disk now
/// (`sync_file_range`, which does not wait for it), so that fsync finds most of it written:
/// the 100k fit's curves.csv (24 MB) is written while the report is drawn, and its fsync at
/// the publication took 13 ms of the command's wall time before. A hint only: errors are left
/// to the fsync.
fn start_writeback(file: &std::fs::File) {
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        // SAFETY: a plain syscall on an open descriptor; it reads no memory of ours.
        unsafe {
            libc::sync_file_range(file.as_raw_fd(), 0, 0, libc::SYNC_FILE_RANGE_WRITE);
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = file;
}

/// fsync the file at `path` (a file no longer there is not part of the set: nothing to sync).
fn sync_file(path: &Path) -> Result<()> {
    match std::fs::File::open(path) {
        Ok(f) => f.sync_all().map_err(|e| Error::io(path, e)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(Error::io(path, e)),
    }
}

/// Stop deferring under `dir` and fsync every file written there since [`defer_sync_under`],
/// one after another on this thread; the first error names its file. Not on threads of their
/// own: under a memory cap a new thread of the Python module can abort the interpreter in the
/// C library ("cannot allocate memory for thread-local data"), which no Rust code can catch.
pub fn sync_deferred(dir: &Path) -> Result<()> {
    let mut files = forget_deferred(dir);
    files.sort();
    files.dedup();
    files.iter().try_for_each(|f| sync_file(f))
}

/// Stop deferring under `dir` (a set dropped unpublished); the files written there since.
pub fn forget_deferred(dir: &Path) -> Vec<PathBuf> {
    let mut list = DEFERRED.lock().unwrap_or_else(|e| e.into_inner());
    match list.iter().position(|(d, _)| d == dir) {
        Some(i) => list.swap_remove(i).1,
        None => Vec::new(),
    }
}

/// Write a device, FIFO or socket through an ordinary open (no create, no truncation, no fsync:
/// a pipe refuses fsync).
fn write_in_place<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> Result<()>,
{
    refuse_when_stopping(path)?;
    let file = std::fs::OpenOptions::new()
        .write(true)
        .open(path)
        .map_err(|e| Error::io(path, e))?;
    let mut out = BufWriter::new(file);
    fill(&mut out)?;
    out.flush().map_err(|e| Error::io(path, e))
}

/// Write `files` (target, content) together: every target is replaced, or none is (e.g. an
/// export's JSON and the script beside it must come from the same fit). Errors name the target,
/// not its temporary file.
pub fn write_together(files: &[(&Path, &[u8])]) -> Result<()> {
    let mut staged = StagedFiles::new();
    for (target, content) in files {
        if let Some(dir) = target.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        let tmp = staged.stage(target)?;
        let named = |e: std::io::Error| {
            Error::Other(format!(
                "{}: {e}; none of {} was written",
                target.display(),
                files
                    .iter()
                    .map(|(t, _)| t.display().to_string())
                    .collect::<Vec<_>>()
                    .join(" and ")
            ))
        };
        let mut file = std::fs::File::create(&tmp).map_err(named)?;
        file.write_all(content)
            .and_then(|()| file.sync_all())
            .map_err(named)?;
    }
    staged.publish()
}

/// Files written under temporary names beside their targets, then published together by
/// [`StagedFiles::publish`]: every target is replaced, or (on an error) none is. For files that
/// must agree, e.g. a synthesized CSV and its truth sidecar.
#[derive(Default)]
pub struct StagedFiles {
    /// (temporary path, target), in publishing order.
    pairs: Vec<(PathBuf, PathBuf)>,
    _in_flight: Vec<InFlight>,
}

/// A fresh `.hairfit-NAME-PID-N.tmp` path beside `target` (`what` tells its role apart).
fn temporary_beside(target: &Path, what: &str) -> PathBuf {
    static COUNT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    target.with_file_name(format!(
        ".hairfit-{name}-{}-{n}{what}.tmp",
        std::process::id()
    ))
}

/// Remove the temporary files of `target` ([`temporary_beside`]) that a process no longer
/// running left beside it: a SIGKILL or a power cut runs no cleanup, and nothing else would
/// ever remove them. Files of a live process (or of a pid this one cannot tell) are left.
fn remove_dead_temporaries(target: &Path) {
    let (Some(dir), Some(name)) = (target.parent(), target.file_name()) else {
        return;
    };
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let prefix = format!(".hairfit-{}-", name.to_string_lossy());
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(pid) = file_name
            .to_str()
            .and_then(|n| n.strip_prefix(&prefix))
            .filter(|rest| rest.ends_with(".tmp"))
            .and_then(|rest| rest.split_once('-'))
            .and_then(|(pid, _)| pid.parse::<u32>().ok())
        else {
            continue;
        };
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        if is_file && !process_alive(pid) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// False only when no process `pid` exists (`kill(pid, 0)` fails with ESRCH).
fn process_alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return true;
    };
    // SAFETY: signal 0 only checks that the process exists; nothing is sent.
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
}

impl StagedFiles {
    pub fn new() -> StagedFiles {
        StagedFiles::default()
    }

    /// Where to write `target` (with any writer, atomic or not) before [`StagedFiles::publish`].
    /// A linked target is resolved (the file it names is replaced); a device, FIFO or socket is
    /// refused, as files published together cannot go to one.
    pub fn stage(&mut self, target: &Path) -> Result<PathBuf> {
        let Destination::Replace(resolved) = destination(target) else {
            return Err(Error::Other(format!(
                "{}: is a device, FIFO or socket; these outputs are written together, so each \
                 must be a file",
                target.display()
            )));
        };
        remove_dead_temporaries(&resolved);
        Ok(self.stage_resolved(resolved))
    }

    /// [`StagedFiles::stage`] for a target already resolved to a file path.
    fn stage_resolved(&mut self, target: PathBuf) -> PathBuf {
        let tmp = temporary_beside(&target, "");
        self._in_flight.push(InFlight::new(&tmp));
        self.pairs.push((tmp.clone(), target));
        tmp
    }

    /// Rename every staged file onto its target. If one rename fails, the targets already
    /// replaced get their old content back (kept as hard links until the end) and the error is
    /// returned.
    pub fn publish(mut self) -> Result<()> {
        let mut backups: Vec<Option<PathBuf>> = Vec::new();
        for (_, target) in &self.pairs {
            let backup = temporary_beside(target, ".old");
            // Listed before it exists, as every temporary is: the exit path removes what is
            // listed and may not allocate to learn of more.
            let listed = InFlight::new(&backup);
            let kept = std::fs::hard_link(target, &backup).is_ok();
            if kept {
                self._in_flight.push(listed);
            }
            backups.push(kept.then_some(backup));
        }
        let mut result = Ok(());
        for (i, (tmp, target)) in self.pairs.iter().enumerate() {
            if let Err(e) = std::fs::rename(tmp, target) {
                for (j, (_, done)) in self.pairs.iter().enumerate().take(i) {
                    match &backups[j] {
                        Some(b) => {
                            let _ = std::fs::rename(b, done);
                        }
                        None => {
                            let _ = std::fs::remove_file(done);
                        }
                    }
                }
                result = Err(Error::io(target, e));
                break;
            }
        }
        for b in backups.iter().flatten() {
            let _ = std::fs::remove_file(b);
        }
        result
    }
}

impl Drop for StagedFiles {
    fn drop(&mut self) {
        for (tmp, _) in &self.pairs {
            let _ = std::fs::remove_file(tmp);
        }
    }
}

/// True when writing `output` would replace the existing file `input`: both resolved through
/// links and `..`. `output` need not exist yet (its directory is resolved instead); an `input`
/// that does not exist cannot be replaced.
pub fn same_file(input: &Path, output: &Path) -> bool {
    let Ok(input) = input.canonicalize() else {
        return false;
    };
    let output = output.canonicalize().ok().or_else(|| {
        let dir = match output.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        Some(dir.canonicalize().ok()?.join(output.file_name()?))
    });
    output.is_some_and(|o| o == input)
}

/// `flag` (e.g. `--output`) must name a file: an existing directory, or a path ending in `/`,
/// is refused before any work (the rename at the end would fail with "Not a directory");
/// `example` is a file name for the hint (`eval.csv`).
pub fn refuse_directory_output(flag: &str, out: &Path, example: &str) -> Result<()> {
    let text = out.as_os_str().to_string_lossy();
    if out.is_dir() || text.ends_with('/') || text.ends_with(std::path::MAIN_SEPARATOR) {
        let dir = text.trim_end_matches(['/', std::path::MAIN_SEPARATOR]);
        return Err(Error::Other(format!(
            "{flag} {text}: that is a directory; {flag} names the file to write, \
             e.g. {flag} {dir}/{example}"
        )));
    }
    Ok(())
}

/// Refuse to write `output` (the option `output_flag`) over one of the files the command reads
/// (`inputs`: option and path): the run would destroy its own input.
pub fn refuse_replacing_inputs(
    output_flag: &str,
    output: &Path,
    inputs: &[(&str, &Path)],
) -> Result<()> {
    for (flag, input) in inputs {
        if same_file(input, output) {
            return Err(Error::Other(format!(
                "{output_flag} {} would replace {flag} {}, which this command reads: write the \
                 output under another name",
                output.display(),
                input.display()
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_no_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.csv");
        let err = write_atomically(&target, |w| {
            w.write_all(b"partial").map_err(|e| Error::io("x", e))?;
            Err(Error::Other("boom".into()))
        });
        assert!(err.is_err());
        assert!(!target.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn staged_files_publish_all_or_none() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.csv"), dir.path().join("a.truth.json"));
        std::fs::write(&a, "old a").unwrap();
        // The second target is a directory: its rename fails, so the first is restored.
        std::fs::create_dir(&b).unwrap();
        let mut staged = StagedFiles::new();
        std::fs::write(staged.stage(&a).unwrap(), "new a").unwrap();
        std::fs::write(staged.stage(&b).unwrap(), "new b").unwrap();
        assert!(staged.publish().is_err());
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old a");
        // Nothing else left: the old file, the directory in the way, no temporaries.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
        std::fs::remove_dir(&b).unwrap();
        let mut staged = StagedFiles::new();
        std::fs::write(staged.stage(&a).unwrap(), "new a").unwrap();
        std::fs::write(staged.stage(&b).unwrap(), "new b").unwrap();
        staged.publish().unwrap();
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new a");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "new b");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    #[test]
    fn successful_write_replaces_the_target() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.csv");
        std::fs::write(&target, "old").unwrap();
        write_atomically(&target, |w| {
            w.write_all(b"new").map_err(|e| Error::io("x", e))
        })
        .unwrap();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
    }
}
