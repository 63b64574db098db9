//! Test support: run the library's Levenberg–Marquardt solver to the end and collect what the
//! tests check (parameters, residuals, Jacobian, counts, why it stopped). Shared by
//! `tests/fit/lm_solver.rs`, `tests/fit/nist.rs` and `benches/lm.rs` (with `#[path]`).

// Each including crate uses a different part of this file.
#![allow(dead_code)]

use argmin::core::{Executor, Jacobian, Operator, State};
use hairfit::lm::{LevenbergMarquardt, LmTermination, DEFAULT_FTOL, DEFAULT_XTOL};
use hairfit::{Error, Result};
use nalgebra::{DMatrix, DVector};

/// Options for [`minimize`].
#[derive(Debug, Clone, Copy)]
pub struct LmOptions {
    /// Relative cost-reduction tolerance.
    pub ftol: f64,
    /// Relative scaled-step tolerance.
    pub xtol: f64,
    /// Gradient cosine tolerance.
    pub gtol: f64,
    /// Maximum number of trial steps (residual evaluations after the first).
    pub max_iters: u64,
    /// Statistical stop: degrees of freedom and predicted-χ² tolerance (0: off).
    pub dof: usize,
    pub chi2: f64,
    /// End at an accepted step meeting `ftol` without linearising there.
    pub lazy_final: bool,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            ftol: DEFAULT_FTOL,
            xtol: DEFAULT_XTOL,
            gtol: 0.0,
            max_iters: 2000,
            dof: 0,
            chi2: 0.0,
            lazy_final: false,
        }
    }
}

/// The outcome of [`minimize`].
#[derive(Debug, Clone)]
pub struct LmReport {
    /// Best parameters found.
    pub param: DVector<f64>,
    /// Residuals at `param`.
    pub residuals: DVector<f64>,
    /// Jacobian at `param`.
    pub jacobian: DMatrix<f64>,
    /// `½‖r‖²` at `param`.
    pub cost: f64,
    /// Trial steps taken.
    pub iterations: u64,
    /// Jacobian evaluations.
    pub jacobian_evals: u64,
    /// Why it stopped; `None` means the iteration limit was hit.
    pub termination: Option<LmTermination>,
}

impl LmReport {
    /// Whether a convergence criterion (not the iteration limit) stopped the solver.
    pub fn converged(&self) -> bool {
        self.termination.is_some()
    }
}

/// Run [`LevenbergMarquardt`] in an argmin `Executor` from `x0`.
pub fn minimize<O>(problem: O, x0: DVector<f64>, options: LmOptions) -> Result<LmReport>
where
    O: Operator<Param = DVector<f64>, Output = DVector<f64>>
        + Jacobian<Param = DVector<f64>, Jacobian = DMatrix<f64>>,
{
    let solver = LevenbergMarquardt::new()
        .with_tolerances(options.ftol, options.xtol, options.gtol)?
        .with_statistical_tolerance(options.dof, options.chi2)?;
    let solver = if options.lazy_final {
        solver.with_lazy_final_linearization()
    } else {
        solver
    };
    let res = Executor::new(problem, solver)
        .configure(|s| s.param(x0).max_iters(options.max_iters).counting(true))
        .run()
        .map_err(|e| Error::Other(format!("Levenberg-Marquardt failed: {e}")))?;
    let termination = res.solver().termination();
    let mut state = res.state().clone();
    let jacobian_evals = state
        .get_func_counts()
        .get("jacobian_count")
        .copied()
        .unwrap_or(0);
    let iterations = state.get_iter();
    let cost = state.get_cost();
    // The current iterate is the best one: LM only accepts cost-decreasing steps.
    let param = state.take_param().unwrap_or_default();
    let residuals = state.take_residuals().unwrap_or_default();
    let jacobian = state.take_jacobian().unwrap_or_default();
    Ok(LmReport {
        param,
        residuals,
        jacobian,
        cost,
        iterations,
        jacobian_evals,
        termination,
    })
}
