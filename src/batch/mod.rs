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
pub use manifest::{Item, Manifest};
pub use shard::Shard;

/// Where a batch writes the record of how each finished item was run.
const STAMP_DIR: &str = ".batch";

/// `DIR/.batch/NAME.json`: the arguments an item's result was made with, so a re-run skips it
/// only while the manifest still asks for the same fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ItemStamp {
    pub argv: Vec<String>,
}

impl ItemStamp {
    fn path(out: &Path, name: &str) -> PathBuf {
        out.join(STAMP_DIR).join(format!("{name}.json"))
    }

    fn read(out: &Path, name: &str) -> Option<ItemStamp> {
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
}

/// What happened to one item of this shard.
#[derive(Debug, Clone, PartialEq)]
pub enum ItemOutcome {
    /// Fitted now; the fit's status (`converged`, …) and the report's line (where it is, or
    /// why it could not be drawn), as `hairfit fit` prints it.
    Fitted { status: String, report: String },
    /// A finished result made with the same arguments was already there.
    Skipped,
    /// The fit could not run (bad data file, …): the error.
    Failed(String),
    /// Ctrl-C/SIGTERM stopped the item; the batch stops after it.
    Interrupted,
}

/// The shard's run: every item it owns with its outcome.
#[derive(Debug, Clone)]
pub struct BatchRun {
    pub shard: Shard,
    pub outcomes: Vec<(String, ItemOutcome)>,
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
            self.count(|o| matches!(o, ItemOutcome::Skipped)),
            self.count(|o| matches!(o, ItemOutcome::Failed(_))),
            if self.interrupted() {
                ", interrupted"
            } else {
                ""
            }
        )
    }

    pub fn interrupted(&self) -> bool {
        self.outcomes
            .iter()
            .any(|(_, o)| matches!(o, ItemOutcome::Interrupted))
    }
}

/// Whether `out/name` holds a finished fit (not interrupted) made with `item`'s arguments.
fn already_finished(out: &Path, item: &Item) -> bool {
    let stamp_matches = ItemStamp::read(out, &item.name).is_some_and(|s| s.argv == item.argv);
    stamp_matches
        && merge::fit_status(&out.join(&item.name)).is_some_and(|status| status != "interrupted")
}

/// Run this shard's items of `manifest` into `out/NAME`, one after another (each fit uses every
/// core). `on_item` hears each item as it ends (for progress lines).
pub fn run_batch(
    manifest: &Manifest,
    out: &Path,
    shard: Shard,
    cancel: Option<Arc<AtomicBool>>,
    mut on_item: impl FnMut(&Item, &ItemOutcome),
) -> Result<BatchRun> {
    let mut outcomes = Vec::new();
    for (i, item) in manifest.items.iter().enumerate() {
        if !shard.owns(i) {
            continue;
        }
        if cancel.as_ref().is_some_and(|c| c.load(Ordering::SeqCst)) {
            break;
        }
        let outcome = if already_finished(out, item) {
            ItemOutcome::Skipped
        } else {
            run_item(item, out, cancel.clone())
        };
        on_item(item, &outcome);
        let stop = matches!(outcome, ItemOutcome::Interrupted);
        outcomes.push((item.name.clone(), outcome));
        if stop {
            break;
        }
    }
    Ok(BatchRun { shard, outcomes })
}

fn run_item(item: &Item, out: &Path, cancel: Option<Arc<AtomicBool>>) -> ItemOutcome {
    let dir = out.join(&item.name);
    let result = item.fit_args(&dir).and_then(|a| {
        crate::cli::fit::fit_command(&a.data, &a.load, &a.fit, &a.out, cancel.clone())
    });
    match result {
        Err(e) => ItemOutcome::Failed(e.to_string()),
        Ok(run) => {
            let status = merge::fit_status(&dir).unwrap_or_else(|| "unknown".into());
            if status == "interrupted" {
                return ItemOutcome::Interrupted;
            }
            // As `hairfit fit`, an item whose report could not be drawn failed (and reruns).
            if let Err(e) = run.report_result(&dir) {
                return ItemOutcome::Failed(e.to_string());
            }
            let stamp = ItemStamp {
                argv: item.argv.clone(),
            };
            match stamp.write(out, &item.name) {
                Ok(()) => ItemOutcome::Fitted {
                    status,
                    report: run.report_line(&dir).trim_end().to_string(),
                },
                Err(e) => ItemOutcome::Failed(format!("fitted, but {e}")),
            }
        }
    }
}
