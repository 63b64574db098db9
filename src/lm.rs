//! Levenberg–Marquardt as an argmin `Solver`, plus the covariance and correlation of the fitted
//! parameters.
//!
//! The algorithm is Moré's (1978) trust-region LM as in MINPACK `lmder`: the step solves
//! `min ‖J p + r‖² + λ‖D p‖²` with `D` the running maximum of the Jacobian's column norms, and `λ`
//! is chosen so that the scaled step `‖D p‖` fits the trust radius `Δ`, which grows or shrinks
//! with the ratio of actual to predicted reduction. The damped system is solved through one SVD
//! of the scaled Jacobian `J D⁻¹` per Jacobian (after a QR reduction when it is tall), never
//! through the normal equations, so the conditioning of `J` is not squared and retrying a step
//! with another `λ` costs no refactorisation. Where the cost change drops below rounding noise,
//! the scaled gradient judges steps instead (see [`DEFAULT_COST_NOISE`]).
//!
//! One argmin iteration is one trial step (one residual evaluation); a Jacobian is evaluated only
//! after an accepted step. The state's cost is `½‖r‖²`.

use argmin::core::{
    Error as ArgminError, Executor, IterState, Jacobian, Operator, Problem, Solver, State,
    TerminationReason, TerminationStatus, KV,
};
use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};

/// The argmin state the solver runs on: param, residuals and Jacobian as nalgebra types.
pub type LmState = IterState<DVector<f64>, (), DMatrix<f64>, (), DVector<f64>, f64>;

/// Why the solver stopped (MINPACK's `info` codes, named).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LmTermination {
    /// Relative reduction of the cost (actual and predicted) is at most `ftol`.
    CostConverged,
    /// Trust radius is at most `xtol` times the scaled parameter norm.
    StepConverged,
    /// Cosine between residuals and every Jacobian column is at most `gtol`.
    GradientConverged,
    /// Residuals are exactly zero.
    ZeroResidual,
    /// A tolerance is below machine precision and the iterate can no longer improve.
    MachinePrecision,
}

impl LmTermination {
    /// Text for the argmin termination reason.
    fn text(self) -> &'static str {
        match self {
            LmTermination::CostConverged => "relative cost reduction below ftol",
            LmTermination::StepConverged => "relative step below xtol",
            LmTermination::GradientConverged => "scaled gradient below gtol",
            LmTermination::ZeroResidual => "residuals are zero",
            LmTermination::MachinePrecision => {
                "no further improvement possible at machine precision"
            }
        }
    }
}

/// SVD of the scaled Jacobian `J D⁻¹ = U Σ Vᵀ`, with `g = Uᵀ r`, kept until the next Jacobian.
#[derive(Debug, Clone)]
struct ScaledSvd {
    sigma: DVector<f64>,
    v_t: DMatrix<f64>,
    g: DVector<f64>,
}

/// A trial step in scaled coordinates `z = D p`, with what the ratio test needs.
#[derive(Debug, Clone)]
struct TrialStep {
    /// Scaled step `z = D p`.
    z: DVector<f64>,
    /// Damping `λ` that produced it.
    lambda: f64,
    /// `‖J p‖²`.
    jp2: f64,
}

/// Moré–MINPACK Levenberg–Marquardt for nonlinear least squares `min ½‖r(x)‖²`.
///
/// Problem: argmin [`Operator`] (residuals `r(x)`, `DVector<f64>`) and [`Jacobian`] (`m×n`
/// `DMatrix<f64>`). Use it with `Executor::new(problem, LevenbergMarquardt::new())` and
/// `.configure(|s| s.param(x0).max_iters(n))`, or through [`minimize`].
///
/// ```
/// use argmin::core::{Error, Executor, Jacobian, Operator, State};
/// use hairfit::lm::LevenbergMarquardt;
/// use nalgebra::{DMatrix, DVector};
///
/// /// Fit y = a·exp(b·t) to three points.
/// struct Exp;
/// const T: [f64; 3] = [0.0, 1.0, 2.0];
/// /// y = 2·exp(t/2) at t = 0, 1, 2.
/// fn y(t: f64) -> f64 { 2.0 * (0.5 * t).exp() }
/// impl Operator for Exp {
///     type Param = DVector<f64>;
///     type Output = DVector<f64>;
///     fn apply(&self, p: &DVector<f64>) -> Result<DVector<f64>, Error> {
///         Ok(DVector::from_iterator(3, T.iter().map(|&t| p[0] * (p[1] * t).exp() - y(t))))
///     }
/// }
/// impl Jacobian for Exp {
///     type Param = DVector<f64>;
///     type Jacobian = DMatrix<f64>;
///     fn jacobian(&self, p: &DVector<f64>) -> Result<DMatrix<f64>, Error> {
///         Ok(DMatrix::from_fn(3, 2, |i, j| {
///             let e = (p[1] * T[i]).exp();
///             if j == 0 { e } else { p[0] * T[i] * e }
///         }))
///     }
/// }
/// let res = Executor::new(Exp, LevenbergMarquardt::new())
///     .configure(|s| s.param(DVector::from_vec(vec![1.0, 0.0])).max_iters(100))
///     .run()
///     .unwrap();
/// let p = res.state().get_param().unwrap();
/// assert!((p[0] - 2.0).abs() < 1e-12 && (p[1] - 0.5).abs() < 1e-12);
/// ```
#[derive(Debug, Clone)]
pub struct LevenbergMarquardt {
    ftol: f64,
    xtol: f64,
    gtol: f64,
    radius_factor: f64,
    noise: f64,
    diag: DVector<f64>,
    delta: f64,
    lambda: f64,
    first_step: bool,
    svd: Option<ScaledSvd>,
    status: Option<LmTermination>,
}

/// Default `xtol`: a few ulps above `f64::EPSILON`, so the solver iterates until its steps are
/// at rounding level — NIST's hard problems need that to reach ≥ 6 correct digits.
pub const DEFAULT_XTOL: f64 = 1e-15;

/// Default `ftol`: 0, the cost test is off. The cost is quadratic in the parameter error, so a
/// cost test at `ftol` only certifies parameters to about `√ftol` of their standard deviation:
/// with `ftol = 1e-15` NIST ENSO stops at 6.5 correct digits; with the test off (termination by
/// `xtol`) every StRD problem reaches ≥ 9.9 (`tests/data/nist/RESULTS.md`).
pub const DEFAULT_FTOL: f64 = 0.0;

/// Relative cost change below which the ratio test is treated as rounding noise and a step that
/// the ratio test rejects is accepted if it reduces the scaled gradient: `√eps`, because
/// the cost is quadratic in the parameter error, so changes below `√eps` relative are where
/// `f - y` cancellation (e.g. Lanczos3, SS = 1.6e-8 on y ≈ 1) makes the cost unreliable.
pub const DEFAULT_COST_NOISE: f64 = 1.5e-8;

/// Initial trust radius `Δ₀ = factor·‖D x₀‖`. MINPACK suggests 100, but on NIST StRD its first
/// step from BoxBOD start 1 jumps onto a plateau where `∂f/∂b2 ≈ e⁻¹¹⁰` and stalls; every
/// factor from 0.1 to 10 solves all 54 problem–start pairs, and 1 needs the fewest iterations.
pub const DEFAULT_RADIUS_FACTOR: f64 = 1.0;

impl Default for LevenbergMarquardt {
    fn default() -> Self {
        Self::new()
    }
}

impl LevenbergMarquardt {
    /// Solver with default tolerances ([`DEFAULT_FTOL`], [`DEFAULT_XTOL`], gtol 0) and
    /// initial trust radius factor [`DEFAULT_RADIUS_FACTOR`].
    pub fn new() -> Self {
        LevenbergMarquardt {
            ftol: DEFAULT_FTOL,
            xtol: DEFAULT_XTOL,
            gtol: 0.0,
            radius_factor: DEFAULT_RADIUS_FACTOR,
            noise: DEFAULT_COST_NOISE,
            diag: DVector::zeros(0),
            delta: 0.0,
            lambda: 0.0,
            first_step: true,
            svd: None,
            status: None,
        }
    }

    /// Set `ftol` (relative cost reduction), `xtol` (relative scaled step) and `gtol` (cosine
    /// between residuals and Jacobian columns). All must be finite and non-negative; 0 turns a
    /// test off (`xtol` 0 still stops once the trust radius reaches rounding level).
    pub fn with_tolerances(mut self, ftol: f64, xtol: f64, gtol: f64) -> Result<Self> {
        for (name, v) in [("ftol", ftol), ("xtol", xtol), ("gtol", gtol)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::Parameter {
                    name: name.into(),
                    value: v,
                    message: "tolerance must be finite and >= 0".into(),
                });
            }
        }
        self.ftol = ftol;
        self.xtol = xtol;
        self.gtol = gtol;
        Ok(self)
    }

    /// Set the initial trust radius as `factor · ‖D x₀‖` (MINPACK's `factor`).
    pub fn with_radius_factor(mut self, factor: f64) -> Result<Self> {
        if !(factor.is_finite() && factor > 0.0) {
            return Err(Error::Parameter {
                name: "radius_factor".into(),
                value: factor,
                message: "must be finite and > 0".into(),
            });
        }
        self.radius_factor = factor;
        Ok(self)
    }

    /// Set the relative cost change below which a rejected step is re-judged by the scaled
    /// gradient ([`DEFAULT_COST_NOISE`]); 0 disables it (pure MINPACK acceptance).
    pub fn with_cost_noise(mut self, noise: f64) -> Result<Self> {
        if !(noise.is_finite() && (0.0..1.0).contains(&noise)) {
            return Err(Error::Parameter {
                name: "cost_noise".into(),
                value: noise,
                message: "must be in [0, 1)".into(),
            });
        }
        self.noise = noise;
        Ok(self)
    }

    /// Why the last run stopped, if it converged (None while running or after max iterations).
    pub fn termination(&self) -> Option<LmTermination> {
        self.status
    }

    /// Update the scaling from a new Jacobian, factor it and run the gradient test.
    fn refresh(&mut self, jacobian: &DMatrix<f64>, residuals: &DVector<f64>) {
        let n = jacobian.ncols();
        let col_norms = column_norms(jacobian);
        if self.diag.len() != n {
            self.diag = col_norms.map(|c| if c > 0.0 { c } else { 1.0 });
        } else {
            self.diag.zip_apply(&col_norms, |d, c| *d = d.max(c));
        }
        let fnorm = residuals.norm();
        if fnorm == 0.0 {
            // Also covers m = 0; nothing to factor.
            self.status = Some(LmTermination::ZeroResidual);
            return;
        } else if gradient_cosine(jacobian, residuals, &col_norms) <= self.gtol {
            self.status = Some(LmTermination::GradientConverged);
        }
        let mut scaled = jacobian.clone();
        for (j, mut col) in scaled.column_iter_mut().enumerate() {
            col /= self.diag[j];
        }
        self.svd = Some(svd_with_projection(scaled, residuals));
    }
}

/// SVD `A = U Σ Vᵀ` with `g = Uᵀ r`. For tall `A` (m > n) it first reduces `A = Q R` by
/// Householder QR and factors the n×n `R`: same backward stability, and ~10× faster than a
/// direct SVD when m ≫ n because `U` is never formed at m×n.
fn svd_with_projection(a: DMatrix<f64>, r: &DVector<f64>) -> ScaledSvd {
    let (m, n) = a.shape();
    let (small, rhs) = if m > n {
        let qr = a.qr();
        let mut qtr = r.clone();
        qr.q_tr_mul(&mut qtr);
        (qr.unpack_r(), qtr.rows(0, n).into_owned())
    } else {
        (a, r.clone())
    };
    let svd = small.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        unreachable!("SVD was asked for U and Vᵀ")
    };
    ScaledSvd {
        sigma: svd.singular_values,
        v_t,
        g: u.tr_mul(&rhs),
    }
}

/// Euclidean norm of each column of `a`.
fn column_norms(a: &DMatrix<f64>) -> DVector<f64> {
    DVector::from_iterator(a.ncols(), a.column_iter().map(|c| c.norm()))
}

/// Whether every entry is finite.
fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Norm of the scaled gradient `‖D⁻¹ Jᵀ r‖`.
fn scaled_gradient(j: &DMatrix<f64>, r: &DVector<f64>, diag: &DVector<f64>) -> f64 {
    j.tr_mul(r).component_div(diag).norm()
}

/// MINPACK's gradient test: `max_j |J_jᵀ r| / (‖J_j‖ ‖r‖)`, the largest cosine between the
/// residual vector and a Jacobian column.
fn gradient_cosine(j: &DMatrix<f64>, r: &DVector<f64>, col_norms: &DVector<f64>) -> f64 {
    let rn = r.norm();
    j.column_iter()
        .zip(col_norms.iter())
        .filter(|(_, &c)| c > 0.0)
        .map(|(col, &c)| (col.dot(r) / (c * rn)).abs())
        .fold(0.0, f64::max)
}

/// Relative singular-value cutoff below which a direction counts as rank-deficient in the
/// Gauss–Newton step: rounding in the SVD perturbs each σ by about `eps·σ_max·max(m,n)`.
fn gauss_newton_cutoff(svd: &ScaledSvd, rows: usize) -> f64 {
    let smax = svd.sigma.max();
    smax * f64::EPSILON * rows.max(svd.sigma.len()) as f64
}

/// The damped scaled step `w = -(Σ² + λ)⁻¹ Σ g` in the SVD basis (Moré 1978, eq. 3.3).
fn damped_coefficients(svd: &ScaledSvd, lambda: f64, cutoff: f64) -> DVector<f64> {
    svd.sigma.zip_map(&svd.g, |s, g| {
        if lambda == 0.0 && s <= cutoff {
            0.0
        } else {
            -s * g / (s * s + lambda)
        }
    })
}

/// `Σ σ²g²/(σ²+λ)³ = -½ d‖z‖²/dλ`, the slope the secular-equation Newton step needs.
fn secular_slope(svd: &ScaledSvd, lambda: f64) -> f64 {
    svd.sigma
        .zip_map(&svd.g, |s, g| {
            let d = s * s + lambda;
            s * s * g * g / (d * d * d)
        })
        .sum()
}

/// The LM step whose scaled length fits the trust radius `delta` to within 10% (Moré's secular
/// equation `‖z(λ)‖ = Δ`, solved by safeguarded Newton on `1/‖z‖`); `λ = 0` if the Gauss–Newton
/// step already fits.
fn trust_region_step(svd: &ScaledSvd, delta: f64, lambda_guess: f64, rows: usize) -> TrialStep {
    let cutoff = gauss_newton_cutoff(svd, rows);
    let gn = damped_coefficients(svd, 0.0, cutoff);
    let mut lambda = 0.0;
    let mut w = gn;
    if w.norm() > 1.1 * delta {
        let sg = svd.sigma.component_mul(&svd.g).norm();
        let (mut lo, mut hi) = (0.0, sg / delta);
        lambda = if lambda_guess > lo && lambda_guess < hi {
            lambda_guess
        } else {
            1e-3 * hi
        };
        for _ in 0..60 {
            w = damped_coefficients(svd, lambda, cutoff);
            let zn = w.norm();
            if (zn - delta).abs() <= 0.1 * delta {
                break;
            }
            if zn > delta {
                lo = lambda;
            } else {
                hi = lambda;
            }
            let slope = secular_slope(svd, lambda);
            let newton = lambda + (zn - delta) / delta * zn * zn / slope;
            lambda = if newton > lo && newton < hi && newton.is_finite() {
                newton
            } else if lo > 0.0 {
                (lo * hi).sqrt()
            } else {
                0.5 * (lo + hi)
            };
        }
    }
    let jp2 = svd.sigma.component_mul(&w).norm_squared();
    TrialStep {
        z: svd.v_t.tr_mul(&w),
        lambda,
        jp2,
    }
}

impl<O> Solver<O, LmState> for LevenbergMarquardt
where
    O: Operator<Param = DVector<f64>, Output = DVector<f64>>
        + Jacobian<Param = DVector<f64>, Jacobian = DMatrix<f64>>,
{
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
        let r = problem.apply(&x0)?;
        if r.iter().any(|v| !v.is_finite()) {
            return Err(anyhow_error(
                "residuals at the initial parameters are not finite; choose another start",
            ));
        }
        let j = problem.jacobian(&x0)?;
        if !all_finite(j.as_slice()) {
            return Err(anyhow_error(
                "Jacobian at the initial parameters is not finite; choose another start",
            ));
        }
        if j.nrows() != r.len() || j.ncols() != x0.len() {
            return Err(anyhow_error(&format!(
                "Jacobian is {}x{} but residuals have {} rows and parameters {} entries",
                j.nrows(),
                j.ncols(),
                r.len(),
                x0.len()
            )));
        }
        self.diag = DVector::zeros(0);
        self.svd = None;
        self.status = None;
        self.first_step = true;
        self.lambda = 0.0;
        self.refresh(&j, &r);
        let xnorm = self.diag.component_mul(&x0).norm();
        self.delta = if xnorm > 0.0 {
            self.radius_factor * xnorm
        } else {
            self.radius_factor
        };
        let cost = 0.5 * r.norm_squared();
        let kv = argmin::kv!("cost" => cost; "delta" => self.delta;);
        Ok((
            state.param(x0).residuals(r).jacobian(j).cost(cost),
            Some(kv),
        ))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        mut state: LmState,
    ) -> std::result::Result<(LmState, Option<KV>), ArgminError> {
        let svd = self.svd.as_ref().ok_or_else(|| {
            anyhow_error("LevenbergMarquardt: no factorisation; was init run and not converged?")
        })?;
        let x = state
            .get_param()
            .ok_or_else(|| anyhow_error("LevenbergMarquardt: param not set"))?
            .clone();
        let fnorm = (2.0 * state.get_cost()).sqrt();
        let rows = state.get_residuals().map_or(0, |r| r.len());

        let step = trust_region_step(svd, self.delta, self.lambda, rows);
        let p = step.z.component_div(&self.diag);
        let pnorm = step.z.norm();
        if self.first_step {
            self.delta = self.delta.min(pnorm);
            self.first_step = false;
        }
        let x_new = &x + &p;
        let r_new = problem.apply(&x_new)?;
        if r_new.len() != rows {
            return Err(anyhow_error(&format!(
                "residual vector changed length from {rows} to {} between evaluations",
                r_new.len()
            )));
        }
        // A step into a region where the model is undefined is a failed step, not an error.
        let fnorm1 = if r_new.iter().all(|v| v.is_finite()) {
            r_new.norm()
        } else {
            f64::INFINITY
        };

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
            let j = problem.jacobian(&x_new)?;
            let old = match (state.get_jacobian(), state.get_residuals()) {
                (Some(jo), Some(ro)) => scaled_gradient(jo, ro, &self.diag),
                _ => f64::INFINITY,
            };
            if all_finite(j.as_slice()) && scaled_gradient(&j, &r_new, &self.diag) < old {
                accepted = true;
                noise_accepted = true;
            }
            j_new = Some(j);
        }
        if accepted {
            let j = match j_new {
                Some(j) => j,
                None => problem.jacobian(&x_new)?,
            };
            if !all_finite(j.as_slice()) {
                return Err(anyhow_error(&format!(
                    "Jacobian is not finite at parameters {:?} where the residuals are finite; \
                     check the model's derivatives",
                    x_new.as_slice()
                )));
            }
            self.refresh(&j, &r_new);
            let cost = 0.5 * fnorm1 * fnorm1;
            state = state
                .param(x_new.clone())
                .residuals(r_new)
                .jacobian(j)
                .cost(cost);
        }
        let xnorm = self
            .diag
            .component_mul(if accepted { &x_new } else { &x })
            .norm();

        if self.status.is_none() {
            let eps = f64::EPSILON;
            self.status = if actred.abs() <= self.ftol && prered <= self.ftol && 0.5 * ratio <= 1.0
            {
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
        match self.status {
            Some(s) => TerminationStatus::Terminated(match s {
                LmTermination::CostConverged
                | LmTermination::StepConverged
                | LmTermination::GradientConverged
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
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            ftol: DEFAULT_FTOL,
            xtol: DEFAULT_XTOL,
            gtol: 0.0,
            max_iters: 2000,
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
    let solver =
        LevenbergMarquardt::new().with_tolerances(options.ftol, options.xtol, options.gtol)?;
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

/// Default relative singular-value cutoff for [`covariance`]: directions of the column-scaled
/// Jacobian with `σ < 1e-10·σ_max` have variance over 1e20 times the best-determined direction,
/// and their σ carries a relative rounding error of `eps/1e-10 ≈ 2e-6` — the data does not
/// determine them.
pub const DEFAULT_RCOND: f64 = 1e-10;

/// Fraction of a parameter's (unit) weight in `V` that may fall into discarded directions
/// before it is flagged as not determined by the data.
const UNDETERMINED_WEIGHT: f64 = 0.1;

/// Parameter covariance with a report of the directions the data does not determine.
#[derive(Debug, Clone)]
pub struct Covariance {
    /// `s² (JᵀJ)⁺`, the (pseudo-)inverse restricted to the retained directions.
    pub matrix: DMatrix<f64>,
    /// `s² = SS / dof`, the residual variance.
    pub residual_variance: f64,
    /// `σ_max/σ_min` of the column-scaled Jacobian (infinite if a σ is zero).
    pub condition_number: f64,
    /// Number of directions dropped by the cutoff.
    pub rank_deficiency: usize,
    /// Per parameter: true if at least 10% of its weight lies in dropped directions.
    pub undetermined: Vec<bool>,
}

/// Covariance `s² (JᵀJ)⁻¹` with `s² = residual_ss/dof`, via the SVD of the column-scaled
/// Jacobian with cutoff [`DEFAULT_RCOND`]. `None` if `dof == 0`, or `J` is empty or not finite.
pub fn covariance(jacobian: &DMatrix<f64>, residual_ss: f64, dof: usize) -> Option<Covariance> {
    covariance_with_rcond(jacobian, residual_ss, dof, DEFAULT_RCOND)
}

/// [`covariance`] with an explicit relative singular-value cutoff `rcond`.
pub fn covariance_with_rcond(
    jacobian: &DMatrix<f64>,
    residual_ss: f64,
    dof: usize,
    rcond: f64,
) -> Option<Covariance> {
    let (m, n) = jacobian.shape();
    if dof == 0 || n == 0 || m == 0 || !residual_ss.is_finite() {
        return None;
    }
    if jacobian.iter().any(|v| !v.is_finite()) {
        return None;
    }
    // Scale columns to unit norm so the cutoff does not depend on the parameters' units.
    let norms = column_norms(jacobian).map(|c| if c > 0.0 { c } else { 1.0 });
    let mut scaled = jacobian.clone();
    for (j, mut col) in scaled.column_iter_mut().enumerate() {
        col /= norms[j];
    }
    let ScaledSvd { sigma, v_t, .. } = svd_with_projection(scaled, &DVector::zeros(m));
    let smax = sigma.max();
    let smin = sigma.min();
    // Thin SVD of an m×n matrix with m < n has only m singular values: the rest are zero.
    let missing = n - sigma.len();
    let condition_number = if smin > 0.0 && missing == 0 {
        smax / smin
    } else {
        f64::INFINITY
    };
    let s2 = residual_ss / dof as f64;
    let mut inner = DMatrix::zeros(n, n);
    let mut dropped_weight = vec![0.0; n];
    let mut rank_deficiency = missing;
    for (k, &s) in sigma.iter().enumerate() {
        let vk = v_t.row(k).transpose();
        if s > rcond * smax {
            inner += &vk * vk.transpose() / (s * s);
        } else {
            rank_deficiency += 1;
            for j in 0..n {
                dropped_weight[j] += vk[j] * vk[j];
            }
        }
    }
    if missing > 0 {
        // Weight in the null space of the thin SVD: 1 - weight in the computed rows.
        for (j, w) in dropped_weight.iter_mut().enumerate() {
            let kept: f64 = (0..sigma.len()).map(|k| v_t[(k, j)].powi(2)).sum();
            *w += (1.0 - kept).max(0.0);
        }
    }
    let mut matrix = inner * s2;
    for i in 0..n {
        for j in 0..n {
            matrix[(i, j)] /= norms[i] * norms[j];
        }
    }
    Some(Covariance {
        matrix,
        residual_variance: s2,
        condition_number,
        rank_deficiency,
        undetermined: dropped_weight
            .iter()
            .map(|&w| w >= UNDETERMINED_WEIGHT)
            .collect(),
    })
}

/// Correlation matrix `C_ij = cov_ij / √(cov_ii cov_jj)`; entries with a zero variance are 0
/// off the diagonal and 1 on it.
pub fn correlation(cov: &DMatrix<f64>) -> DMatrix<f64> {
    let n = cov.nrows();
    DMatrix::from_fn(n, n, |i, j| {
        if i == j {
            return 1.0;
        }
        let d = (cov[(i, i)] * cov[(j, j)]).sqrt();
        if d > 0.0 {
            cov[(i, j)] / d
        } else {
            0.0
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `y = a + b x` on x = 0..3: Jᵀ J = [[4, 6], [6, 14]], so (JᵀJ)⁻¹ = [[14, -6], [-6, 4]]/20.
    fn line_jacobian() -> DMatrix<f64> {
        DMatrix::from_row_slice(4, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0, 1.0, 3.0])
    }

    #[test]
    fn covariance_of_a_straight_line_matches_the_closed_form() {
        let ss = 0.7;
        let cov = covariance(&line_jacobian(), ss, 2).expect("full rank, dof > 0");
        let s2 = ss / 2.0;
        let expected = DMatrix::from_row_slice(2, 2, &[14.0, -6.0, -6.0, 4.0]) * (s2 / 20.0);
        // A 4×2 SVD with condition ~5 is accurate to a few ulps; 1e-13 leaves margin.
        assert!((&cov.matrix - &expected).abs().max() < 1e-13 * expected.abs().max());
        assert_eq!(cov.rank_deficiency, 0);
        assert_eq!(cov.undetermined, vec![false, false]);
        assert!(cov.condition_number.is_finite() && cov.condition_number > 1.0);
        let corr = correlation(&cov.matrix);
        let r = -6.0 / (14.0f64 * 4.0).sqrt();
        assert!((corr[(0, 1)] - r).abs() < 1e-13);
        assert!((corr[(1, 0)] - r).abs() < 1e-13);
        assert_eq!(corr[(0, 0)], 1.0);
    }

    #[test]
    fn covariance_flags_parameters_the_data_cannot_separate() {
        // Third column is twice the second: only b1 + 2 b2 is determined.
        let j = DMatrix::from_row_slice(
            4,
            3,
            &[1.0, 0.0, 0.0, 1.0, 1.0, 2.0, 1.0, 2.0, 4.0, 1.0, 3.0, 6.0],
        );
        let cov = covariance(&j, 1.0, 1).expect("dof > 0");
        assert_eq!(cov.rank_deficiency, 1);
        assert_eq!(cov.undetermined, vec![false, true, true]);
        assert!(cov.condition_number > 1e10);
        assert!(cov.matrix.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn covariance_is_independent_of_parameter_units() {
        // Rescaling a parameter by 1e6 rescales its column; the scaled SVD must not drop it.
        let mut j = line_jacobian();
        j.column_mut(1).scale_mut(1e-6);
        let cov = covariance(&j, 0.7, 2).expect("full rank");
        assert_eq!(cov.rank_deficiency, 0);
        let base = covariance(&line_jacobian(), 0.7, 2).expect("full rank");
        // Var(b') = 1e12 Var(b) exactly in exact arithmetic; rounding is a few ulps.
        assert!((cov.matrix[(1, 1)] / base.matrix[(1, 1)] / 1e12 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn covariance_needs_degrees_of_freedom() {
        assert!(covariance(&line_jacobian(), 1.0, 0).is_none());
        assert!(covariance(&DMatrix::zeros(0, 0), 1.0, 1).is_none());
    }

    #[test]
    fn tolerances_must_be_finite_and_non_negative() {
        assert!(LevenbergMarquardt::new()
            .with_tolerances(-1.0, 1e-10, 0.0)
            .is_err());
        assert!(LevenbergMarquardt::new()
            .with_tolerances(1e-10, f64::NAN, 0.0)
            .is_err());
        assert!(LevenbergMarquardt::new().with_radius_factor(0.0).is_err());
        assert!(LevenbergMarquardt::new()
            .with_tolerances(0.0, 0.0, 1e-8)
            .is_ok());
    }

    #[test]
    fn secular_step_fits_the_trust_radius() {
        let svd = ScaledSvd {
            sigma: DVector::from_vec(vec![3.0, 1e-3]),
            v_t: DMatrix::identity(2, 2),
            g: DVector::from_vec(vec![1.0, 1.0]),
        };
        // Gauss–Newton step has length ~1000, far outside Δ = 0.5.
        let step = trust_region_step(&svd, 0.5, 0.0, 5);
        assert!(step.lambda > 0.0);
        // Moré accepts |‖z‖ - Δ| ≤ 0.1 Δ.
        assert!((step.z.norm() - 0.5).abs() <= 0.05);
        let inside = trust_region_step(&svd, 1e4, 0.0, 5);
        assert_eq!(inside.lambda, 0.0);
    }
}
