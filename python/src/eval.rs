//! eval: S at given angles for a parameter file or JSON, batched exactly as `hairfit eval`.

use std::path::{Path, PathBuf};

use numpy::{PyArray2, PyReadonlyArray1};
use pyo3::prelude::*;
use rayon::prelude::*;

use hairfit::family::{FamilyModel, FamilyParams};
use hairfit::model::Angles;

use crate::args::{parse, ModelCli};
use crate::arrays::{angle_unit, angles_from, array2, unit_name, vec_of};
use crate::errors::{hf, name_parameter_file, warn, HairfitError};

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
pub(crate) fn eval<'py>(
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
    let model = FamilyModel::new(&file, &args.setup().map_err(hf)?);
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
    array2(py, (n, nc), values)
}

/// The output column names `hairfit eval` appends for a parameter file: `s`, or `s_0…`.
#[pyfunction]
#[pyo3(signature = (params_json, params_path, model_args))]
pub(crate) fn eval_columns(
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
