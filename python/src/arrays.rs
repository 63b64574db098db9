//! Arrays ⇄ NumPy: angle units, the four angle arrays as checked model angles, value tables.

use std::borrow::Cow;

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray1};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use hairfit::data::AngleUnit;
use hairfit::geometry::Angles;

use crate::errors::HairfitError;

pub(crate) fn angle_unit(text: &str) -> PyResult<AngleUnit> {
    match text.trim().to_ascii_lowercase().as_str() {
        "deg" => Ok(AngleUnit::Deg),
        "rad" => Ok(AngleUnit::Rad),
        other => Err(HairfitError::new_err(format!(
            "angles `{other}`: use deg or rad"
        ))),
    }
}

pub(crate) fn unit_name(unit: AngleUnit) -> &'static str {
    match unit {
        AngleUnit::Deg => "degrees",
        AngleUnit::Rad => "radians",
    }
}

const NAMES: [&str; 4] = ["theta_i", "phi_i", "theta_r", "phi_r"];

/// The common length of the four angle arrays, or the error naming the one that differs.
pub(crate) fn common_length(arrays: [&[f64]; 4]) -> std::result::Result<usize, String> {
    let n = arrays[0].len();
    match arrays.iter().position(|a| a.len() != n) {
        None => Ok(n),
        Some(k) => Err(format!(
            "{} has {} values but theta_i has {n}: give the four angle arrays the same length",
            NAMES[k],
            arrays[k].len()
        )),
    }
}

/// Check every value of the four angle arrays (of one length) as `hairfit eval` checks a row;
/// the error names the first bad value by array and index.
pub(crate) fn check_angles(
    arrays: [&[f64]; 4],
    unit: AngleUnit,
) -> std::result::Result<(), String> {
    let (theta_limit, phi_limit) = (unit.theta_limit(), unit.phi_limit());
    for i in 0..arrays[0].len() {
        for (k, array) in arrays.iter().enumerate() {
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
        }
    }
    Ok(())
}

/// One sample's angles (in `unit`) as model angles, as `hairfit eval` converts a row.
#[inline]
pub(crate) fn to_angles(v: [f64; 4], unit: AngleUnit) -> Angles {
    match unit {
        AngleUnit::Deg => Angles::from_degrees(v[0], v[1], v[2], v[3]),
        AngleUnit::Rad => Angles {
            theta_i: v[0],
            phi_i: v[1],
            theta_r: v[2],
            phi_r: v[3],
        },
    }
}

/// The four angle arrays as model angles, each value checked as `hairfit eval` checks a row
/// (finite, |θ| < 90°, |φ| ≤ 720°); errors name the array and index.
pub(crate) fn angles_from(
    arrays: [&[f64]; 4],
    unit: AngleUnit,
) -> std::result::Result<Vec<Angles>, String> {
    let n = common_length(arrays)?;
    check_angles(arrays, unit)?;
    Ok((0..n)
        .map(|i| to_angles(arrays.map(|a| a[i]), unit))
        .collect())
}

/// An array's values in place when it is contiguous (what `hairfit.eval` and `hairfit.data`
/// pass: `np.ascontiguousarray`), else copied.
pub(crate) fn values_of<'a>(a: &'a PyReadonlyArray1<'_, f64>) -> Cow<'a, [f64]> {
    match a.as_slice() {
        Ok(s) => Cow::Borrowed(s),
        Err(_) => Cow::Owned(a.as_array().iter().copied().collect()),
    }
}

/// Row-major `values` as a NumPy array of `shape` (samples, channels).
pub(crate) fn array2<'py>(
    py: Python<'py>,
    shape: (usize, usize),
    values: Vec<f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    Array2::from_shape_vec(shape, values)
        .map(|a| a.into_pyarray(py))
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))
}
