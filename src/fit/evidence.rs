//! What the verdict and the suggestions look at ([`Evidence`]): the fit's data, evaluator, final
//! evaluation and the fit.json entries assembled so far. Its own module so that the verdict and
//! the suggestions both read it without importing each other.

use super::problem::{Evaluation, Evaluator, FitData, Forward, ParamSet};
use crate::files::{FitStatus, ParameterEntry, ScaleEntry, TraceStage};

/// A residual beyond this many robust noise levels is "large" (evidence for a robust loss).
pub const LARGE_RESIDUAL: f64 = 5.0;

/// What the verdict looks at: the fit's data, its evaluator and final evaluation, and the
/// entries already assembled for fit.json.
pub struct Evidence<'a, 'e, 'f, F: Forward> {
    pub data: &'a FitData,
    pub ev: &'e Evaluator<'f, F>,
    pub e: &'a Evaluation,
    /// The worst row's relative misfit (see [`super::EXACT_MISFIT`]).
    pub worst_row_misfit: f64,
    /// Every parameter at the optimum (natural units).
    pub params: &'a ParamSet<F>,
    pub status: FitStatus,
    pub parameters: &'a [ParameterEntry],
    pub scale: &'a [ScaleEntry],
    pub trace: &'a [TraceStage],
    pub warnings: &'a [String],
    /// Residual degrees of freedom (residuals − free parameters − scales).
    pub dof: usize,
}

impl<F: Forward> Evidence<'_, '_, '_, F> {
    /// Number of fitted quantities: free parameters and per-channel scales.
    pub fn n_fitted(&self) -> usize {
        self.e.raw.len().saturating_sub(self.dof)
    }
}
