//! What one evaluation of a fit's residual returns ([`Evaluation`]), how the per-channel scale
//! enters it ([`ScaleMode`]), and the fixed-chunk sums that keep results bit-identical for any
//! thread count.

use rayon::prelude::*;

/// Samples per parallel work item and per partial sum (fixed: part of the result's bit pattern).
pub const CHUNK: usize = 256;

/// How the per-channel scale enters an evaluation.
#[derive(Debug, Clone, Copy)]
pub enum ScaleMode<'a> {
    /// Closed-form optimum inside the residual (variable projection).
    Projected,
    /// `ln s_c` are the trailing parameters.
    ExplicitLog(&'a [f64]),
    /// Fixed `s_c`, with Jacobian columns `∂r/∂s_c` appended (for standard errors).
    FixedNatural(&'a [f64]),
}

/// One evaluation of the residual vector.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// Loss-adjusted residuals `r̃`, row `i * nc + c`.
    pub residual: Vec<f64>,
    /// Residuals before the loss (normalised, in the fit space).
    pub raw: Vec<f64>,
    /// Final robust-loss weights `ρ′` (1 = not down-weighted).
    pub robust_weight: Vec<f64>,
    /// Model values `S` (times `cos θ_i` for radiance; without scale).
    pub model: Vec<f64>,
    /// Per-channel scale `s_c`.
    pub scale: Vec<f64>,
    /// Jacobian, row-major `(i * nc + c) * n_cols + j`, when asked for.
    pub jacobian: Option<Vec<f64>>,
    /// Number of Jacobian columns.
    pub n_cols: usize,
}

impl Evaluation {
    /// `½‖r̃‖²`.
    pub fn cost(&self) -> f64 {
        0.5 * chunked_sum(&self.residual, |r| r * r)
    }
}

/// Sum `f(x)` over `xs` in fixed chunks added in order (deterministic for any thread count).
pub fn chunked_sum(xs: &[f64], f: impl Fn(f64) -> f64 + Sync) -> f64 {
    xs.par_chunks(CHUNK * 4)
        .map(|c| c.iter().map(|&x| f(x)).sum::<f64>())
        .collect::<Vec<_>>()
        .into_iter()
        .sum()
}
