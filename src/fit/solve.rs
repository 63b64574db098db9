//! Running the local solver through argmin's `Executor`: a cost-trace observer, a cancellation
//! wrapper, and the multi-start driver (short runs on a subsample, then polish on all data).
//!
//! Cancellation: argmin's own `ctrlc` feature installs a process-wide handler per `Executor::run`
//! and only the first installation wins, so with many executors running in parallel (multi-start)
//! most runs would not see Ctrl-C. Instead the CLI installs one handler that sets a shared
//! `AtomicBool`, and every run is wrapped in [`Cancellable`], whose `terminate` (the hook argmin
//! gives a solver to decide when it stops) checks it.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{
    Error as ArgminError, Executor, Problem, Solver, State, TerminationReason, TerminationStatus,
    KV,
};
use nalgebra::DVector;

use super::problem::{Evaluator, Forward, LsqProblem};
use crate::lm::LmState;

/// How a solver run ended (the same type as fit.json's `status`).
pub use crate::files::FitStatus as RunStatus;

/// Trial steps over which a fit must still make statistically visible progress.
pub const STALL_WINDOW: usize = 20;
/// Progress below this many χ² units over [`STALL_WINDOW`] steps counts as converged: Δχ² = 1 is
/// one standard error along one direction, so what is left moves nothing the data can see. This
/// ends LM's crawl along directions the data leave (nearly) flat, where its relative tolerances
/// would exhaust the iteration limit instead.
pub const STALL_CHI2: f64 = 1e-3;

/// Wraps a solver so that a shared flag stops it at the next iteration boundary, and so that a
/// statistically invisible crawl ([`STALL_CHI2`]) stops it as converged.
pub struct Cancellable<S> {
    pub inner: S,
    pub flag: Option<Arc<AtomicBool>>,
    /// Degrees of freedom of the residuals (0: no stall test).
    pub dof: usize,
    /// Cost after each step so far.
    pub costs: Vec<f64>,
}

impl<O, S: Solver<O, LmState>> Solver<O, LmState> for Cancellable<S> {
    fn name(&self) -> &str {
        self.inner.name()
    }
    fn init(
        &mut self,
        problem: &mut Problem<O>,
        state: LmState,
    ) -> Result<(LmState, Option<KV>), ArgminError> {
        self.inner.init(problem, state)
    }
    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        state: LmState,
    ) -> Result<(LmState, Option<KV>), ArgminError> {
        let out = self.inner.next_iter(problem, state)?;
        self.costs.push(out.0.get_cost());
        Ok(out)
    }
    fn terminate(&mut self, state: &LmState) -> TerminationStatus {
        if is_cancelled(&self.flag) {
            return TerminationStatus::Terminated(TerminationReason::Interrupt);
        }
        let k = self.costs.len();
        if self.dof > 0 && k > STALL_WINDOW {
            let (then, now) = (self.costs[k - 1 - STALL_WINDOW], self.costs[k - 1]);
            // Δχ² = 2Δcost/s² with s² = 2·cost/dof.
            if now > 0.0 && (then - now) * self.dof as f64 / now < STALL_CHI2 {
                return TerminationStatus::Terminated(TerminationReason::SolverConverged);
            }
        }
        self.inner.terminate(state)
    }
}

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
pub fn local_solver(dof: usize) -> crate::lm::LevenbergMarquardt {
    crate::lm::LevenbergMarquardt::new()
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

/// Run the local solver from `u0` for at most `max_iters` iterations. A raised `cancel` stops it
/// within one chunk of samples, with the best point reached so far.
pub fn run_local<F: Forward>(
    ev: &Evaluator<'_, F>,
    u0: &[f64],
    max_iters: u64,
    cancel: &Option<Arc<AtomicBool>>,
) -> LocalRun {
    run_local_with_progress(ev, u0, max_iters, cancel, None)
}

/// [`run_local`], showing each iteration and its cost on `progress` (the polish on all data can
/// take minutes on millions of samples).
pub fn run_local_with_progress<F: Forward>(
    ev: &Evaluator<'_, F>,
    u0: &[f64],
    max_iters: u64,
    cancel: &Option<Arc<AtomicBool>>,
    progress: Option<&indicatif::ProgressBar>,
) -> LocalRun {
    let t0 = Instant::now();
    let full_cost = |u: &[f64]| ev.cost_internal(u, None).unwrap_or(f64::INFINITY);
    let history = Arc::new(Mutex::new(Vec::new()));
    let last = Arc::new(Mutex::new(None));
    let dof = ev
        .n_residuals()
        .saturating_sub(ev.n_params() + ev.n_channels);
    let solver = Cancellable {
        inner: local_solver(dof),
        flag: cancel.clone(),
        dof,
        costs: Vec::new(),
    };
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
