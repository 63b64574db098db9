//! A fit published with its report: the fit's files and its plotted report written into an
//! output set ([`crate::outdir::OutputSet`]) together, and what the command tells the user about
//! the report. Here, above both the fit and the output directories, so neither reaches up.

use std::path::Path;

use crate::error::{Error, Result};
use crate::fit::FitOutcome;
use crate::outdir::OutputSet;

/// Write a fit's files (fit.json, params.json, curves.csv, timing.json) and its plotted
/// report into `dir`, the staging directory of `set` or a [`OutputSet::sub_dir`] of it. Why the
/// report could not be drawn names the published place, not the staging one.
pub fn write_fit<P>(
    set: &OutputSet,
    dir: &Path,
    mut outcome: FitOutcome<P>,
) -> Result<PublishedFit<P>> {
    let writing = std::time::Instant::now();
    // The report draws what curves.csv holds (`--curves`), as `hairfit report` would later.
    let curves = crate::fit::written_curves(&outcome);
    crate::fit::write_outputs_with(dir, &outcome, curves.as_deref())?;
    let drawn = super::write_report_of(
        dir,
        &outcome.json,
        curves.as_deref(),
        &super::ReportOptions::default(),
    );
    drop(curves);
    outcome.timing.outputs_s = Some(writing.elapsed().as_secs_f64());
    crate::files::write_timing(dir, &outcome.timing)?;
    // Messages name the directory the user asked for, not the staging one.
    let report_error = drawn.err().map(|e| {
        e.to_string().replace(
            &set.staging().display().to_string(),
            &set.dir().display().to_string(),
        )
    });
    Ok(PublishedFit {
        outcome,
        report_error,
    })
}

/// The files a report draws (figures and the page): redrawn by every report, never carried over.
pub fn is_report_file(name: &str) -> bool {
    name == "index.html" || name.ends_with(".svg") || name.ends_with(".png")
}

/// A fit published into its output directory: the outcome, and whether its plotted report
/// could be drawn (the fit's files are published either way).
#[derive(Debug)]
pub struct PublishedFit<P = crate::family::FamilyParams> {
    pub outcome: FitOutcome<P>,
    /// Why the report could not be drawn, if it could not.
    pub report_error: Option<String>,
}

impl<P> PublishedFit<P> {
    /// The summary's last line: where the report is (nothing when it failed: see
    /// [`PublishedFit::report_result`]).
    pub fn report_line(&self, dir: &Path) -> String {
        match self.report_error {
            None => format!("report: {}\n", dir.join("index.html").display()),
            Some(_) => String::new(),
        }
    }

    /// An error when the report could not be drawn: the command then exits non-zero, though
    /// the fit's own files are written.
    pub fn report_result(&self, dir: &Path) -> Result<()> {
        match &self.report_error {
            None => Ok(()),
            Some(e) => Err(Error::Other(format!(
                "the fit's files are written to {}, but its plotted report could not be drawn: {e}",
                dir.display()
            ))),
        }
    }
}

/// Run `produce` (which may write extra files, e.g. the demo's data, into the staging directory
/// it is given) under the lock of `out`, write the fit's files and its report beside them, and
/// publish the whole set. `inputs` are the files the run reads (see [`OutputSet::begin`]).
pub fn publish_fit<P>(
    out: &Path,
    command: &str,
    force: bool,
    inputs: &[&Path],
    produce: impl FnOnce(&Path) -> Result<FitOutcome<P>>,
) -> Result<PublishedFit<P>> {
    let set = OutputSet::begin(out, command, force, inputs)?;
    let outcome = produce(set.staging())?;
    let published = write_fit(&set, set.staging(), outcome)?;
    set.publish()?;
    Ok(published)
}
