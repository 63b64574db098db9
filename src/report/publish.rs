//! A fit published with its report: the fit's files and its plotted report written into an
//! output set ([`crate::outdir::OutputSet`]) together, and what the command tells the user about
//! the report. Here, above both the fit and the output directories, so neither reaches up.

use std::path::Path;

use crate::error::{Error, Result};
use crate::fit::FitOutcome;
use crate::outdir::OutputSet;

/// Write a fit's files (fit.json, params.json, curves.csv, timing.json) and its plotted
/// report into `dir`, the staging directory of `set` or a [`OutputSet::sub_dir`] of it. A report
/// that cannot be drawn (a full disk) is an error: the set is then not published, and what
/// `--out` held stays whole. Messages name the published place, not the staging one.
pub fn write_fit<P: Sync>(
    set: &OutputSet,
    dir: &Path,
    mut outcome: FitOutcome<P>,
) -> Result<PublishedFit<P>> {
    let writing = std::time::Instant::now();
    // The report draws what curves.csv holds (`--curves`), as `hairfit report` would later.
    let curves = crate::fit::written_curves(&outcome);
    // The files and the figures do not read each other: the report is drawn on the pool while
    // this thread writes the files (curves.csv's writes stay here, its formatting goes to the
    // pool), so the report's serial parts (regrouping 100k rows by sample, the slice search,
    // PNG encoding) fill the core that curves.csv's formatting and writing leave idle.
    let mut report = None;
    let files = rayon::in_place_scope(|scope| {
        scope.spawn(|_| {
            report = Some(super::write_report_of(
                dir,
                &outcome.json,
                curves.as_deref(),
                outcome.curve_slices.as_deref(),
                &super::ReportOptions::default(),
            ))
        });
        crate::files::write_fit_files(dir, &outcome.json, curves.as_deref())
    });
    let report = report.expect("the scope ends after the report");
    files.map_err(|e| set.explain(e))?;
    report.map_err(|e| {
        let e = set.explain(e);
        Error::Other(format!("the plotted report could not be drawn: {e}"))
    })?;
    drop(curves);
    outcome.timing.outputs_s = Some(writing.elapsed().as_secs_f64());
    crate::files::write_timing(dir, &outcome.timing).map_err(|e| set.explain(e))?;
    Ok(PublishedFit { outcome })
}

/// The files a report draws (figures and the page): redrawn by every report, never carried over.
pub fn is_report_file(name: &str) -> bool {
    name == "index.html" || name.ends_with(".svg") || name.ends_with(".png")
}

/// A fit published into its output directory with its plotted report.
#[derive(Debug)]
pub struct PublishedFit<P = crate::families::FamilyParams> {
    pub outcome: FitOutcome<P>,
}

impl<P> PublishedFit<P> {
    /// The summary's last line: where the report is.
    pub fn report_line(&self, dir: &Path) -> String {
        format!("report: {}\n", dir.join("index.html").display())
    }
}

/// Run `produce` (which may write extra files, e.g. the demo's data, into the staging directory
/// it is given) under the lock of `out`, write the fit's files and its report beside them, and
/// publish the whole set. `inputs` are the files the run reads (see [`OutputSet::begin`]).
pub fn publish_fit<P: Sync>(
    out: &Path,
    command: &str,
    force: bool,
    inputs: &[&Path],
    produce: impl FnOnce(&Path) -> Result<FitOutcome<P>>,
) -> Result<PublishedFit<P>> {
    let set = OutputSet::begin(out, command, force, inputs)?;
    let outcome = produce(set.staging()).map_err(|e| set.explain(e))?;
    let published = write_fit(&set, set.staging(), outcome)?;
    set.publish()?;
    Ok(published)
}
