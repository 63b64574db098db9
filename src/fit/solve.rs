//! Running the fit's solvers through argmin's `Executor`: [`run_lm`], the one Levenberg–Marquardt
//! runner of the multi-start, the polish and the profile re-fits, and the derivative-free global
//! stages. Observers only watch (cost and parameter traces, the progress bar); the solver itself
//! decides when to stop, cancellation (the CLI's Ctrl-C flag) and the stall test included.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{Error as ArgminError, Executor, State, TerminationReason, KV};
use nalgebra::DVector;

use super::problem::{Evaluator, Forward, LsqProblem};
use crate::lm::{LevenbergMarquardt, LmState};

/// How a solver run ended (the same type as fit.json's `status`).
pub use crate::files::FitStatus as RunStatus;

/// Trial steps over which a fit must still make statistically visible progress.
pub const STALL_WINDOW: usize = 20;
/// Progress below this many χ² units over [`STALL_WINDOW`] steps counts as converged: Δχ² = 1 is
/// one standard error along one direction, so what is left moves nothing the data can see. This
/// ends LM's crawl along directions the data leave (nearly) flat, where its relative tolerances
/// would exhaust the iteration limit instead.
pub const STALL_CHI2: f64 = 1e-3;

/// True when the cancellation flag is set.
pub fn is_cancelled(flag: &Option<Arc<AtomicBool>>) -> bool {
    flag.as_ref().is_some_and(|f| f.load(Ordering::SeqCst))
}

/// Records the state's cost after every iteration, for each of the fit's solvers: LM's current
/// cost (a step accepted within rounding noise may raise it slightly), Nelder–Mead's best vertex,
/// the swarm's best particle.
struct CostTrace(Arc<Mutex<Vec<f64>>>);

impl<S: State<Float = f64>> Observe<S> for CostTrace {
    fn observe_iter(&mut self, state: &S, _kv: &KV) -> Result<(), ArgminError> {
        if let Ok(mut h) = self.0.lock() {
            h.push(state.get_cost());
        }
        Ok(())
    }
}

/// Outcome of one local solver run.
#[derive(Debug, Clone)]
pub struct LocalRun {
    /// Best solver parameters found.
    pub u: Vec<f64>,
    /// `½‖r̃‖²` at `u`.
    pub cost: f64,
    pub iterations: u64,
    /// Solver cost after every iteration.
    pub history: Vec<f64>,
    pub status: RunStatus,
    pub wall_s: f64,
}

/// Relative cost-reduction tolerance of the fit's LM runs. Noisy fits normally stop earlier, by
/// [`PREDICTED_CHI2`]; this one still ends a parameter creeping onto a bound (the sin transform
/// flattens there) instead of exhausting the iteration limit, and runs without degrees of
/// freedom; noise-free fits are unaffected (their cost falls by O(1) factors down to rounding).
pub const FTOL: f64 = 1e-12;

/// The fit's runs stop once the Gauss–Newton step predicts a χ² decrease below this: what is
/// left moves every parameter by at most √0.001 ≈ 3% of its standard error. Without it the
/// polish of 1M samples × 3 channels spent two of its three ~1.3 s iterations on a χ² change of
/// 3e-4 and then rounding noise.
pub const PREDICTED_CHI2: f64 = 1e-3;

/// The local least-squares solver: Moré–MINPACK Levenberg–Marquardt (`crate::lm`), for residuals
/// with `dof` degrees of freedom (the statistical stop, [`PREDICTED_CHI2`], needs them).
pub fn local_solver(dof: usize) -> LevenbergMarquardt {
    LevenbergMarquardt::new()
        .with_tolerances(FTOL, crate::lm::DEFAULT_XTOL, 0.0)
        .and_then(|lm| lm.with_statistical_tolerance(dof, PREDICTED_CHI2))
        .unwrap_or_default()
}

/// Records the parameters after every iteration, so a run stopped by an error mid-iteration
/// (a cancelled linearisation) still hands back where it was.
struct ParamTrace(Arc<Mutex<Option<Vec<f64>>>>);

impl Observe<LmState> for ParamTrace {
    fn observe_iter(&mut self, state: &LmState, _kv: &KV) -> Result<(), ArgminError> {
        let best = state.get_best_param().or(state.get_param());
        if let (Ok(mut slot), Some(p)) = (self.0.lock(), best) {
            *slot = Some(p.as_slice().to_vec());
        }
        Ok(())
    }
}

/// Shows a long run's iteration and cost as the progress bar's message.
struct IterationMessage(indicatif::ProgressBar);

impl Observe<LmState> for IterationMessage {
    fn observe_iter(&mut self, state: &LmState, _kv: &KV) -> Result<(), ArgminError> {
        self.0.set_message(format!(
            "polish: iteration {}, cost {:.6e}",
            state.get_iter(),
            state.get_best_cost()
        ));
        Ok(())
    }
}

/// Run the fit's local solver ([`local_solver`]) from `u0` for at most `max_iters` iterations.
/// A raised `cancel` stops it within one chunk of samples, with the best point reached so far.
pub fn run_local<F: Forward>(
    ev: &Evaluator<'_, F>,
    u0: &[f64],
    max_iters: u64,
    cancel: &Option<Arc<AtomicBool>>,
) -> LocalRun {
    let solver = local_solver(residual_dof(ev));
    run_lm(ev, u0, solver, max_iters, cancel, None)
}

/// Degrees of freedom of `ev`'s residuals: samples less free parameters and channel scales.
pub fn residual_dof<F: Forward>(ev: &Evaluator<'_, F>) -> usize {
    ev.n_residuals()
        .saturating_sub(ev.n_params() + ev.n_channels)
}

/// The fit's one LM runner: `solver` from `u0` for at most `max_iters` iterations, with the
/// stall test ([`STALL_CHI2`]) and `cancel` added, each iteration shown on `progress` (the
/// polish on all data can take minutes on millions of samples). A raised `cancel` stops it
/// within one chunk of samples, with the best point reached so far; the point handed back is
/// never worse than the start.
pub fn run_lm<F: Forward>(
    ev: &Evaluator<'_, F>,
    u0: &[f64],
    solver: LevenbergMarquardt,
    max_iters: u64,
    cancel: &Option<Arc<AtomicBool>>,
    progress: Option<&indicatif::ProgressBar>,
) -> LocalRun {
    let t0 = Instant::now();
    let full_cost = |u: &[f64]| ev.cost_internal(u, None).unwrap_or(f64::INFINITY);
    let history = Arc::new(Mutex::new(Vec::new()));
    let last = Arc::new(Mutex::new(None));
    let solver = solver
        .with_stall_test(residual_dof(ev), STALL_WINDOW, STALL_CHI2)
        .expect("the stall test's constants are valid")
        .with_cancel(cancel.clone());
    let problem = LsqProblem {
        ev,
        cancel: cancel.clone(),
    };
    let mut executor = Executor::new(problem, solver)
        .configure(|s| s.param(DVector::from_column_slice(u0)).max_iters(max_iters))
        .add_observer(CostTrace(history.clone()), ObserverMode::Always)
        .add_observer(ParamTrace(last.clone()), ObserverMode::Always);
    if let Some(bar) = progress {
        executor = executor.add_observer(IterationMessage(bar.clone()), ObserverMode::Always);
    }
    let result = executor.run();
    let history = history.lock().map(|h| h.clone()).unwrap_or_default();
    // The solver's best cost where it has one (its best point is never worse than the start,
    // which it evaluated first); otherwise one pass each: on millions of samples a pass is
    // a noticeable share of the polish.
    let mut solver_cost = None;
    let (u, iterations, status) = match result {
        Ok(res) => {
            let st = &res.state;
            solver_cost = st
                .get_best_param()
                .map(|_| st.get_best_cost())
                .filter(|c| c.is_finite());
            let u = st
                .get_best_param()
                .or(st.get_param())
                .map(|p| p.as_slice().to_vec())
                .unwrap_or_else(|| u0.to_vec());
            let status = match st.get_termination_reason() {
                Some(TerminationReason::Interrupt) => RunStatus::Interrupted,
                Some(TerminationReason::MaxItersReached) => RunStatus::MaxIterations,
                // LM's other exits (converged, or no further progress possible at machine
                // precision) both leave the best point it can reach.
                _ => RunStatus::Converged,
            };
            (u, st.get_iter(), status)
        }
        // Cancelled inside a linearisation: the last iterate observed.
        Err(_) if is_cancelled(cancel) => {
            let u = last.lock().ok().and_then(|l| l.clone());
            let u = u.unwrap_or_else(|| u0.to_vec());
            (u, history.len() as u64, RunStatus::Interrupted)
        }
        Err(_) => (u0.to_vec(), 0, RunStatus::Failed),
    };
    let (u, cost) = match solver_cost {
        Some(cost) => (u, cost),
        None => {
            let (cost, start_cost) = (full_cost(&u), full_cost(u0));
            // Never hand back a point worse than the start (a failed run keeps the start).
            if cost.is_finite() && cost <= start_cost || !start_cost.is_finite() {
                (u, cost)
            } else {
                (u0.to_vec(), start_cost)
            }
        }
    };
    LocalRun {
        u,
        cost,
        iterations,
        history,
        status,
        wall_s: t0.elapsed().as_secs_f64(),
    }
}

/// The subsample cost as an argmin `CostFunction` (for the derivative-free global stage).
struct CostOnly<'e, 'f, F: Forward> {
    ev: &'e Evaluator<'f, F>,
}

impl<F: Forward> argmin::core::CostFunction for CostOnly<'_, '_, F> {
    type Param = DVector<f64>;
    type Output = f64;
    fn cost(&self, u: &DVector<f64>) -> Result<f64, ArgminError> {
        let c = self.ev.eval_internal(u.as_slice(), false).cost();
        Ok(if c.is_finite() { c } else { f64::MAX })
    }
}

/// argmin's Nelder–Mead from `u0` (initial simplex: steps of 0.2 in each internal coordinate,
/// about a tenth of a bounded parameter's range); returns `(u, cost, iterations, history)`.
pub fn nelder_mead<F: Forward>(
    ev: &Evaluator<'_, F>,
    u0: &[f64],
    max_iters: u64,
) -> (Vec<f64>, f64, u64, Vec<f64>) {
    let x0 = DVector::from_column_slice(u0);
    let mut simplex = vec![x0.clone()];
    for j in 0..u0.len() {
        let mut x = x0.clone();
        x[j] += 0.2;
        simplex.push(x);
    }
    let history = Arc::new(Mutex::new(Vec::new()));
    let solver = argmin::solver::neldermead::NelderMead::new(simplex);
    let res = Executor::new(CostOnly { ev }, solver)
        .configure(|s| s.max_iters(max_iters))
        .add_observer(CostTrace(history.clone()), ObserverMode::Always)
        .run();
    let history = history.lock().map(|h| h.clone()).unwrap_or_default();
    let start_cost = ev.eval_internal(u0, false).cost();
    match res {
        Ok(r) => {
            let st = r.state();
            let u = st
                .get_best_param()
                .map(|p| p.as_slice().to_vec())
                .unwrap_or_else(|| u0.to_vec());
            let c = ev.eval_internal(&u, false).cost();
            if c <= start_cost {
                (u, c, st.get_iter(), history)
            } else {
                (u0.to_vec(), start_cost, st.get_iter(), history)
            }
        }
        Err(_) => (u0.to_vec(), start_cost, 0, history),
    }
}

/// argmin's particle swarm over the box `lower..upper` of internal coordinates, seeded (ChaCha8,
/// so a seed means the same swarm on every platform); returns `(u, cost, iterations, history)`.
/// argmin evaluates the swarm sequentially here; the cost itself is parallel over samples.
pub fn particle_swarm<F: Forward>(
    ev: &Evaluator<'_, F>,
    lower: &[f64],
    upper: &[f64],
    particles: usize,
    max_iters: u64,
    seed: u64,
) -> (Vec<f64>, f64, u64, Vec<f64>) {
    use rand_chacha::rand_core::SeedableRng;
    let history = Arc::new(Mutex::new(Vec::new()));
    let solver = argmin::solver::particleswarm::ParticleSwarm::new(
        (
            DVector::from_column_slice(lower),
            DVector::from_column_slice(upper),
        ),
        particles,
    )
    .with_rng_generator(rand_chacha::ChaCha8Rng::seed_from_u64(seed));
    let res = Executor::new(CostOnly { ev }, solver)
        .configure(|s| s.max_iters(max_iters))
        .add_observer(CostTrace(history.clone()), ObserverMode::Always)
        .run();
    let history = history.lock().map(|h| h.clone()).unwrap_or_default();
    let mid: Vec<f64> = lower
        .iter()
        .zip(upper)
        .map(|(a, b)| 0.5 * (a + b))
        .collect();
    match res {
        Ok(r) => {
            let st = r.state();
            let u = st
                .get_best_param()
                .map(|p| p.position.as_slice().to_vec())
                .unwrap_or(mid);
            let c = ev.eval_internal(&u, false).cost();
            (u, c, st.get_iter(), history)
        }
        Err(_) => {
            let c = ev.eval_internal(&mid, false).cost();
            (mid, c, 0, history)
        }
    }
}
