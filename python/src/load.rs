//! load: the `Data` class, samples loaded from a file or built from NumPy arrays.

use std::path::PathBuf;

use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use hairfit::data::{AngleUnit, Dataset, LoadOptions, LoadReport};

use crate::args::{parse, LoadCli};
use crate::arrays::{angle_unit, angles_from, array2, values_of};
use crate::errors::{hf, HairfitError};
use crate::interrupt::off_gil;

/// Loaded samples (angles in radians inside) with the loader's report on every row.
#[pyclass(module = "hairfit._native", frozen)]
pub(crate) struct Data {
    pub(crate) ds: Dataset,
    pub(crate) report: LoadReport,
    /// The file and loader options, when loaded from a file (a fit records them as the CLI's).
    pub(crate) source: Option<(PathBuf, LoadOptions)>,
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
        array2(py, shape, values.clone()).map(Some)
    }
}

/// `hairfit load PATH [loader options]`: the samples and the report.
#[pyfunction]
pub(crate) fn load(py: Python<'_>, path: PathBuf, load_args: Vec<String>) -> PyResult<Data> {
    let cli: LoadCli = parse(load_args)?;
    let options = cli.load;
    let (ds, report) = off_gil(py, || hairfit::data::load(&path, &options))?.map_err(hf)?;
    Ok(Data {
        ds,
        report,
        source: Some((path, options)),
    })
}

/// Samples from arrays (angles in `angles`, values (n, channels)): the loader's report then
/// says every row was accepted, its lines the sample indices from 1.
#[pyfunction]
#[pyo3(signature = (theta_i, phi_i, theta_r, phi_r, radiance, sigma, weight, channels, angles))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn data_from_arrays<'py>(
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
        values_of(&theta_i),
        values_of(&phi_i),
        values_of(&theta_r),
        values_of(&phi_r),
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
    })
}
