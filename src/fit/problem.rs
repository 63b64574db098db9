//! The least-squares problem of a fit: the samples to fit ([`FitData`]) and the argmin
//! `Operator` + `Jacobian` the solvers run on. Its parts: the forward model with exact Jacobians
//! (`forward`), data prepared for a fit space (`evaluator`), the residual vector (`residual`) and
//! the variable-projected per-channel scale (`projection`).

use nalgebra::{DMatrix, DVector};

use crate::model::Angles;

mod evaluator;
mod forward;
mod projection;
mod residual;

pub use evaluator::{Evaluator, Floored, Space, LOG_MIN_SNR};
pub use forward::{gradients, FitParam, Forward, ModelForward, ParamSet};
pub use residual::{chunked_sum, Evaluation, ScaleMode, CHUNK};

/// Samples to fit: angles (radians) and values row-major `i * n_channels + c`.
#[derive(Debug, Clone, Default)]
pub struct FitData {
    pub channels: Vec<String>,
    pub angles: Vec<Angles>,
    pub values: Vec<f64>,
    /// Standard deviation of each value, same layout as `values`.
    pub sigma: Option<Vec<f64>>,
    /// Weight of each value, same layout as `values`.
    pub weight: Option<Vec<f64>>,
    /// Source line of each sample (1-based), for reports.
    pub line: Vec<u64>,
}

impl FitData {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.angles.len()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.angles.is_empty()
    }

    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        self.channels.len()
    }

    /// The samples at `idx` (in that order).
    pub fn subset(&self, idx: &[usize]) -> FitData {
        let nc = self.n_channels();
        let rows = |v: &Vec<f64>| -> Vec<f64> {
            idx.iter()
                .flat_map(|&i| v[i * nc..(i + 1) * nc].iter().copied())
                .collect()
        };
        FitData {
            channels: self.channels.clone(),
            angles: idx.iter().map(|&i| self.angles[i]).collect(),
            values: rows(&self.values),
            sigma: self.sigma.as_ref().map(rows),
            weight: self.weight.as_ref().map(rows),
            line: idx
                .iter()
                .map(|&i| self.line.get(i).copied().unwrap_or(i as u64 + 1))
                .collect(),
        }
    }
}

/// The argmin problem over solver parameters `u`.
pub struct LsqProblem<'e, 'f, F: Forward> {
    pub ev: &'e Evaluator<'f, F>,
}

impl<F: Forward> argmin::core::Operator for LsqProblem<'_, '_, F> {
    type Param = DVector<f64>;
    type Output = DVector<f64>;
    fn apply(&self, u: &DVector<f64>) -> Result<DVector<f64>, argmin::core::Error> {
        Ok(DVector::from_vec(
            self.ev.eval_internal(u.as_slice(), false).residual,
        ))
    }
}

impl<F: Forward> argmin::core::Jacobian for LsqProblem<'_, '_, F> {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;
    fn jacobian(&self, u: &DVector<f64>) -> Result<DMatrix<f64>, argmin::core::Error> {
        let e = self.ev.eval_internal(u.as_slice(), true);
        let m = e.residual.len();
        Ok(DMatrix::from_row_slice(
            m,
            e.n_cols,
            e.jacobian.as_deref().unwrap_or(&[]),
        ))
    }
}
