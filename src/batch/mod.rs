//! `hairfit batch`: many fits from one manifest. A process runs one deterministic shard of the
//! items (so a scheduler's array job runs the shards), skips items already finished (so a
//! pre-empted job resumes), and `--merge` gathers every item into one summary table and page.

pub mod manifest;
pub mod merge;
pub mod shard;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::files::Verdict;
pub use manifest::{Item, Manifest};
pub use shard::Shard;

/// Where a batch writes the record of how each item was last run.
const STAMP_DIR: &str = ".batch";

/// What `hairfit batch` names its output directory's marker after.
pub const COMMAND: &str = "hairfit batch";

/// Make `out` the batch's output directory (see [`crate::outdir::claim_shared_dir`]): never
/// `.`, a file, or a directory of the user's own files. A directory holding `.batch` was made
/// by a batch before the marker existed.
pub fn claim_out_dir(out: &Path) -> Result<()> {
    crate::outdir::claim_shared_dir(out, COMMAND, &[STAMP_DIR])
}

/// Which data file an item's result was fitted to: its canonical path (the same from any
/// current directory), size and modification time. Size and time, not a content hash: a
/// resubmitted array job checks every item, and hashing gigabytes of data each time would
/// cost more than small fits; an instrument rewriting a file changes its time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DataIdentity {
    pub path: String,
    pub size: u64,
    /// Nanoseconds since the Unix epoch (0 where the file system keeps no time).
    pub modified_ns: u64,
}

impl DataIdentity {
    /// The identity of `path` now, if it can be read.
    pub fn of(path: &Path) -> Option<DataIdentity> {
        let canonical = path.canonicalize().ok()?;
        let meta = std::fs::metadata(&canonical).ok()?;
        let modified_ns = meta
            .modified()
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
        Some(DataIdentity {
            path: canonical.display().to_string(),
            size: meta.len(),
            modified_ns,
        })
    }
}

/// `DIR/.batch/NAME.json`: how an item was last run (its options and data file) and, when it
/// ended in an error before or after writing a result, the error. A re-run skips the item only
/// while the manifest asks for the same fit of the same, unchanged data; `--merge` shows the
/// error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ItemRecord {
    /// The `hairfit fit` options (without the data path and `--out`).
    pub options: Vec<String>,
    /// The data file as it was when the item ran (absent when it could not be read).
    pub data: Option<DataIdentity>,
    /// Why the last run of the item failed, if it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

impl ItemRecord {
    fn path(out: &Path, name: &str) -> PathBuf {
        out.join(STAMP_DIR).join(format!("{name}.json"))
    }

    /// The record of `name`, if there is a readable one (an older format reads as none).
    pub fn read(out: &Path, name: &str) -> Option<ItemRecord> {
        let text = std::fs::read_to_string(Self::path(out, name)).ok()?;
        serde_json::from_str(&text).ok()
    }

    fn write(&self, out: &Path, name: &str) -> Result<()> {
        let path = Self::path(out, name);
        write_atomically(&path, |w| {
            serde_json::to_writer_pretty(&mut *w, self)
                .map_err(|e| Error::Other(format!("{}: {e}", path.display())))
        })
    }

    /// The error of `item`'s last run, if its record is of the item's current options.
    pub fn error_of(out: &Path, item: &Item) -> Option<String> {
        ItemRecord::read(out, &item.name)
            .filter(|r| r.options == item.options())
            .and_then(|r| r.error)
    }
}

/// What happened to one item of this shard.
#[derive(Debug, Clone, PartialEq)]
pub enum ItemOutcome {
    /// Fitted now: the verdict, the fit's status (`converged`, …) and the report's line (where
    /// it is), as `hairfit fit` prints them.
    Fitted {
        verdict: Verdict,
        status: String,
        report: String,
    },
    /// A finished result of the same fit of the same data was already there: its verdict.
    Skipped(Verdict),
    /// The fit could not run (bad data file, …), or its report could not be drawn: the error.
    Failed(String),
    /// Ctrl-C/SIGTERM stopped the item; the batch stops after it.
    Interrupted,
}

impl ItemOutcome {
    /// The item's verdict, if it has a result.
    pub fn verdict(&self) -> Option<Verdict> {
        match self {
            ItemOutcome::Fitted { verdict, .. } | ItemOutcome::Skipped(verdict) => Some(*verdict),
            ItemOutcome::Failed(_) => None,
            ItemOutcome::Interrupted => Some(Verdict::Interrupted),
        }
    }

    /// An error, or a result whose verdict is `failed`.
    pub fn failed(&self) -> bool {
        matches!(self, ItemOutcome::Failed(_)) || self.verdict() == Some(Verdict::Failed)
    }
}

/// The shard's run: every item it owns with its outcome.
#[derive(Debug, Clone)]
pub struct BatchRun {
    pub shard: Shard,
    pub outcomes: Vec<(String, ItemOutcome)>,
    /// The shard's items a signal kept from starting (each item that ran is complete).
    pub not_run: Vec<String>,
}

impl BatchRun {
    pub fn count(&self, pred: impl Fn(&ItemOutcome) -> bool) -> usize {
        self.outcomes.iter().filter(|(_, o)| pred(o)).count()
    }

    /// One line for the end of the run.
    pub fn summary_line(&self) -> String {
        format!(
            "shard {}: {} items, {} fitted, {} skipped (already finished), {} failed{}",
            self.shard,
            self.outcomes.len(),
            self.count(|o| matches!(o, ItemOutcome::Fitted { .. })),
            self.count(|o| matches!(o, ItemOutcome::Skipped(_))),
            self.count(ItemOutcome::failed),
            match (self.interrupted(), self.not_run.len()) {
                (false, _) => String::new(),
                (true, 0) => ", interrupted".into(),
                (true, n) => format!(", interrupted ({n} not started)"),
            }
        )
    }

    /// A signal stopped the shard: an item was interrupted, or some were never started. A
    /// signal after the last item had finished leaves every result complete: not interrupted.
    pub fn interrupted(&self) -> bool {
        !self.not_run.is_empty()
            || self
                .outcomes
                .iter()
                .any(|(_, o)| matches!(o, ItemOutcome::Interrupted))
    }

    /// The names of the items that failed.
    pub fn failed_names(&self) -> Vec<&str> {
        self.names_where(ItemOutcome::failed)
    }

    /// The names of the items whose verdict is poor_fit or undetermined (`--strict` refuses
    /// them).
    pub fn not_good_names(&self) -> Vec<&str> {
        self.names_where(|o| matches!(o.verdict(), Some(Verdict::PoorFit | Verdict::Undetermined)))
    }

    fn names_where(&self, keep: impl Fn(&ItemOutcome) -> bool) -> Vec<&str> {
        self.outcomes
            .iter()
            .filter(|(_, o)| keep(o))
            .map(|(n, _)| n.as_str())
            .collect()
    }
}

/// How a shard runs: `strict` is `hairfit batch --strict` (every item gets `--strict`),
/// `rerun` is `--force` (fit every item again, finished or not).
#[derive(Debug, Clone, Copy, Default)]
pub struct RunOptions {
    pub strict: bool,
    pub rerun: bool,
}

/// The verdict of `out/name`'s finished result of `item`, if it has one: the record says the
/// same options and the same, unchanged data file, fit.json holds a verdict other than failed
/// or interrupted (those run again), and none of the fit's files is missing (a user who deleted
/// params.json or the report gets them back).
fn finished_verdict(out: &Path, item: &Item) -> Option<Verdict> {
    let record = ItemRecord::read(out, &item.name)?;
    let same = record.error.is_none()
        && record.options == item.options()
        && record.data.is_some()
        && record.data == DataIdentity::of(Path::new(&item.argv[0]));
    if !same {
        return None;
    }
    let dir = out.join(&item.name);
    let fit = crate::files::FitJson::load(&dir.join("fit.json")).ok()?;
    let curves = fit.options.curves != crate::files::curves::CurvesMode::None;
    let complete = ["params.json", "index.html"]
        .iter()
        .chain(curves.then_some(&"curves.csv"))
        .all(|name| dir.join(name).is_file());
    Some(fit.verdict).filter(|v| complete && !matches!(v, Verdict::Failed | Verdict::Interrupted))
}

/// Run this shard's items of `manifest` into `out/NAME`, one after another (each fit uses every
/// core). `on_item` hears each item as it ends (for progress lines).
pub fn run_batch(
    manifest: &Manifest,
    out: &Path,
    shard: Shard,
    options: RunOptions,
    cancel: Option<Arc<AtomicBool>>,
    mut on_item: impl FnMut(&Item, &ItemOutcome),
) -> Result<BatchRun> {
    manifest.check_channels(shard)?;
    claim_out_dir(out)?;
    let mut outcomes = Vec::new();
    let mut not_run = Vec::new();
    let mut stopped = false;
    for (i, item) in manifest.items.iter().enumerate() {
        if !shard.owns(i) {
            continue;
        }
        stopped = stopped || cancel.as_ref().is_some_and(|c| c.load(Ordering::SeqCst));
        if stopped {
            not_run.push(item.name.clone());
            continue;
        }
        let finished = if options.rerun {
            None
        } else {
            finished_verdict(out, item)
        };
        let outcome = match finished {
            Some(verdict) => ItemOutcome::Skipped(verdict),
            None => run_item(item, out, options.strict, cancel.clone()),
        };
        on_item(item, &outcome);
        stopped = matches!(outcome, ItemOutcome::Interrupted);
        outcomes.push((item.name.clone(), outcome));
    }
    Ok(BatchRun {
        shard,
        outcomes,
        not_run,
    })
}

fn run_item(item: &Item, out: &Path, strict: bool, cancel: Option<Arc<AtomicBool>>) -> ItemOutcome {
    let dir = out.join(&item.name);
    // Taken before the fit: a file rewritten while it runs then differs next time.
    let data = DataIdentity::of(Path::new(&item.argv[0]));
    let result = item.fit_args(&dir, strict).and_then(|a| {
        crate::cli::fit::fit_command(&a.data, &a.load, &a.fit, &a.out, cancel.clone())
    });
    let record = |error: Option<String>| ItemRecord {
        options: item.options().to_vec(),
        data: data.clone(),
        error,
    };
    let failed = |message: String| {
        let message = manifest::as_manifest_words(&message);
        match record(Some(message.clone())).write(out, &item.name) {
            Ok(()) => ItemOutcome::Failed(message),
            Err(e) => ItemOutcome::Failed(format!("{message} (and its record: {e})")),
        }
    };
    let run = match result {
        Err(e) => return failed(e.to_string()),
        Ok(run) => run,
    };
    let verdict = run.outcome.json.verdict;
    if verdict == Verdict::Interrupted {
        // Its best so far is written; the record says which fit it was (it runs again).
        let _ = record(None).write(out, &item.name);
        return ItemOutcome::Interrupted;
    }
    match record(None).write(out, &item.name) {
        Ok(()) => ItemOutcome::Fitted {
            verdict,
            status: run.outcome.json.status.as_str().to_string(),
            report: run.report_line(&dir).trim_end().to_string(),
        },
        Err(e) => ItemOutcome::Failed(format!("fitted, but {e}")),
    }
}
