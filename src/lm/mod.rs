//! Levenberg–Marquardt as an argmin `Solver`: the solver type, its options and why it stopped.
//! The iteration is in `iterate`, the trust-region step in `step`, and what the data determine
//! about the solution (covariance, correlation, null space) in [`covariance`](mod@covariance).
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
//! A linearisation may come by blocks ([`BlockSystem`]: a few shared columns, the rest each
//! confined to one block of rows, as a channel's own parameters are); the step is then solved by
//! block elimination (`blocks`) for each `λ`, in time and memory linear in the number of blocks.
//!
//! One argmin iteration is one trial step (one residual evaluation); a Jacobian is evaluated only
//! after an accepted step. The state's cost is `½‖r‖²`.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use argmin::core::IterState;
use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};

pub mod blocks;
pub mod covariance;
mod iterate;
mod least_squares;
mod step;

pub use blocks::{block_covariance, Block, BlockCovariance, BlockSystem};
pub use covariance::{
    correlation, covariance, covariance_with_rcond, null_space_weights, Covariance,
    ParameterCovariance, DEFAULT_RCOND,
};
pub use least_squares::{LeastSquares, Linearized, System};
use step::ScaledSvd;

/// The factorisation of the scaled linearisation kept until the next one.
#[derive(Debug, Clone)]
enum Factored {
    /// SVD of a dense `J D⁻¹`: every `λ` costs a diagonal solve.
    Svd(ScaledSvd),
    /// The column-scaled block system, refactored per `λ` by block elimination.
    Blocks(BlockSystem),
}

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
    /// The Gauss–Newton step from the current point predicts a χ² decrease below the statistical
    /// tolerance ([`LevenbergMarquardt::with_statistical_tolerance`]).
    StatisticallyConverged,
    /// The cost fell by less than the stall test's χ² over its window of steps
    /// ([`LevenbergMarquardt::with_stall_test`]).
    Stalled,
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
            LmTermination::StatisticallyConverged => {
                "the Gauss-Newton step predicts a chi-square decrease below tolerance"
            }
            LmTermination::Stalled => "no statistically visible progress over the stall window",
        }
    }
}

/// Moré–MINPACK Levenberg–Marquardt for nonlinear least squares `min ½‖r(x)‖²`.
///
/// Problem: any [`LeastSquares`] — argmin [`Operator`] (residuals `r(x)`, `DVector<f64>`) and
/// [`Jacobian`] (`m×n` `DMatrix<f64>`) qualify, or a problem that hands over a reduced
/// linearisation instead of its Jacobian. Use it with `Executor::new(problem, LevenbergMarquardt::new())` and
/// `.configure(|s| s.param(x0).max_iters(n))`.
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
    factor: Option<Factored>,
    /// `Jᵀr` at the current point (judges noise-level steps).
    gradient: DVector<f64>,
    status: Option<LmTermination>,
    /// Number of residuals of the problem (the linearisation may have fewer rows).
    rows: usize,
    /// Statistical stop: degrees of freedom of the residuals and the χ² tolerance (0: off).
    dof: usize,
    chi2_tol: f64,
    /// Stop at an accepted step that meets the cost tolerance without linearising there.
    lazy_final: bool,
    /// Stops the run at the next step once raised (Ctrl-C, a memory refusal).
    cancel: Option<Arc<AtomicBool>>,
    stall: Option<StallTest>,
    /// The state's cost after each step of this run (the stall test's window).
    costs: Vec<f64>,
}

/// Stop when `window` steps lowered χ² (with `dof` degrees of freedom) by less than `chi2`.
#[derive(Debug, Clone, Copy)]
struct StallTest {
    dof: usize,
    window: usize,
    chi2: f64,
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
            factor: None,
            gradient: DVector::zeros(0),
            status: None,
            rows: 0,
            dof: 0,
            chi2_tol: 0.0,
            lazy_final: false,
            cancel: None,
            stall: None,
            costs: Vec::new(),
        }
    }

    /// Set `ftol` (relative cost reduction), `xtol` (relative scaled step) and `gtol` (cosine
    /// between residuals and Jacobian columns). All must be finite and non-negative; 0 turns a
    /// test off (`xtol` 0 still stops once the trust radius reaches rounding level).
    pub fn with_tolerances(mut self, ftol: f64, xtol: f64, gtol: f64) -> Result<Self> {
        for (name, v) in [("ftol", ftol), ("xtol", xtol), ("gtol", gtol)] {
            check_option(
                name,
                v,
                v.is_finite() && v >= 0.0,
                "tolerance must be finite and >= 0",
            )?;
        }
        self.ftol = ftol;
        self.xtol = xtol;
        self.gtol = gtol;
        Ok(self)
    }

    /// Set the initial trust radius as `factor · ‖D x₀‖` (MINPACK's `factor`).
    pub fn with_radius_factor(mut self, factor: f64) -> Result<Self> {
        let ok = factor.is_finite() && factor > 0.0;
        check_option("radius_factor", factor, ok, "must be finite and > 0")?;
        self.radius_factor = factor;
        Ok(self)
    }

    /// Set the relative cost change below which a rejected step is re-judged by the scaled
    /// gradient ([`DEFAULT_COST_NOISE`]); 0 disables it (pure MINPACK acceptance).
    pub fn with_cost_noise(mut self, noise: f64) -> Result<Self> {
        let ok = noise.is_finite() && (0.0..1.0).contains(&noise);
        check_option("cost_noise", noise, ok, "must be in [0, 1)")?;
        self.noise = noise;
        Ok(self)
    }

    /// Also stop once the Gauss–Newton step from an accepted point predicts a decrease of
    /// `χ² = ‖r‖²/s²` below `chi2`, with the residual variance `s² = ‖r‖²/dof`. What is left then
    /// moves each parameter by at most `√chi2` of its standard error (Cauchy–Schwarz on
    /// `δᵀJᵀJδ`), so iterating further changes digits the data do not determine; on millions of
    /// residuals each iteration is a full model pass. `dof` 0 or `chi2` 0 turns it off (the
    /// default: the solver iterates to rounding level, as NIST's certified values need).
    pub fn with_statistical_tolerance(mut self, dof: usize, chi2: f64) -> Result<Self> {
        let ok = chi2.is_finite() && chi2 >= 0.0;
        check_option("chi2", chi2, ok, "must be finite and >= 0")?;
        self.dof = dof;
        self.chi2_tol = chi2;
        Ok(self)
    }

    /// End a run at an accepted step whose trial already meets the cost tolerance (`ftol`)
    /// without linearising at its new point: for callers that want the minimum's cost and
    /// position only (a profile's re-fits), that saves a Jacobian pass per run. The final
    /// state then carries no Jacobian or residuals.
    pub fn with_lazy_final_linearization(mut self) -> Self {
        self.lazy_final = true;
        self
    }

    /// Also stop, as converged, once the last `window` steps together lowered `χ² = ‖r‖²/s²`
    /// (`s² = ‖r‖²/dof`) by less than `chi2`: a statistically invisible crawl along directions
    /// the data leave (nearly) flat, where the relative tolerances would exhaust the iteration
    /// limit instead. `dof` 0 turns it off.
    pub fn with_stall_test(mut self, dof: usize, window: usize, chi2: f64) -> Result<Self> {
        let ok = chi2.is_finite() && chi2 >= 0.0 && window > 0;
        check_option(
            "stall chi2",
            chi2,
            ok,
            "must be finite and >= 0, window > 0",
        )?;
        self.stall = (dof > 0).then_some(StallTest { dof, window, chi2 });
        Ok(self)
    }

    /// Stop at the next step boundary once `flag` is raised; argmin reports the run as
    /// interrupted. (argmin's own `ctrlc` feature installs one process-wide handler per run, and
    /// only the first wins: runs in parallel would not all see it.)
    pub fn with_cancel(mut self, flag: Option<Arc<AtomicBool>>) -> Self {
        self.cancel = flag;
        self
    }

    /// True when the run's cancellation flag is raised.
    fn cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|f| f.load(Ordering::SeqCst))
    }

    /// The stall test after the latest step.
    fn stalled(&self) -> bool {
        let (Some(t), k) = (self.stall, self.costs.len()) else {
            return false;
        };
        if k <= t.window {
            return false;
        }
        let (then, now) = (self.costs[k - 1 - t.window], self.costs[k - 1]);
        // Δχ² = 2Δcost/s² with s² = 2·cost/dof.
        now > 0.0 && (then - now) * t.dof as f64 / now < t.chi2
    }

    /// Why the last run stopped, if it converged (None while running or after max iterations).
    pub fn termination(&self) -> Option<LmTermination> {
        self.status
    }
}

/// `Ok` when `ok`, else the error naming the solver option `name` and its rejected `value`.
fn check_option(name: &str, value: f64, ok: bool, message: &str) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(Error::Parameter {
            name: name.into(),
            value,
            message: message.into(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
