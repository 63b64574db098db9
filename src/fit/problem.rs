//! The least-squares problem of a fit: the samples to fit ([`FitData`]) and the argmin
//! `Operator` + `Jacobian` the solvers run on. Its parts: the forward model with exact Jacobians
//! (`forward`), data prepared for a fit space (`evaluator`), the residual vector (`residual`) and
//! the variable-projected per-channel scale (`projection`).

use nalgebra::DVector;

use crate::geometry::Angles;

mod evaluation;
mod evaluator;
mod forward;
mod linearize;
mod memo;
mod passes;
mod projection;
mod residual;

pub use evaluation::{chunked_sum, Evaluation, ScaleMode, CHUNK};
pub use evaluator::{Evaluator, Floored, Space, LOG_MIN_SNR};
pub(crate) use forward::with_dual_dim;
pub use forward::{FitParam, Forward, ParamSet};
pub use linearize::Linearization;

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

    /// Sample `i`'s angles in degrees, `[θ_i, φ_i, θ_r, φ_r]` (the order reports use).
    pub fn angles_deg(&self, i: usize) -> [f64; 4] {
        let a = &self.angles[i];
        [a.theta_i, a.phi_i, a.theta_r, a.phi_r].map(f64::to_degrees)
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

/// The argmin problem over solver parameters `u`: trial costs and linearisations accumulated in
/// chunks (the Jacobian is never stored), abandoned mid-pass when `cancel` is raised.
pub struct LsqProblem<'e, 'f, F: Forward> {
    pub ev: &'e Evaluator<'f, F>,
    pub cancel: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

impl<F: Forward> crate::lm::LeastSquares for LsqProblem<'_, '_, F> {
    /// The fit-space scale of the trial, so the linearisation there skips a model pass.
    type Trial = Option<Vec<f64>>;

    /// A cancelled pass is an infinite norm: the step is rejected and the solver stops at the
    /// iteration boundary with its best point.
    fn trial(&self, u: &DVector<f64>) -> Result<(f64, Self::Trial), argmin::core::Error> {
        Ok(
            match self.ev.cost_and_scale(u.as_slice(), self.cancel.as_deref()) {
                Some((c, sq)) => ((2.0 * c).sqrt(), Some(sq)),
                None => (f64::INFINITY, None),
            },
        )
    }

    fn linearize(
        &self,
        u: &DVector<f64>,
        scale: Self::Trial,
    ) -> Result<crate::lm::Linearized, argmin::core::Error> {
        let lin = self
            .ev
            .linearize_internal(u.as_slice(), scale, self.cancel.as_deref())
            .ok_or_else(|| argmin::core::Error::msg("interrupted"))?;
        let mut lin = lin.into_lm();
        lin.flatness = Some(self.ev.flatness(u.as_slice()));
        Ok(lin)
    }
}
