//! `hairfit._native`: the Python extension module over the hairfit library (PyO3 + rust-numpy).
//!
//! Thin by design: every function parses its options with the command line's own clap types
//! (`ModelArgs`, `LoadOptions`, `FitArgs`, `SynthArgs`, `CompareArgs`, `ExportArgs`) from the
//! argument list `python/hairfit/__init__.py` builds out of keyword arguments, and then calls the
//! same library functions `src/main.rs` calls, so defaults, checks, values and error messages
//! are the CLI's. Work runs with the GIL released; fits and comparisons run on a worker thread
//! while the calling thread polls for Ctrl-C and, on one, sets the fit's cancel flag.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use clap::Parser;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use rayon::prelude::*;

use hairfit::cli::fit::FitArgs;
use hairfit::cli::ModelArgs;
use hairfit::data::{AngleUnit, Dataset, LoadOptions, LoadReport};
use hairfit::family::{FamilyModel, FamilyParams};
use hairfit::fit::{fit_family, into_fit_data, FitOutcome};
use hairfit::model::Angles;

create_exception!(
    _native,
    HairfitError,
    PyValueError,
    "An error hairfit reports about its input (file:line:column where it has one); the message \
     is what the `hairfit` command line prints after `hairfit: error: ` for the same input."
);

// ---------------------------------------------------------------------------------------------
// Errors and option parsing

/// An error and its causes joined by `: `, each said once: `error_text` of src/main.rs, so the
/// exception says what the CLI prints.
fn error_text(err: &(dyn std::error::Error + 'static)) -> String {
    let mut text = String::new();
    let mut cause = Some(err);
    while let Some(c) = cause {
        let part = c.to_string();
        if !text.ends_with(&part) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&part);
        }
        cause = c.source();
    }
    text
}

fn hf(err: hairfit::Error) -> PyErr {
    HairfitError::new_err(error_text(&err))
}

/// A clap error as one message: its first paragraph, without `error: ` and the usage lines
/// (which name command-line flags a Python caller did not type).
fn clap_text(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let text = text.trim_start().trim_start_matches("error: ");
    text.split("\n\n")
        .next()
        .unwrap_or(text)
        .trim_end()
        .to_string()
}

/// Parse `args` (command-line flags built by the Python layer) with the CLI's own option type.
fn parse<T: Parser>(args: Vec<String>) -> PyResult<T> {
    T::try_parse_from(std::iter::once("hairfit".to_string()).chain(args))
        .map_err(|e| HairfitError::new_err(clap_text(&e)))
}

#[derive(Parser)]
#[command(name = "hairfit")]
struct ModelCli {
    #[command(flatten)]
    model: ModelArgs,
}

#[derive(Parser)]
#[command(name = "hairfit")]
struct LoadCli {
    #[command(flatten)]
    load: LoadOptions,
}

#[derive(Parser)]
#[command(name = "hairfit")]
struct FitCli {
    #[command(flatten)]
    fit: FitArgs,
}

#[derive(Parser)]
#[command(name = "hairfit")]
struct SynthCli {
    #[command(flatten)]
    synth: hairfit::cli::synth::SynthArgs,
}

#[derive(Parser)]
#[command(name = "hairfit")]
struct CompareCli {
    #[command(flatten)]
    compare: hairfit::cli::compare::CompareArgs,
}

#[derive(Parser)]
#[command(name = "hairfit")]
struct ExportCli {
    #[command(flatten)]
    export: hairfit::cli::export::ExportArgs,
}

fn angle_unit(text: &str) -> PyResult<AngleUnit> {
    match text.trim().to_ascii_lowercase().as_str() {
        "deg" => Ok(AngleUnit::Deg),
        "rad" => Ok(AngleUnit::Rad),
        other => Err(HairfitError::new_err(format!(
            "angles `{other}`: use deg or rad"
        ))),
    }
}

fn unit_name(unit: AngleUnit) -> &'static str {
    match unit {
        AngleUnit::Deg => "degrees",
        AngleUnit::Rad => "radians",
    }
}

fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    let text = std::ffi::CString::new(message.replace('\0', " ")).unwrap_or_default();
    PyErr::warn(py, &py.get_type::<PyUserWarning>(), &text, 2)
}

// ---------------------------------------------------------------------------------------------
// Running work off the GIL, interruptibly

/// Run `work` on a worker thread with the GIL released; every ~50 ms the calling thread checks
/// for signals. On Ctrl-C (or any exception a signal handler raises) the cancel flag is set, the
/// worker is waited for (a fit stops at its next iteration) and the exception is raised.
fn interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(Arc<AtomicBool>) -> T + Send,
) -> PyResult<T> {
    let cancel = Arc::new(AtomicBool::new(false));
    std::thread::scope(|scope| {
        let (tx, rx) = mpsc::channel();
        let flag = cancel.clone();
        scope.spawn(move || {
            let _ = tx.send(work(flag));
        });
        let mut rx = rx;
        loop {
            let (back, got) = py.allow_threads(move || {
                let got = rx.recv_timeout(Duration::from_millis(50));
                (rx, got)
            });
            rx = back;
            match got {
                Ok(value) => return Ok(value),
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if let Err(signal) = py.check_signals() {
                        cancel.store(true, Ordering::SeqCst);
                        let _ = py.allow_threads(move || rx.recv());
                        return Err(signal);
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(PyRuntimeError::new_err(
                        "hairfit: the worker thread panicked (a bug: please report it)",
                    ))
                }
            }
        }
    })
}

// ---------------------------------------------------------------------------------------------
// eval

/// `hairfit eval`'s chunking (src/eval.rs: CHUNK_ROWS, CHUNK_VALUES, EVAL_BATCH): the lane
/// kernel evaluates a batch eight samples at a time and the rest one by one, so the values are
/// bit-identical to the CLI's only when the batches are the same.
const CHUNK_ROWS: usize = 16_384;
const CHUNK_VALUES: usize = 1 << 20;
const EVAL_BATCH: usize = 256;

/// S at every sample, row-major (sample, channel), batched exactly as `hairfit eval` batches.
fn eval_rows(model: &FamilyModel, angles: &[Angles], out: &mut [f64]) {
    let nc = model.n_channels().max(1);
    let chunk_rows = (CHUNK_VALUES / nc).clamp(1, CHUNK_ROWS);
    let batches = |out: &mut [f64], angles: &[Angles]| {
        out.par_chunks_mut(nc * EVAL_BATCH)
            .zip(angles.par_chunks(EVAL_BATCH))
            .for_each(|(o, a)| model.eval_batch_fast(a, o));
    };
    if chunk_rows.is_multiple_of(EVAL_BATCH) {
        // The chunks split at batch boundaries: one parallel pass has the same batches.
        batches(out, angles);
    } else {
        for (a, o) in angles
            .chunks(chunk_rows)
            .zip(out.chunks_mut(chunk_rows * nc))
        {
            batches(o, a);
        }
    }
}

/// src/main.rs's `name_parameter_file`: a domain error says which file it is in.
fn name_parameter_file(err: hairfit::Error, path: &Path) -> String {
    match err {
        hairfit::Error::Parameter { .. } => {
            format!("in parameter file {}: {}", path.display(), error_text(&err))
        }
        other => error_text(&other),
    }
}

/// The four angle arrays as model angles, each value checked as `hairfit eval` checks a row
/// (finite, |θ| < 90°, |φ| ≤ 720°); errors name the array and index.
fn angles_from(arrays: [&[f64]; 4], unit: AngleUnit) -> std::result::Result<Vec<Angles>, String> {
    const NAMES: [&str; 4] = ["theta_i", "phi_i", "theta_r", "phi_r"];
    let n = arrays[0].len();
    for (k, a) in arrays.iter().enumerate() {
        if a.len() != n {
            return Err(format!(
                "{} has {} values but theta_i has {n}: give the four angle arrays the same length",
                NAMES[k],
                a.len()
            ));
        }
    }
    let (theta_limit, phi_limit) = (unit.theta_limit(), unit.phi_limit());
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut v = [0.0; 4];
        for (k, (slot, array)) in v.iter_mut().zip(arrays).enumerate() {
            let value = array[i];
            let name = NAMES[k];
            if !value.is_finite() {
                return Err(format!("{name}[{i}] = {value} is not finite"));
            }
            if k % 2 == 0 && value.abs() >= theta_limit {
                return Err(format!(
                    "{name}[{i}] = {value} {} lies on the fiber axis or beyond; inclinations must satisfy |θ| < 90° (π/2)",
                    unit_name(unit)
                ));
            }
            if k % 2 == 1 && value.abs() > phi_limit {
                return Err(format!(
                    "{name}[{i}] = {value} {} is more than two turns; azimuths must satisfy |φ| ≤ 720° (4π), as the loader requires",
                    unit_name(unit)
                ));
            }
            *slot = value;
        }
        out.push(match unit {
            AngleUnit::Deg => Angles::from_degrees(v[0], v[1], v[2], v[3]),
            AngleUnit::Rad => Angles {
                theta_i: v[0],
                phi_i: v[1],
                theta_r: v[2],
                phi_r: v[3],
            },
        });
    }
    Ok(out)
}

fn vec_of(a: &PyReadonlyArray1<'_, f64>) -> Vec<f64> {
    a.as_array().iter().copied().collect()
}

/// Read a parameter file (`path`) or parameter JSON text (`text`, named `<params>` in messages)
/// as the family `model_args` asks for.
fn family_params(
    py: Python<'_>,
    text: Option<String>,
    path: Option<PathBuf>,
    family: hairfit::family::ModelFamily,
) -> PyResult<FamilyParams> {
    let (file, name) = match (text, path) {
        (Some(text), _) => (
            FamilyParams::from_json_text(text, Path::new("<params>"), family).map_err(|e| {
                HairfitError::new_err(name_parameter_file(e, Path::new("<params>")))
            })?,
            "<params>".to_string(),
        ),
        (None, Some(path)) => (
            FamilyParams::load(&path, family)
                .map_err(|e| HairfitError::new_err(name_parameter_file(e, &path)))?,
            path.display().to_string(),
        ),
        (None, None) => return Err(HairfitError::new_err("no parameters given")),
    };
    for w in file.warnings() {
        warn(py, &format!("{name}: {w}"))?;
    }
    Ok(file)
}

/// S (n, channels) at the given angles: what `hairfit eval` appends to each row.
#[pyfunction]
#[pyo3(signature = (params_json, params_path, theta_i, phi_i, theta_r, phi_r, model_args, angles))]
#[allow(clippy::too_many_arguments)]
fn eval<'py>(
    py: Python<'py>,
    params_json: Option<String>,
    params_path: Option<PathBuf>,
    theta_i: PyReadonlyArray1<'py, f64>,
    phi_i: PyReadonlyArray1<'py, f64>,
    theta_r: PyReadonlyArray1<'py, f64>,
    phi_r: PyReadonlyArray1<'py, f64>,
    model_args: Vec<String>,
    angles: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let unit = angle_unit(angles)?;
    let cli: ModelCli = parse(model_args)?;
    let args = cli.model;
    args.check_family_options().map_err(hf)?;
    let file = family_params(py, params_json, params_path, args.family)?;
    let model = FamilyModel::new(
        &file,
        args.config().map_err(hf)?,
        &args.chiang().map_err(hf)?,
    );
    let arrays = [
        vec_of(&theta_i),
        vec_of(&phi_i),
        vec_of(&theta_r),
        vec_of(&phi_r),
    ];
    let nc = model.n_channels().max(1);
    let (values, n) = py
        .allow_threads(|| {
            let a = angles_from(
                [&arrays[0], &arrays[1], &arrays[2], &arrays[3]],
                unit,
            )?;
            let mut values = vec![0.0; a.len() * nc];
            eval_rows(&model, &a, &mut values);
            if let Some(j) = values.iter().position(|v| !v.is_finite()) {
                let i = j / nc;
                return Err(format!(
                    "the model gives S = {} for sample {i} (theta_i={}, phi_i={}, theta_r={}, phi_r={} {}) with the parameters {}: use parameters the model can evaluate",
                    values[j],
                    arrays[0][i],
                    arrays[1][i],
                    arrays[2][i],
                    arrays[3][i],
                    unit_name(unit),
                    file.json_line()
                ));
            }
            Ok((values, a.len()))
        })
        .map_err(HairfitError::new_err)?;
    let array = Array2::from_shape_vec((n, nc), values)
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    Ok(array.into_pyarray(py))
}

/// The output column names `hairfit eval` appends for a parameter file: `s`, or `s_0…`.
#[pyfunction]
#[pyo3(signature = (params_json, params_path, model_args))]
fn eval_columns(
    py: Python<'_>,
    params_json: Option<String>,
    params_path: Option<PathBuf>,
    model_args: Vec<String>,
) -> PyResult<Vec<String>> {
    let cli: ModelCli = parse(model_args)?;
    let file = family_params(py, params_json, params_path, cli.model.family)?;
    Ok(hairfit::eval::output_columns(
        file.n_channels(),
        file.sigma_a_is_scalar(),
    ))
}

// ---------------------------------------------------------------------------------------------
// Data

/// Loaded samples (angles in radians inside) with the loader's report on every row.
#[pyclass(module = "hairfit._native", frozen)]
struct Data {
    ds: Dataset,
    report: LoadReport,
    /// The file and loader options, when loaded from a file (a fit records them as the CLI's).
    source: Option<(PathBuf, LoadOptions)>,
    load_s: Option<f64>,
}

#[pymethods]
impl Data {
    /// The four angle arrays in `unit` (`deg`: the degrees the writers put in files, which map
    /// back to the same radians).
    fn angles<'py>(&self, py: Python<'py>, unit: &str) -> PyResult<Vec<Bound<'py, PyArray1<f64>>>> {
        let unit = angle_unit(unit)?;
        let conv = |v: &Vec<f64>| -> Vec<f64> {
            match unit {
                AngleUnit::Deg => v
                    .iter()
                    .map(|&x| hairfit::data::round_trip_degrees(x))
                    .collect(),
                AngleUnit::Rad => v.clone(),
            }
        };
        Ok([
            &self.ds.theta_i,
            &self.ds.phi_i,
            &self.ds.theta_r,
            &self.ds.phi_r,
        ]
        .into_iter()
        .map(|v| conv(v).into_pyarray(py))
        .collect())
    }

    fn radiance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.table(py, Some(&self.ds.radiance))
            .map(|t| t.expect("radiance"))
    }

    fn sigma<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        self.table(py, self.ds.sigma.as_ref())
    }

    fn weight<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        self.table(py, self.ds.weight.as_ref())
    }

    fn source_line<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u64>> {
        self.ds.source_line.clone().into_pyarray(py)
    }

    fn channels(&self) -> Vec<String> {
        self.ds.channels.clone()
    }

    fn file(&self) -> Option<String> {
        self.source.as_ref().map(|(p, _)| p.display().to_string())
    }

    /// The load report as JSON (`hairfit load --json`).
    fn report_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.report).map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// The load report as `hairfit load` prints it.
    fn report_text(&self) -> String {
        self.report.to_string()
    }

    fn __len__(&self) -> usize {
        self.ds.len()
    }
}

impl Data {
    fn table<'py>(
        &self,
        py: Python<'py>,
        values: Option<&Vec<f64>>,
    ) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        let Some(values) = values else {
            return Ok(None);
        };
        let shape = (self.ds.len(), self.ds.n_channels());
        Array2::from_shape_vec(shape, values.clone())
            .map(|a| Some(a.into_pyarray(py)))
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }
}

/// `hairfit load PATH [loader options]`: the samples and the report.
#[pyfunction]
fn load(py: Python<'_>, path: PathBuf, load_args: Vec<String>) -> PyResult<Data> {
    let cli: LoadCli = parse(load_args)?;
    let options = cli.load;
    let started = Instant::now();
    let (ds, report) = py
        .allow_threads(|| hairfit::data::load(&path, &options))
        .map_err(hf)?;
    Ok(Data {
        ds,
        report,
        source: Some((path, options)),
        load_s: Some(started.elapsed().as_secs_f64()),
    })
}

/// Samples from arrays (angles in `angles`, values (n, channels)): the loader's report then
/// says every row was accepted, its lines the sample indices from 1.
#[pyfunction]
#[pyo3(signature = (theta_i, phi_i, theta_r, phi_r, radiance, sigma, weight, channels, angles))]
#[allow(clippy::too_many_arguments)]
fn data_from_arrays<'py>(
    theta_i: PyReadonlyArray1<'py, f64>,
    phi_i: PyReadonlyArray1<'py, f64>,
    theta_r: PyReadonlyArray1<'py, f64>,
    phi_r: PyReadonlyArray1<'py, f64>,
    radiance: PyReadonlyArray2<'py, f64>,
    sigma: Option<PyReadonlyArray2<'py, f64>>,
    weight: Option<PyReadonlyArray2<'py, f64>>,
    channels: Vec<String>,
    angles: &str,
) -> PyResult<Data> {
    let unit = angle_unit(angles)?;
    let arrays = [
        vec_of(&theta_i),
        vec_of(&phi_i),
        vec_of(&theta_r),
        vec_of(&phi_r),
    ];
    let a = angles_from([&arrays[0], &arrays[1], &arrays[2], &arrays[3]], unit)
        .map_err(HairfitError::new_err)?;
    let n = a.len();
    let nc = channels.len();
    let table =
        |name: &str, t: &PyReadonlyArray2<'py, f64>, positive: bool| -> PyResult<Vec<f64>> {
            let v = t.as_array();
            if v.shape() != [n, nc] {
                return Err(HairfitError::new_err(format!(
                    "{name} has shape {:?} but the data have {n} samples × {nc} channels ({})",
                    v.shape(),
                    channels.join(",")
                )));
            }
            let values: Vec<f64> = v.iter().copied().collect();
            if let Some(j) = values
                .iter()
                .position(|x| !x.is_finite() || (positive && *x <= 0.0))
            {
                return Err(HairfitError::new_err(format!(
                    "{name}[{}, {}] = {} {}",
                    j / nc,
                    j % nc,
                    values[j],
                    if positive {
                        "must be a finite number > 0"
                    } else {
                        "is not finite (leave out the samples that were not measured)"
                    }
                )));
            }
            Ok(values)
        };
    let values = table("radiance", &radiance, false)?;
    let sigma = sigma.map(|s| table("sigma", &s, true)).transpose()?;
    let weight = weight.map(|w| table("weight", &w, true)).transpose()?;
    if nc == 0 {
        return Err(HairfitError::new_err(
            "no channels: radiance needs at least one column",
        ));
    }
    let mut ds = Dataset::with_channels(channels, sigma.is_some(), weight.is_some());
    for (i, ang) in a.iter().enumerate() {
        let row = i * nc..(i + 1) * nc;
        ds.push(
            [ang.theta_i, ang.phi_i, ang.theta_r, ang.phi_r],
            &values[row.clone()],
            sigma.as_ref().map(|s| &s[row.clone()]),
            weight.as_ref().map(|w| &w[row.clone()]),
            i as u64 + 1,
        );
    }
    let report = LoadReport {
        file: "<arrays>".into(),
        format: "arrays".into(),
        rows_read: n as u64,
        accepted: n as u64,
        ..LoadReport::default()
    };
    Ok(Data {
        ds,
        report,
        source: None,
        load_s: None,
    })
}

// ---------------------------------------------------------------------------------------------
// fit

/// A finished fit: fit.json's content, the parameters, curves and timing, as `hairfit fit`
/// has them before it writes its --out directory.
#[pyclass(module = "hairfit._native", frozen)]
struct Fit {
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
        let published = py.allow_threads(|| {
            let inputs: Vec<&Path> = self.inputs.iter().map(PathBuf::as_path).collect();
            hairfit::report::publish::publish_fit(&dir, "hairfit fit", force, &inputs, |_| {
                Ok(self.outcome.clone())
            })
        });
        let published = published.map_err(hf)?;
        published.report_result(&dir).map_err(hf)?;
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
        let mut outcome = fit_family(&fit_data, &file, data.report.clone(), &opts)?;
        if let Some((_, load_options)) = &data.source {
            // What `fit_command` adds: the loader's settings, its warnings, its time.
            outcome.json.options.load = Some(format!("{load_options:?}"));
            outcome
                .json
                .warnings
                .splice(0..0, data.report.warnings.clone());
            outcome.timing.load_s = data.load_s;
        }
        Ok(outcome)
    })?
    .map_err(hf)?;
    let inputs = data.source.iter().map(|(p, _)| p.clone()).collect();
    Ok(Fit { outcome, inputs })
}

/// `hairfit fit DATA [options]` without --out: load (`load_args`), then fit (`fit_args`).
#[pyfunction]
fn fit_file(
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
fn fit(py: Python<'_>, data: &Data, fit_args: Vec<String>) -> PyResult<Fit> {
    let cli: FitCli = parse(fit_args)?;
    fit_data(py, data, &cli.fit)
}

// ---------------------------------------------------------------------------------------------
// synth, compare, export

/// `hairfit synth ARGS`: (csv path, truth path, samples, outliers, notes).
#[pyfunction]
fn synth(
    py: Python<'_>,
    args: Vec<String>,
) -> PyResult<(String, String, usize, usize, Vec<String>)> {
    let argv = std::iter::once("hairfit".to_string())
        .chain(std::iter::once("synth".to_string()))
        .chain(args.iter().cloned());
    let command_line = hairfit::cli::synth::command_line_string(argv);
    let cli: SynthCli = parse(args)?;
    let s = py
        .allow_threads(|| hairfit::cli::synth::run(&cli.synth, Some(command_line)))
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
fn compare(py: Python<'_>, args: Vec<String>) -> PyResult<String> {
    let cli: CompareCli = parse(args)?;
    let a = cli.compare;
    let done = interruptible(py, |cancel| {
        hairfit::cli::compare::compare_command(&a, Some(cancel))
    })?
    .map_err(hf)?;
    let mut text: String = done.report_lines.concat();
    text.push_str(&hairfit::compare::summary_text(&done.comparison, &a.out));
    Ok(text)
}

/// `hairfit export DIR --to R [--output F]`: (summary line, the file's text when no --output).
#[pyfunction]
fn export(py: Python<'_>, args: Vec<String>) -> PyResult<(String, Option<String>)> {
    let cli: ExportCli = parse(args)?;
    py.allow_threads(|| hairfit::cli::export::export_command(&cli.export))
        .map_err(hf)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("HairfitError", m.py().get_type::<HairfitError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<Data>()?;
    m.add_class::<Fit>()?;
    m.add_function(wrap_pyfunction!(eval, m)?)?;
    m.add_function(wrap_pyfunction!(eval_columns, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(data_from_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(fit_file, m)?)?;
    m.add_function(wrap_pyfunction!(synth, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(export, m)?)?;
    Ok(())
}
