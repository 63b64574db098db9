//! An engine's inputs fitted to the source fit's `S` in log space, for the exports whose engine
//! is not a variant of the Chiang model (`--to unity`): the engine gives its `S` and `∂S/∂x` for
//! free variables `x` ([`LogModel`]); residuals are `ln(S_engine + f_c) − ln(S_source + f_c)`
//! with [`super::mapping`]'s floor `f_c`, over the same directions (measured plus the dense
//! sphere), solved by the project's Levenberg–Marquardt from each start, best kept.

use argmin::core::{Jacobian, Operator};
use nalgebra::{DMatrix, DVector};

use super::reference::{channel_floor, least_squares, log_floored, max, rms, MAX_ITERATIONS};
use crate::error::{Error, Result};

/// An engine's `S` as a function of its free (unconstrained) variables.
pub trait LogModel: Sync {
    /// `S` at every direction and channel, `out[k·n + c]`.
    fn values(&self, x: &[f64]) -> Vec<f64>;
    /// `S` and its Jacobian, row-major: `jac[row·x.len() + j] = ∂S_row/∂x_j`.
    fn jacobian(&self, x: &[f64]) -> (Vec<f64>, Vec<f64>);
}

/// The source's `S` in log space with its per-channel floor.
#[derive(Debug, Clone)]
pub struct LogTarget {
    target_log: Vec<f64>,
    floor: Vec<f64>,
    n: usize,
}

impl LogTarget {
    /// `target[k·n + c]` for `n` channels.
    pub fn new(target: &[f64], n: usize) -> LogTarget {
        let floor = channel_floor(target, n);
        LogTarget {
            target_log: log_floored(target, &floor, n),
            floor,
            n,
        }
    }

    /// `ln(S + f_c) − ln(S_source + f_c)` for every row.
    pub fn residuals(&self, values: &[f64]) -> Vec<f64> {
        log_floored(values, &self.floor, self.n)
            .iter()
            .zip(&self.target_log)
            .map(|(a, b)| a - b)
            .collect()
    }

    /// `x` with its log-gain variable `x[gain]` moved so the mean log residual of `model` is
    /// zero (where each LM start begins: the light's level matched, the shape left alone).
    pub fn with_best_gain(&self, model: &dyn LogModel, mut x: Vec<f64>, gain: usize) -> Vec<f64> {
        let r = self.residuals(&model.values(&x));
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        if mean.is_finite() {
            x[gain] -= mean;
        }
        x
    }

    /// `|Δ ln S|` for every row.
    pub fn errors(&self, values: &[f64]) -> Vec<f64> {
        self.residuals(values).iter().map(|r| r.abs()).collect()
    }
}

/// How far an engine's S is from the source's: rms and max `|Δ ln S|` over every row, and the
/// rms over the measured directions' rows (they come first), None without any.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogErrors {
    pub rms: f64,
    pub max: f64,
    pub rms_measured: Option<f64>,
}

impl LogErrors {
    /// The summary of `errors`, whose first `measured_rows` rows are the measured directions'.
    pub fn of(errors: &[f64], measured_rows: usize) -> LogErrors {
        LogErrors {
            rms: rms(errors),
            max: max(errors),
            rms_measured: (measured_rows > 0).then(|| rms(&errors[..measured_rows])),
        }
    }
}

/// The best of the LM runs: its variables, cost `½‖r‖²`, and the work done.
#[derive(Debug, Clone)]
pub struct LogFit {
    pub x: Vec<f64>,
    pub cost: f64,
    pub iterations: u64,
    pub starts: usize,
}

/// Fit `model` to `target` from each of `starts` (at most [`MAX_ITERATIONS`] LM steps each).
pub fn fit_log(model: &dyn LogModel, target: &LogTarget, starts: &[Vec<f64>]) -> Result<LogFit> {
    let problem = Problem { model, target };
    let mut best: Option<LogFit> = None;
    let mut iterations = 0;
    for x0 in starts {
        let (x, steps) = least_squares(problem, x0, MAX_ITERATIONS)?;
        iterations += steps;
        let x = x.as_slice().to_vec();
        let r = target.residuals(&model.values(&x));
        let cost = 0.5 * r.iter().map(|v| v * v).sum::<f64>();
        if cost.is_finite() && best.as_ref().is_none_or(|b| cost < b.cost) {
            best = Some(LogFit {
                x,
                cost,
                iterations: 0,
                starts: starts.len(),
            });
        }
    }
    let mut best = best.ok_or_else(|| {
        Error::Other("the engine mapping fit ended non-finite from every start".into())
    })?;
    best.iterations = iterations;
    Ok(best)
}

/// The least-squares problem as argmin takes it (by value: a pair of references).
#[derive(Clone, Copy)]
struct Problem<'a> {
    model: &'a dyn LogModel,
    target: &'a LogTarget,
}

impl Operator for Problem<'_> {
    type Param = DVector<f64>;
    type Output = DVector<f64>;
    fn apply(&self, x: &DVector<f64>) -> std::result::Result<DVector<f64>, argmin::core::Error> {
        // A non-finite residual is a failed trial step to the solver, not an error.
        let values = self.model.values(x.as_slice());
        Ok(DVector::from_vec(self.target.residuals(&values)))
    }
}

impl Jacobian for Problem<'_> {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;
    fn jacobian(&self, x: &DVector<f64>) -> std::result::Result<DMatrix<f64>, argmin::core::Error> {
        let nx = x.len();
        let (values, jac) = self.model.jacobian(x.as_slice());
        let (floor, n) = (&self.target.floor, self.target.n);
        // d ln(S + f)/dx = (dS/dx)/(S + f).
        let m = DMatrix::from_fn(values.len(), nx, |k, j| {
            jac[k * nx + j] / (values[k] + floor[k % n])
        });
        if m.iter().all(|v| v.is_finite()) {
            Ok(m)
        } else {
            Err(argmin::core::Error::msg(
                "non-finite Jacobian in the engine mapping fit",
            ))
        }
    }
}
