//! synth, compare, export: the commands that write files, run as the CLI runs them.

use pyo3::prelude::*;

use crate::args::{parse, CompareCli, ExportCli, SynthCli};
use crate::errors::hf;
use crate::interrupt::{interruptible, off_gil};

/// `hairfit synth ARGS`: (csv path, truth path, samples, outliers, notes).
#[pyfunction]
pub(crate) fn synth(
    py: Python<'_>,
    args: Vec<String>,
) -> PyResult<(String, String, usize, usize, Vec<String>)> {
    let argv = std::iter::once("hairfit".to_string())
        .chain(std::iter::once("synth".to_string()))
        .chain(args.iter().cloned());
    let command_line = hairfit::cli::synth::command_line_string(argv);
    let cli: SynthCli = parse(args)?;
    let s = off_gil(py, || {
        hairfit::cli::synth::run(&cli.synth, Some(command_line))
    })?
    .map_err(hf)?;
    Ok((
        s.csv.display().to_string(),
        s.truth.display().to_string(),
        s.n_samples,
        s.n_outliers,
        s.notes,
    ))
}

/// `hairfit compare DATA --out DIR [options]`: the text the command prints.
#[pyfunction]
pub(crate) fn compare(py: Python<'_>, args: Vec<String>) -> PyResult<String> {
    let cli: CompareCli = parse(args)?;
    let a = cli.compare;
    let end = interruptible(py, |cancel| {
        hairfit::cli::compare::compare_command(&a, Some(cancel))
    })?
    .map_err(hf)?;
    let done = match end {
        hairfit::compare::CompareEnd::Published(done) => *done,
        hairfit::compare::CompareEnd::Interrupted(why) => {
            return Err(pyo3::exceptions::PyKeyboardInterrupt::new_err(why))
        }
    };
    // As the CLI exits 1: a comparison with no successful fit is not a result.
    if let Some(e) = done.no_fit_succeeded(&a.out) {
        return Err(hf(e));
    }
    let mut text: String = done.report_lines.concat();
    text.push_str(&hairfit::compare::summary_text(&done.comparison, &a.out));
    Ok(text)
}

/// `hairfit export DIR --to R [--output F]`: (summary line, the file's text when no --output).
#[pyfunction]
pub(crate) fn export(py: Python<'_>, args: Vec<String>) -> PyResult<(String, Option<String>)> {
    let cli: ExportCli = parse(args)?;
    off_gil(py, || hairfit::cli::export::export_command(&cli.export))?.map_err(hf)
}
