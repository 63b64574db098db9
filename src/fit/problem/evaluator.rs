//! Data prepared for one fit space: the residual [`Space`], targets and weights per value
//! (log-space values that are not significantly positive become linear residuals), and the
//! mapping between solver parameters and natural parameter values.

use super::evaluation::{Evaluation, ScaleMode};
use super::forward::{FitParam, Forward, ParamSet};
use super::memo::PassMemo;
use super::FitData;
use crate::fit::bounds::Bound;
use nalgebra::DVector;

/// A parameter whose transform's slope is under 1/this of its steepest sits on its bound: within
/// 2.5e-7 of its range of it (both bounds) or 5e-7 above it (a lower bound only). Elsewhere the solver scales its column by
/// its norm as usual, so fits away from their bounds run exactly as before.
pub const ON_BOUND_FLATNESS: f64 = 1e3;
use crate::fit::loss::Loss;
use crate::geometry::Angles;

pub use crate::files::settings::Space;

/// Data prepared for one fit space plus everything fixed during a fit.
pub struct Evaluator<'f, F: Forward> {
    pub forward: &'f F,
    /// The data's angles, borrowed (a copy is 32 bytes per sample: 320 MB at 10M samples).
    pub angles: &'f [Angles],
    pub n_channels: usize,
    pub space: Space,
    pub loss: Loss,
    pub loss_scale: f64,
    /// `y` (linear) or `ln y` (log; `y` itself for linear-fallback rows).
    pub(super) target: Vec<f64>,
    /// Residual weight `1/σ` (log: `y/σ`), `√weight`, or 1.
    pub(super) w: Vec<f64>,
    /// Log space only: rows whose value is not significantly positive (`y ≤ 0`, or `y < 2σ`),
    /// fitted as linear residuals `w (y − s·S)` — a log would turn a zero reading into an
    /// arbitrary, hugely weighted outlier. They do not enter the closed-form scale.
    pub(super) lin: Vec<bool>,
    /// Fixed parameters (and the start values of free ones).
    pub base: ParamSet<F>,
    pub free: Vec<F::Param>,
    pub bounds: Vec<Bound>,
    /// Scale is explicit (robust loss) rather than projected.
    pub explicit_scale: bool,
    /// The latest value and gradient passes, reused at the same point.
    pub(super) memo: PassMemo<ParamSet<F>, F::Param>,
    /// Every value pass computes the gradients too (kept in the memo, within its budget), as a
    /// family with cheap gradients always does: for a fit whose trial steps are nearly always
    /// accepted, where the linearisation follows at the same point.
    pub gradients_with_values: bool,
}

/// A reading below this many σ is not significantly positive: its log is not approximately
/// Gaussian (the log-normal approximation σ_log = σ/y needs y ≫ σ), so it is fitted linearly.
pub const LOG_MIN_SNR: f64 = 5.0;

/// Values a log-space fit cannot take the logarithm of (fit.json `options.log_floored`).
pub use crate::files::Floored;

impl<'f, F: Forward> Evaluator<'f, F> {
    /// Prepare `data` for `space`; in log space values that are not significantly positive
    /// become linear residuals (see `lin`), counted in the returned [`Floored`].
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        forward: &'f F,
        data: &'f FitData,
        space: Space,
        loss: Loss,
        loss_scale: f64,
        base: ParamSet<F>,
        free: Vec<F::Param>,
    ) -> crate::Result<(Self, Floored)> {
        let nc = data.n_channels();
        let mut floored = Floored {
            count: vec![0; nc],
            floor: vec![0.0; nc],
        };
        if space == Space::Log {
            for c in 0..nc {
                let min_pos = (0..data.len())
                    .map(|i| data.values[i * nc + c])
                    .filter(|&v| v > 0.0 && v.is_finite())
                    .fold(f64::INFINITY, f64::min);
                if !min_pos.is_finite() {
                    return Err(crate::Error::Other(format!(
                        "channel `{}` has no positive value: a log-space fit is impossible; use --space linear",
                        data.channels[c]
                    )));
                }
                floored.floor[c] = 0.5 * min_pos;
            }
        }
        let mut target = Vec::with_capacity(data.values.len());
        let mut w = Vec::with_capacity(data.values.len());
        let mut lin = Vec::with_capacity(data.values.len());
        for (k, &y) in data.values.iter().enumerate() {
            let c = k % nc;
            let sigma = data.sigma.as_ref().map(|s| s[k]);
            let weight = data.weight.as_ref().map(|wt| wt[k].max(0.0).sqrt());
            let fallback =
                space == Space::Log && (y <= 0.0 || sigma.is_some_and(|s| y < LOG_MIN_SNR * s));
            let wk = match (space, fallback) {
                (Space::Linear, _) | (Space::Log, true) => match (sigma, weight) {
                    (Some(s), _) => 1.0 / s,
                    (None, Some(wt)) if space == Space::Linear => wt,
                    (None, Some(wt)) => wt / floored.floor[c],
                    (None, None) if space == Space::Linear => 1.0,
                    (None, None) => 1.0 / floored.floor[c],
                },
                (Space::Log, false) => match (sigma, weight) {
                    (Some(s), _) => y / s,
                    (None, Some(wt)) => wt,
                    (None, None) => 1.0,
                },
            };
            if fallback {
                floored.count[c] += 1;
            }
            target.push(if space == Space::Log && !fallback {
                y.ln()
            } else {
                y
            });
            w.push(if wk.is_finite() { wk } else { 0.0 });
            lin.push(fallback);
        }
        let bounds = free.iter().map(|&n| n.bound()).collect();
        Ok((
            Evaluator {
                forward,
                angles: &data.angles,
                n_channels: nc,
                space,
                loss,
                loss_scale,
                target,
                w,
                lin,
                base,
                free,
                bounds,
                explicit_scale: loss != Loss::L2,
                memo: PassMemo::default(),
                gradients_with_values: false,
            },
            floored,
        ))
    }

    /// At most `bytes` of recent model passes kept for reuse (default
    /// [`super::memo::MEMO_MAX_BYTES`]; 0 keeps none: every pass runs the model).
    pub fn with_memo_limit(mut self, bytes: usize) -> Self {
        self.memo = PassMemo::default();
        self.memo.max_bytes = bytes;
        self
    }

    /// Number of residuals.
    pub fn n_residuals(&self) -> usize {
        self.target.len()
    }

    /// Number of solver parameters (free shape parameters, plus scales when explicit).
    pub fn n_params(&self) -> usize {
        self.free.len()
            + if self.explicit_scale {
                self.n_channels
            } else {
                0
            }
    }

    /// Residual weights (for reports).
    pub fn weights(&self) -> &[f64] {
        &self.w
    }

    /// Natural values of the free parameters for internal `u`.
    pub fn natural(&self, u: &[f64]) -> Vec<f64> {
        self.bounds
            .iter()
            .zip(u)
            .map(|(b, &v)| b.to_natural(v))
            .collect()
    }

    /// Internal `u` of natural free values `x` (scale entries, when explicit, appended as given).
    pub fn internal(&self, x: &[f64]) -> Vec<f64> {
        self.bounds
            .iter()
            .zip(x)
            .map(|(b, &v)| b.to_internal(v))
            .collect()
    }

    /// Full parameter set with free values `x` (natural units).
    pub fn params_at(&self, x: &[f64]) -> ParamSet<F> {
        let mut p = self.base.clone();
        for (&n, &v) in self.free.iter().zip(x) {
            n.set(&mut p, v);
        }
        p
    }

    /// Solver parameters `u` as the passes take them: natural free values, the transforms'
    /// derivatives `dx/du` (the column factors) and the scale (projected, or `u`'s tail).
    pub fn solver_point<'u>(&self, u: &'u [f64]) -> (Vec<f64>, Vec<f64>, ScaleMode<'u>) {
        let nf = self.free.len();
        let x = self.natural(&u[..nf]);
        let dxdu: Vec<f64> = self
            .bounds
            .iter()
            .zip(u)
            .map(|(b, &v)| b.derivative(v))
            .collect();
        let mode = if self.explicit_scale {
            ScaleMode::ExplicitLog(&u[nf..])
        } else {
            ScaleMode::Projected
        };
        (x, dxdu, mode)
    }

    /// Per solver coordinate, the flatness of its bound transform at `u` where the parameter sits
    /// on its bound (the transform's slope under [`ON_BOUND_FLATNESS`]⁻¹ of its steepest), else
    /// 1: the LM solver's scaling reads it ([`crate::lm::Linearized::flatness`]). Explicit
    /// scales are never bounded.
    pub fn flatness(&self, u: &[f64]) -> DVector<f64> {
        DVector::from_iterator(
            u.len(),
            u.iter().enumerate().map(|(j, &v)| {
                let f = self.bounds.get(j).map_or(1.0, |b| b.flatness(v));
                if f > ON_BOUND_FLATNESS {
                    f
                } else {
                    1.0
                }
            }),
        )
    }

    /// Evaluate at solver parameters `u` (transforms applied; scale per `explicit_scale`).
    pub fn eval_internal(&self, u: &[f64], jac: bool) -> Evaluation {
        let (x, dxdu, mode) = self.solver_point(u);
        self.evaluate(&x, &dxdu, mode, jac)
    }
}
