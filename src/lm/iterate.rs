//! One Levenberg–Marquardt iteration as argmin's `Solver`: `init` evaluates the start, each
//! `next_iter` tries one step, accepts or rejects it and updates the trust radius.

use argmin::core::{
    Error as ArgminError, Problem, Solver, State, TerminationReason, TerminationStatus, KV,
};
use nalgebra::DVector;

use super::blocks::block_trust_region_step;
use super::least_squares::{LeastSquares, Linearized, System};
use super::step::{
    column_norms, gradient_cosine, gradient_cosine_of, scaled_gradient, svd_with_projection,
    trust_region_step,
};
use super::{Factored, LevenbergMarquardt, LmState, LmTermination};

impl LevenbergMarquardt {
    /// Update the scaling from a new linearisation (`M`, `t`; `‖r‖ = fnorm`), factor it and run
    /// the gradient test.
    fn refresh(&mut self, lin: &Linearized, fnorm: f64) {
        let col_norms = match &lin.system {
            System::Dense { matrix, .. } => column_norms(matrix),
            System::Blocks(b) => b.column_norms(),
        };
        // A column whose parameter sits where its transform is flat (on its bound) is scaled as
        // if the transform were at its steepest: by its own norm, that coordinate's steps would
        // be as many times larger than the others' as the transform is flatter, and every one
        // rejected, so a run starting there (a profile's re-fit of a fit with a parameter on
        // its bound) stopped where it started.
        let col_norms = match &lin.flatness {
            Some(f) => col_norms.zip_map(f, |c, f| if f > 1.0 { c * f } else { c }),
            None => col_norms,
        };
        let n = col_norms.len();
        if self.diag.len() != n {
            self.diag = col_norms.map(|c| if c > 0.0 && c.is_finite() { c } else { 1.0 });
        } else {
            self.diag.zip_apply(&col_norms, |d, c| *d = d.max(c));
        }
        self.gradient = lin.gradient();
        if fnorm == 0.0 {
            // Also covers m = 0; nothing to factor.
            self.status = Some(LmTermination::ZeroResidual);
            return;
        }
        let cosine = match &lin.system {
            System::Dense { matrix, residuals } => {
                gradient_cosine(matrix, residuals, &col_norms, fnorm)
            }
            System::Blocks(_) => gradient_cosine_of(&self.gradient, &col_norms, fnorm),
        };
        if cosine <= self.gtol {
            self.status = Some(LmTermination::GradientConverged);
        }
        self.factor = Some(match &lin.system {
            System::Dense { matrix, residuals } => {
                let mut scaled = matrix.clone();
                for (j, mut col) in scaled.column_iter_mut().enumerate() {
                    col /= self.diag[j];
                }
                Factored::Svd(svd_with_projection(scaled, residuals))
            }
            System::Blocks(b) => Factored::Blocks(b.scale_columns(&self.diag)),
        });
        if self.status.is_none() && self.chi2_tol > 0.0 && self.dof > 0 {
            let decrement = self.gauss_newton_decrement();
            if decrement * self.dof as f64 <= self.chi2_tol * fnorm * fnorm {
                self.status = Some(LmTermination::StatisticallyConverged);
            }
        }
    }

    /// `‖J p‖²` of the undamped (Gauss–Newton) step at the current factorisation: the decrease of
    /// `‖r‖²` the linear model predicts for going all the way to its minimum.
    fn gauss_newton_decrement(&self) -> f64 {
        match &self.factor {
            Some(Factored::Svd(svd)) => trust_region_step(svd, f64::INFINITY, 0.0, self.rows).jp2,
            Some(Factored::Blocks(scaled)) => {
                block_trust_region_step(scaled, f64::INFINITY, 0.0, self.rows).jp2
            }
            None => f64::INFINITY,
        }
    }
}

/// The state at an accepted linearisation: a dense one keeps its Jacobian and residuals there
/// (argmin's usual fields); a block one has no dense Jacobian to keep.
fn with_linearization(state: LmState, lin: Linearized) -> LmState {
    match lin.system {
        System::Dense { matrix, residuals } => state.residuals(residuals).jacobian(matrix),
        System::Blocks(_) => state,
    }
}

/// The linearisation at `x` after a trial evaluation there, checked for shape and finiteness.
fn linearize_checked<O: LeastSquares>(
    problem: &mut Problem<O>,
    x: &DVector<f64>,
    trial: O::Trial,
) -> Result<Linearized, ArgminError> {
    let lin = problem.problem("jacobian_count", |p| p.linearize(x, trial))?;
    match &lin.system {
        System::Dense { matrix, residuals } => {
            if matrix.nrows() != residuals.len() || matrix.ncols() != x.len() {
                return Err(anyhow_error(&format!(
                    "Jacobian is {}x{} but residuals have {} rows and parameters {} entries",
                    matrix.nrows(),
                    matrix.ncols(),
                    residuals.len(),
                    x.len()
                )));
            }
        }
        System::Blocks(b) => {
            let bad = b.ncols != x.len()
                || b.blocks.iter().any(|blk| {
                    blk.matrix.ncols() != b.shared.len() + blk.local.len()
                        || blk.matrix.nrows() != blk.rhs.len()
                });
            if bad {
                return Err(anyhow_error(&format!(
                    "block linearisation does not match {} parameters or its residuals",
                    x.len()
                )));
            }
        }
    }
    Ok(lin)
}

impl<O: LeastSquares> Solver<O, LmState> for LevenbergMarquardt {
    fn name(&self) -> &str {
        "Levenberg-Marquardt (Moré)"
    }

    fn init(
        &mut self,
        problem: &mut Problem<O>,
        mut state: LmState,
    ) -> std::result::Result<(LmState, Option<KV>), ArgminError> {
        let x0 = state.take_param().ok_or_else(|| {
            anyhow_error("LevenbergMarquardt needs an initial parameter vector: configure the Executor with `.param(x0)`")
        })?;
        if x0.is_empty() {
            return Err(anyhow_error(
                "LevenbergMarquardt needs at least one parameter",
            ));
        }
        let (fnorm, trial) = problem.problem("operator_count", |p| p.trial(&x0))?;
        if !fnorm.is_finite() {
            return Err(anyhow_error(
                "residuals at the initial parameters are not finite; choose another start",
            ));
        }
        let lin = linearize_checked(problem, &x0, trial)?;
        if !lin.all_finite() {
            return Err(anyhow_error(
                "Jacobian at the initial parameters is not finite; choose another start",
            ));
        }
        self.diag = DVector::zeros(0);
        self.factor = None;
        self.status = None;
        self.costs.clear();
        self.first_step = true;
        self.lambda = 0.0;
        self.rows = lin.rows;
        self.refresh(&lin, fnorm);
        let xnorm = self.diag.component_mul(&x0).norm();
        self.delta = if xnorm > 0.0 {
            self.radius_factor * xnorm
        } else {
            self.radius_factor
        };
        let cost = 0.5 * fnorm * fnorm;
        let kv = argmin::kv!("cost" => cost; "delta" => self.delta;);
        Ok((
            with_linearization(state.param(x0).cost(cost), lin),
            Some(kv),
        ))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        mut state: LmState,
    ) -> std::result::Result<(LmState, Option<KV>), ArgminError> {
        let factor = self.factor.as_ref().ok_or_else(|| {
            anyhow_error("LevenbergMarquardt: no factorisation; was init run and not converged?")
        })?;
        let x = state
            .get_param()
            .ok_or_else(|| anyhow_error("LevenbergMarquardt: param not set"))?
            .clone();
        let fnorm = (2.0 * state.get_cost()).sqrt();
        let rows = self.rows;

        let step = match factor {
            Factored::Svd(svd) => trust_region_step(svd, self.delta, self.lambda, rows),
            Factored::Blocks(scaled) => {
                block_trust_region_step(scaled, self.delta, self.lambda, rows)
            }
        };
        let p = step.z.component_div(&self.diag);
        let pnorm = step.z.norm();
        if self.first_step {
            self.delta = self.delta.min(pnorm);
            self.first_step = false;
        }
        let x_new = &x + &p;
        // A step into a region where the model is undefined is a failed step, not an error.
        let (fnorm1, trial) = problem.problem("operator_count", |p| p.trial(&x_new))?;
        let fnorm1 = if fnorm1.is_finite() {
            fnorm1
        } else {
            f64::INFINITY
        };
        let mut trial = Some(trial);

        let actred = if 0.1 * fnorm1 < fnorm {
            1.0 - (fnorm1 / fnorm).powi(2)
        } else {
            -1.0
        };
        let f2 = fnorm * fnorm;
        let prered = (step.jp2 + 2.0 * step.lambda * pnorm * pnorm) / f2;
        let dirder = -(step.jp2 + step.lambda * pnorm * pnorm) / f2;
        let ratio = if prered > 0.0 { actred / prered } else { 0.0 };

        // Moré's radius update: shrink on poor agreement, double on good agreement.
        if ratio <= 0.25 {
            let mut temp = if actred >= 0.0 {
                0.5
            } else {
                0.5 * dirder / (dirder + 0.5 * actred)
            };
            if 0.1 * fnorm1 >= fnorm || temp < 0.1 || !temp.is_finite() {
                temp = 0.1;
            }
            self.delta = temp * self.delta.min(pnorm / 0.1);
            self.lambda = step.lambda / temp;
        } else if step.lambda == 0.0 || ratio >= 0.75 {
            self.delta = pnorm / 0.5;
            self.lambda = 0.5 * step.lambda;
        } else {
            self.lambda = step.lambda;
        }

        // Near a minimum of a small-residual problem the cost change falls below its rounding
        // noise (r = f - y cancels), so the ratio test rejects steps that are still accurate.
        // There the gradient, which shrinks linearly rather than quadratically with the
        // distance to the minimum, decides instead.
        let mut accepted = ratio >= 1e-4;
        let mut noise_accepted = false;
        let mut j_new = None;
        if !accepted && fnorm1.is_finite() && prered <= self.noise && actred >= -self.noise {
            let trial = trial.take().expect("trial is taken once");
            let lin = linearize_checked(problem, &x_new, trial)?;
            let old = scaled_gradient(&self.gradient, &self.diag);
            if lin.all_finite() && scaled_gradient(&lin.gradient(), &self.diag) < old {
                accepted = true;
                noise_accepted = true;
            }
            j_new = Some(lin);
        }
        let cost_converged = actred.abs() <= self.ftol && prered <= self.ftol && 0.5 * ratio <= 1.0;
        if accepted && self.lazy_final && j_new.is_none() && cost_converged {
            // The cost test below ends the run here: no linearisation at the new point.
            state = state.param(x_new.clone()).cost(0.5 * fnorm1 * fnorm1);
            state.take_jacobian();
            state.take_residuals();
        } else if accepted {
            let lin = match j_new {
                Some(lin) => lin,
                None => {
                    let trial = trial.take().expect("trial is taken once");
                    linearize_checked(problem, &x_new, trial)?
                }
            };
            if lin.rows != rows {
                return Err(anyhow_error(&format!(
                    "residual vector changed length from {rows} to {} between evaluations",
                    lin.rows
                )));
            }
            if !lin.all_finite() {
                return Err(anyhow_error(&format!(
                    "Jacobian is not finite at parameters {:?} where the residuals are finite; \
                     check the model's derivatives",
                    x_new.as_slice()
                )));
            }
            self.refresh(&lin, fnorm1);
            let cost = 0.5 * fnorm1 * fnorm1;
            state = with_linearization(state.param(x_new.clone()).cost(cost), lin);
        }
        let xnorm = self
            .diag
            .component_mul(if accepted { &x_new } else { &x })
            .norm();

        if self.status.is_none() {
            let eps = f64::EPSILON;
            self.status = if cost_converged {
                Some(LmTermination::CostConverged)
            } else if self.delta <= self.xtol * xnorm || self.delta <= f64::MIN_POSITIVE {
                Some(LmTermination::StepConverged)
            } else if (self.ftol > 0.0
                && actred.abs() <= eps
                && prered <= eps
                && 0.5 * ratio <= 1.0)
                || self.delta <= eps * xnorm
            {
                Some(LmTermination::MachinePrecision)
            } else {
                None
            };
        }

        self.costs.push(state.get_cost());
        if self.status.is_none() && self.stalled() {
            self.status = Some(LmTermination::Stalled);
        }

        let kv = argmin::kv!(
            "cost" => state.get_cost();
            "lambda" => step.lambda;
            "delta" => self.delta;
            "step_norm" => pnorm;
            "gain_ratio" => ratio;
            "accepted" => accepted;
            "noise_accepted" => noise_accepted;
        );
        Ok((state, Some(kv)))
    }

    fn terminate(&mut self, _state: &LmState) -> TerminationStatus {
        if self.cancelled() {
            return TerminationStatus::Terminated(TerminationReason::Interrupt);
        }
        match self.status {
            Some(s) => TerminationStatus::Terminated(match s {
                LmTermination::CostConverged
                | LmTermination::StepConverged
                | LmTermination::GradientConverged
                | LmTermination::StatisticallyConverged
                | LmTermination::Stalled
                | LmTermination::ZeroResidual => TerminationReason::SolverConverged,
                LmTermination::MachinePrecision => TerminationReason::SolverExit(s.text().into()),
            }),
            None => TerminationStatus::NotTerminated,
        }
    }
}

/// An argmin error carrying `msg`.
fn anyhow_error(msg: &str) -> ArgminError {
    ArgminError::msg(msg.to_string())
}
