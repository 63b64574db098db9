//! eval: S at given angles for a parameter file or JSON, batched exactly as `hairfit eval`.
//!
//! The angle arrays are read in place and S is written straight into the result array: each
//! batch of `EVAL_BATCH` samples checks and converts its angles into a buffer on the stack,
//! evaluates them into its rows of the result and checks the values, so no pass over the
//! whole input or output is added to the model's own work.

use std::mem::MaybeUninit;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use numpy::{PyArray2, PyArrayMethods, PyReadonlyArray1, PyUntypedArrayMethods};
use pyo3::prelude::*;
use rayon::prelude::*;

use hairfit::data::AngleUnit;
use hairfit::families::{FamilyModel, FamilyParams};
use hairfit::geometry::Angles;

use crate::args::{parse, ModelCli};
use crate::arrays::{angle_unit, check_angles, common_length, unit_name, values_of};
use crate::errors::{hf, name_parameter_file, warn, HairfitError};
use crate::interrupt::off_gil;

/// `hairfit eval`'s chunking (src/eval.rs: CHUNK_ROWS, CHUNK_VALUES, EVAL_BATCH): the lane
/// kernel evaluates a batch eight samples at a time and the rest one by one, so the values are
/// bit-identical to the CLI's only when the batches are the same.
const CHUNK_ROWS: usize = 16_384;
const CHUNK_VALUES: usize = 1 << 20;
const EVAL_BATCH: usize = 256;

/// What evaluating the samples found wrong, worst last: the error is then found again by a
/// sequential pass, so it names the first bad sample whatever order the batches ran in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Fault {
    None,
    /// A value S is not finite for (its batch was evaluated).
    Value,
    /// An angle outside the model's domain (its batch was not evaluated).
    Angle,
}

/// One batch (at most `EVAL_BATCH` samples): check and convert the angles, evaluate them into
/// `out` (row-major, sample × channel), check the values.
fn eval_batch(model: &FamilyModel, a: [&[f64]; 4], unit: AngleUnit, out: &mut [f64]) -> Fault {
    let m = a[0].len();
    assert!(m <= EVAL_BATCH, "a batch has at most EVAL_BATCH samples");
    // Each `m` long (or a panic), so the loops below see exactly `m` samples.
    let a = [a[0], &a[1][..m], &a[2][..m], &a[3][..m]];
    let rows = || a[0].iter().zip(a[1]).zip(a[2]).zip(a[3]);
    // `check_angles`' rules without branches (NaN and ±∞ fail every comparison; the limits are
    // finite), so the compiler checks several samples per instruction.
    let (theta, phi) = (unit.theta_limit(), unit.phi_limit());
    let mut ok = true;
    for (((ti, pi), tr), pr) in rows() {
        ok &= (ti.abs() < theta) & (pi.abs() <= phi) & (tr.abs() < theta) & (pr.abs() <= phi);
    }
    if !ok {
        return Fault::Angle;
    }
    // The batch's model angles on the stack, written once (no zeroing first).
    let mut buffer = [MaybeUninit::<Angles>::uninit(); EVAL_BATCH];
    let slots = buffer.iter_mut().zip(rows());
    match unit {
        AngleUnit::Deg => {
            for (slot, (((&ti, &pi), &tr), &pr)) in slots {
                slot.write(Angles::from_degrees(ti, pi, tr, pr));
            }
        }
        AngleUnit::Rad => {
            for (slot, (((&theta_i, &phi_i), &theta_r), &phi_r)) in slots {
                slot.write(Angles {
                    theta_i,
                    phi_i,
                    theta_r,
                    phi_r,
                });
            }
        }
    }
    // SAFETY: the loop above wrote the first `m` slots (`m ≤ EVAL_BATCH` and the four slices
    // are `m` long, both ensured above), and `Angles` is plain data.
    let angles = unsafe { std::slice::from_raw_parts(buffer.as_ptr().cast::<Angles>(), m) };
    model.eval_batch_fast(angles, out);
    if out.iter().fold(true, |ok, v| ok & v.is_finite()) {
        Fault::None
    } else {
        Fault::Value
    }
}

/// S at every sample into `out` (row-major, sample × channel), batched exactly as `hairfit
/// eval` batches; the worst fault any batch found. After an angle fault the batches not yet
/// started are skipped.
fn eval_rows(model: &FamilyModel, a: [&[f64]; 4], unit: AngleUnit, out: &mut [f64]) -> Fault {
    let nc = model.n_channels().max(1);
    let chunk_rows = (CHUNK_VALUES / nc).clamp(1, CHUNK_ROWS);
    let stop = AtomicBool::new(false);
    let batches = |out: &mut [f64], rows: std::ops::Range<usize>| -> Fault {
        out.par_chunks_mut(nc * EVAL_BATCH)
            .enumerate()
            .map(|(b, o)| {
                if stop.load(Ordering::Relaxed) {
                    return Fault::Angle;
                }
                let start = rows.start + b * EVAL_BATCH;
                let r = start..(start + EVAL_BATCH).min(rows.end);
                let fault = eval_batch(model, a.map(|x| &x[r.clone()]), unit, o);
                if fault == Fault::Angle {
                    stop.store(true, Ordering::Relaxed);
                }
                fault
            })
            .max()
            .unwrap_or(Fault::None)
    };
    let n = a[0].len();
    if chunk_rows.is_multiple_of(EVAL_BATCH) {
        // The chunks split at batch boundaries: one parallel pass has the same batches.
        batches(out, 0..n)
    } else {
        let mut worst = Fault::None;
        for (c, o) in out.chunks_mut(chunk_rows * nc).enumerate() {
            let start = c * chunk_rows;
            worst = worst.max(batches(o, start..(start + chunk_rows).min(n)));
            if worst == Fault::Angle {
                break;
            }
        }
        worst
    }
}

/// Read a parameter file (`path`) or parameter JSON text (`text`, named `<params>` in messages)
/// as the family `model_args` asks for.
fn family_params(
    py: Python<'_>,
    text: Option<String>,
    path: Option<PathBuf>,
    family: hairfit::families::ModelFamily,
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

/// S (n, channels) at the given angles: what `hairfit eval` appends to each row; into `out`
/// when given (C-contiguous, (n, channels), writeable, not overlapping the angles).
#[pyfunction]
#[pyo3(signature = (params_json, params_path, theta_i, phi_i, theta_r, phi_r, model_args, angles, out=None))]
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
    out: Option<Bound<'py, PyArray2<f64>>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let unit = angle_unit(angles)?;
    let cli: ModelCli = parse(model_args)?;
    let args = cli.model;
    args.check_family_options().map_err(hf)?;
    let file = family_params(py, params_json, params_path, args.family)?;
    let model = FamilyModel::new(&file, &args.setup().map_err(hf)?);
    let inputs = [
        values_of(&theta_i),
        values_of(&phi_i),
        values_of(&theta_r),
        values_of(&phi_r),
    ];
    let a: [&[f64]; 4] = [&inputs[0], &inputs[1], &inputs[2], &inputs[3]];
    let n = common_length(a).map_err(HairfitError::new_err)?;
    let nc = model.n_channels().max(1);
    let result = match out {
        Some(given) => {
            let shape = given.shape().to_vec();
            if shape != [n, nc] || !given.is_c_contiguous() {
                return Err(HairfitError::new_err(format!(
                    "out has shape {shape:?}{}; eval writes {n} samples × {nc} channels: pass a C-contiguous np.empty(({n}, {nc}))",
                    if given.is_c_contiguous() { "" } else { " and is not C-contiguous" }
                )));
            }
            given
        }
        // Not zeroed: a pass over the whole array that `eval_rows` overwrites anyway (every
        // value when it succeeds; on a fault the array is dropped, never returned).
        // SAFETY: f64 has no invalid bit patterns, so reading an unwritten value would give
        // garbage but not undefined behaviour, and none is read before it is written.
        None => unsafe { PyArray2::<f64>::new(py, [n, nc], false) },
    };
    // A writeable borrow: refused for a read-only `out` or one overlapping an angle array.
    let mut borrow = result.try_readwrite().map_err(|e| {
        HairfitError::new_err(format!(
            "out cannot be written ({e}): pass a writeable array that does not share memory with the angles"
        ))
    })?;
    let out = borrow
        .as_slice_mut()
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    off_gil(py, || match eval_rows(&model, a, unit, out) {
        Fault::None => Ok(()),
        Fault::Angle => Err(check_angles(a, unit)
            .expect_err("a batch found an angle out of the domain")),
        Fault::Value => {
            let j = out.iter().position(|v| !v.is_finite()).unwrap_or(0);
            let i = j / nc;
            Err(format!(
                "the model gives S = {} for sample {i} (theta_i={}, phi_i={}, theta_r={}, phi_r={} {}) with the parameters {}: use parameters the model can evaluate",
                out[j],
                a[0][i],
                a[1][i],
                a[2][i],
                a[3][i],
                unit_name(unit),
                file.json_line()
            ))
        }
    })?
    .map_err(HairfitError::new_err)?;
    drop(borrow);
    Ok(result)
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
