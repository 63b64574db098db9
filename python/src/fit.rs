//! fit: the `Fit` class (a finished fit, saved as `hairfit fit --out` saves it) and the fits.

use std::path::{Path, PathBuf};

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use hairfit::cli::fit::FitArgs;
use hairfit::families::FamilyParams;
use hairfit::fit::registry::fit_family;
use hairfit::fit::{into_fit_data, FitOutcome};

use crate::args::{parse, FitCli};
use crate::errors::{hf, HairfitError};
use crate::interrupt::{interruptible, off_gil};
use crate::load::{load, Data};

/// A finished fit: fit.json's content, the parameters, curves and timing, as `hairfit fit`
/// has them before it writes its --out directory.
#[pyclass(module = "hairfit._native", frozen)]
pub(crate) struct Fit {
    outcome: FitOutcome<FamilyParams>,
    /// The data file, which `save` never replaces (as `hairfit fit` refuses to).
    inputs: Vec<PathBuf>,
}

#[pymethods]
impl Fit {
    /// fit.json's content as JSON text.
    fn fit_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.outcome.json)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// params.json's content as JSON text.
    fn params_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.outcome.params)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// timing.json's content as JSON text (wall-clock times; differ run to run).
    fn timing_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.outcome.timing)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// The summary `hairfit fit` prints (without the report's line).
    fn summary(&self) -> String {
        hairfit::cli::summary::summary(&self.outcome, None)
    }

    fn relative_misfit(&self) -> f64 {
        self.outcome.relative_misfit
    }

    /// Write what `hairfit fit --out DIR` writes (fit.json, params.json, curves.csv,
    /// timing.json and the plotted report), published as one set; the report's line.
    fn save(&self, py: Python<'_>, dir: PathBuf, force: bool) -> PyResult<String> {
        let published = off_gil(py, || {
            let inputs: Vec<&Path> = self.inputs.iter().map(PathBuf::as_path).collect();
            hairfit::report::publish::publish_fit(&dir, "hairfit fit", force, &inputs, |_| {
                Ok(self.outcome.clone())
            })
        });
        let published = published?.map_err(hf)?;
        Ok(published.report_line(&dir))
    }
}

/// Fit `data` as `hairfit fit` would (its options from `fit_args`), interruptibly.
fn fit_data(py: Python<'_>, data: &Data, args: &FitArgs) -> PyResult<Fit> {
    // The options' own errors come first, as in `hairfit fit`.
    args.options(None).map_err(hf)?;
    if args.strict {
        if let Some((path, _)) = &data.source {
            if let Some(w) = data
                .report
                .warnings
                .iter()
                // src/data/unit.rs RADIANS_WARNING (crate-private), as `fit_command` tests it.
                .find(|w| w.starts_with("angles look like radians: pass --angles rad"))
            {
                return Err(HairfitError::new_err(format!(
                    "{}: {w} (--strict makes this an error)",
                    path.display()
                )));
            }
        }
    }
    let file = match &data.source {
        Some((path, _)) => path.display().to_string(),
        None => data.report.file.clone(),
    };
    let outcome = interruptible(py, |cancel| -> hairfit::Result<FitOutcome<FamilyParams>> {
        let opts = args.options(Some(cancel))?;
        let fit_data = into_fit_data(data.ds.clone());
        // A loaded file's report carries the loader's settings, warnings and time into the fit.
        fit_family(&fit_data, &file, data.report.clone(), &opts)
    })?
    .map_err(hf)?;
    let inputs = data.source.iter().map(|(p, _)| p.clone()).collect();
    Ok(Fit { outcome, inputs })
}

/// `hairfit fit DATA [options]` without --out: load (`load_args`), then fit (`fit_args`).
#[pyfunction]
pub(crate) fn fit_file(
    py: Python<'_>,
    path: PathBuf,
    load_args: Vec<String>,
    fit_args: Vec<String>,
) -> PyResult<Fit> {
    let cli: FitCli = parse(fit_args)?;
    cli.fit.options(None).map_err(hf)?;
    let data = load(py, path, load_args)?;
    fit_data(py, &data, &cli.fit)
}

/// Fit loaded samples (`load` or `data_from_arrays`).
#[pyfunction]
pub(crate) fn fit(py: Python<'_>, data: &Data, fit_args: Vec<String>) -> PyResult<Fit> {
    let cli: FitCli = parse(fit_args)?;
    fit_data(py, data, &cli.fit)
}
