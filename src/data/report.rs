//! The load report's one-screen text; the type itself is an on-disk format and lives in
//! [`crate::files::load_report`].

use std::fmt;

pub use crate::files::load_report::{LineTally, LoadReport, RejectReason, FIRST_LINES};

/// Lines as `3, 7, 9` with `, ...` when more rows than listed.
fn line_list(t: &LineTally) -> String {
    let mut s = t
        .first_lines
        .iter()
        .map(u64::to_string)
        .collect::<Vec<_>>()
        .join(", ");
    if t.count > t.first_lines.len() as u64 {
        s.push_str(", ...");
    }
    s
}

impl fmt::Display for LoadReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{} ({}): {} rows read, {} accepted, {} rejected",
            self.file,
            self.format,
            self.rows_read,
            self.accepted,
            self.rejected_total()
        )?;
        for (reason, t) in &self.rejected {
            writeln!(
                f,
                "  rejected, {}: {} (lines {})",
                reason.describe(),
                t.count,
                line_list(t)
            )?;
        }
        for [line, earlier] in &self.duplicate_of {
            writeln!(f, "    line {line} repeats line {earlier}")?;
        }
        if self.replicates.count > 0 {
            writeln!(
                f,
                "  replicates (a direction measured again, kept): {} (lines {})",
                self.replicates.count,
                line_list(&self.replicates)
            )?;
        }
        if self.negative_kept.count > 0 {
            writeln!(
                f,
                "  kept with negative radiance: {} (lines {})",
                self.negative_kept.count,
                line_list(&self.negative_kept)
            )?;
        }
        for note in &self.notes {
            writeln!(f, "  note: {note}")?;
        }
        for warning in &self.warnings {
            writeln!(f, "  warning: {warning}")?;
        }
        Ok(())
    }
}
