//! Behaviour of the Levenberg–Marquardt solver through argmin's Executor.

use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{Error as ArgminError, Executor, Jacobian, Operator, State, KV};
use hairfit::lm::{LevenbergMarquardt, LmState, LmTermination};
use lm::{minimize, LmOptions};
use nalgebra::{DMatrix, DVector};
use std::sync::{Arc, Mutex};

use crate::support::lm;

/// Rosenbrock as residuals: r = (10 (x2 - x1²), 1 - x1), zero at (1, 1).
struct Rosenbrock;

impl Operator for Rosenbrock {
    type Param = DVector<f64>;
    type Output = DVector<f64>;
    fn apply(&self, x: &DVector<f64>) -> Result<DVector<f64>, ArgminError> {
        Ok(DVector::from_vec(vec![
            10.0 * (x[1] - x[0] * x[0]),
            1.0 - x[0],
        ]))
    }
}

impl Jacobian for Rosenbrock {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;
    fn jacobian(&self, x: &DVector<f64>) -> Result<DMatrix<f64>, ArgminError> {
        Ok(DMatrix::from_row_slice(
            2,
            2,
            &[-20.0 * x[0], 10.0, -1.0, 0.0],
        ))
    }
}

/// r(x) = ln x - ln 4: undefined for x ≤ 0, where a full Gauss–Newton step from x = 100 lands.
struct Log;

impl Operator for Log {
    type Param = DVector<f64>;
    type Output = DVector<f64>;
    fn apply(&self, x: &DVector<f64>) -> Result<DVector<f64>, ArgminError> {
        Ok(DVector::from_vec(vec![x[0].ln() - 4f64.ln()]))
    }
}

impl Jacobian for Log {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;
    fn jacobian(&self, x: &DVector<f64>) -> Result<DMatrix<f64>, ArgminError> {
        Ok(DMatrix::from_element(1, 1, 1.0 / x[0]))
    }
}

/// Linear model r = A x - b: LM must land on the least-squares solution.
struct Linear {
    a: DMatrix<f64>,
    b: DVector<f64>,
}

impl Operator for Linear {
    type Param = DVector<f64>;
    type Output = DVector<f64>;
    fn apply(&self, x: &DVector<f64>) -> Result<DVector<f64>, ArgminError> {
        Ok(&self.a * x - &self.b)
    }
}

impl Jacobian for Linear {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;
    fn jacobian(&self, _x: &DVector<f64>) -> Result<DMatrix<f64>, ArgminError> {
        Ok(self.a.clone())
    }
}

/// Records every iteration's KV and cost.
#[derive(Clone, Default)]
struct Recorder(Arc<Mutex<Vec<(f64, KV)>>>);

impl Observe<LmState> for Recorder {
    fn observe_iter(&mut self, state: &LmState, kv: &KV) -> Result<(), ArgminError> {
        self.0.lock().unwrap().push((state.get_cost(), kv.clone()));
        Ok(())
    }
}

#[test]
fn rosenbrock_converges_to_its_zero_residual_minimum() {
    let res = Executor::new(Rosenbrock, LevenbergMarquardt::new())
        .configure(|s| s.param(DVector::from_vec(vec![-1.2, 1.0])).max_iters(200))
        .run()
        .unwrap();
    let x = res.state().get_param().unwrap();
    // Zero-residual problem: LM converges quadratically, so the iterate is exact to rounding.
    assert!(
        (x[0] - 1.0).abs() < 1e-12 && (x[1] - 1.0).abs() < 1e-12,
        "{x}"
    );
    assert!(res.solver().termination().is_some());
    assert!(res.state().get_iter() < 200);
}

#[test]
fn non_finite_residuals_are_rejected_steps_not_nans() {
    let rec = Recorder::default();
    let res = Executor::new(Log, LevenbergMarquardt::new())
        .configure(|s| s.param(DVector::from_vec(vec![100.0])).max_iters(200))
        .add_observer(rec.clone(), ObserverMode::Always)
        .run()
        .unwrap();
    let x = res.state().get_param().unwrap()[0];
    // One well-conditioned unknown: converged to rounding of ln.
    assert!((x - 4.0).abs() < 1e-12, "{x}");
    let log = rec.0.lock().unwrap();
    assert!(log.iter().all(|(c, _)| c.is_finite()));
    let rejected = log
        .iter()
        .filter(|(_, kv)| kv.get("accepted").and_then(|v| v.get_bool()) == Some(false))
        .count();
    assert!(rejected >= 1, "the first step from x = 100 reaches x ≤ 0");
}

#[test]
fn observers_see_cost_lambda_step_and_gain_ratio() {
    let rec = Recorder::default();
    let res = Executor::new(Rosenbrock, LevenbergMarquardt::new())
        .configure(|s| s.param(DVector::from_vec(vec![-1.2, 1.0])).max_iters(200))
        .add_observer(rec.clone(), ObserverMode::Always)
        .run()
        .unwrap();
    let log = rec.0.lock().unwrap();
    assert_eq!(log.len() as u64, res.state().get_iter());
    for (cost, kv) in log.iter() {
        for key in ["cost", "lambda", "delta", "step_norm", "gain_ratio"] {
            assert!(kv.get(key).and_then(|v| v.get_float()).is_some(), "{key}");
        }
        assert_eq!(kv.get("cost").unwrap().get_float().unwrap(), *cost);
    }
    // Accepted steps never increase the cost.
    assert!(log.windows(2).all(|w| w[1].0 <= w[0].0));
}

#[test]
fn cost_is_half_the_squared_residual_norm() {
    let res = Executor::new(Rosenbrock, LevenbergMarquardt::new())
        .configure(|s| s.param(DVector::from_vec(vec![-1.2, 1.0])).max_iters(0))
        .run()
        .unwrap();
    // r(-1.2, 1) = (10 (1 - 1.44), 2.2) = (-4.4, 2.2): ½‖r‖² = 12.1.
    assert!((res.state().get_cost() - 12.1).abs() < 1e-12);
}

#[test]
fn linear_least_squares_matches_the_qr_solution() {
    let a = DMatrix::from_row_slice(
        5,
        3,
        &[
            1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 2.0, 4.0, 1.0, 3.0, 9.0, 1.0, 4.0, 16.0,
        ],
    );
    let b = DVector::from_vec(vec![1.0, 2.5, 2.9, 4.2, 7.1]);
    let qr = a.clone().qr();
    let exact = qr
        .r()
        .solve_upper_triangular(&(qr.q().transpose() * &b))
        .unwrap();
    let report = minimize(Linear { a, b }, DVector::zeros(3), LmOptions::default()).unwrap();
    // cond(A) ≈ 50: the solution is determined to ~1e-14; 1e-11 is generous.
    assert!((&report.param - &exact).abs().max() < 1e-11);
    assert!(report.converged(), "{report:?}");
    assert!(report.jacobian_evals >= 1);
    assert_eq!(report.jacobian.shape(), (5, 3));
}

#[test]
fn missing_or_empty_start_is_an_error_not_a_panic() {
    let res = Executor::new(Rosenbrock, LevenbergMarquardt::new()).run();
    assert!(res.is_err());
    let empty = minimize(Rosenbrock, DVector::zeros(0), LmOptions::default());
    assert!(empty.is_err());
}

#[test]
fn non_finite_start_is_an_error_not_a_panic() {
    let res = minimize(Log, DVector::from_vec(vec![-1.0]), LmOptions::default());
    let msg = res.unwrap_err().to_string();
    assert!(msg.contains("not finite"), "{msg}");
}

#[test]
fn no_observations_is_a_zero_residual_fit() {
    let no_data = Linear {
        a: DMatrix::zeros(0, 2),
        b: DVector::zeros(0),
    };
    let report = minimize(
        no_data,
        DVector::from_vec(vec![1.0, 2.0]),
        LmOptions::default(),
    )
    .unwrap();
    assert_eq!(report.termination, Some(LmTermination::ZeroResidual));
    assert_eq!(report.param.as_slice(), &[1.0, 2.0]);
}

#[test]
fn zero_residual_start_stops_immediately() {
    let report = minimize(
        Rosenbrock,
        DVector::from_vec(vec![1.0, 1.0]),
        LmOptions::default(),
    )
    .unwrap();
    assert_eq!(report.termination, Some(LmTermination::ZeroResidual));
    assert_eq!(report.iterations, 0);
}

#[test]
fn rank_deficient_and_underdetermined_problems_still_converge() {
    // Columns 2 and 3 are equal: only x1 + x2 is determined; the minimum SS is still reached.
    let a = DMatrix::from_row_slice(
        4,
        3,
        &[1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 1.0, 3.0, 3.0],
    );
    let b = DVector::from_vec(vec![0.9, 3.1, 5.0, 7.1]);
    let report = minimize(Linear { a, b }, DVector::zeros(3), LmOptions::default()).unwrap();
    // Straight-line fit of b on t = 0..3: slope 10.25/5 = 2.05, intercept 4.025 - 1.5·2.05 = 0.95.
    // The determined part has condition ~5, so rounding is ~1e-15; 1e-10 is generous.
    let x = &report.param;
    assert!(
        (x[0] - 0.95).abs() < 1e-10 && (x[1] + x[2] - 2.05).abs() < 1e-10,
        "{x}"
    );
    assert!(report.param.iter().all(|v| v.is_finite()));

    // One equation, two unknowns: any point on x0 + x1 = 2 is a zero-residual solution.
    let under = Linear {
        a: DMatrix::from_row_slice(1, 2, &[1.0, 1.0]),
        b: DVector::from_vec(vec![2.0]),
    };
    let report = minimize(
        under,
        DVector::from_vec(vec![5.0, -1.0]),
        LmOptions::default(),
    )
    .unwrap();
    // Linear and consistent: the residual reaches rounding level of the inputs.
    assert!(report.cost < 1e-28, "{}", report.cost);
}

/// y = a·exp(−b·t) + c at 200 points of [0, 5] with deterministic pseudo-noise of σ = 0.01.
struct NoisyDecay {
    t: Vec<f64>,
    y: Vec<f64>,
}

impl NoisyDecay {
    fn new() -> Self {
        let mut state = 7u64;
        let mut uniform = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let t: Vec<f64> = (0..200).map(|i| 5.0 * i as f64 / 199.0).collect();
        // Sum of 12 uniforms − 6: close to a unit normal.
        let y = t
            .iter()
            .map(|&t| {
                let noise: f64 = (0..12).map(|_| uniform()).sum::<f64>() - 6.0;
                2.0 * (-1.3 * t).exp() + 0.5 + 0.01 * noise
            })
            .collect();
        NoisyDecay { t, y }
    }
}

impl Operator for NoisyDecay {
    type Param = DVector<f64>;
    type Output = DVector<f64>;
    fn apply(&self, p: &DVector<f64>) -> Result<DVector<f64>, ArgminError> {
        Ok(DVector::from_iterator(
            self.t.len(),
            self.t
                .iter()
                .zip(&self.y)
                .map(|(&t, &y)| p[0] * (-p[1] * t).exp() + p[2] - y),
        ))
    }
}

impl Jacobian for NoisyDecay {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;
    fn jacobian(&self, p: &DVector<f64>) -> Result<DMatrix<f64>, ArgminError> {
        Ok(DMatrix::from_fn(self.t.len(), 3, |i, j| {
            let e = (-p[1] * self.t[i]).exp();
            match j {
                0 => e,
                1 => -p[0] * self.t[i] * e,
                _ => 1.0,
            }
        }))
    }
}

#[test]
fn statistical_stop_ends_within_its_share_of_a_standard_error() {
    let start = DVector::from_vec(vec![1.0, 0.5, 0.0]);
    let exact = minimize(NoisyDecay::new(), start.clone(), LmOptions::default()).unwrap();
    let dof = 200 - 3;
    let chi2 = 1e-3;
    let options = LmOptions {
        dof,
        chi2,
        ..LmOptions::default()
    };
    let early = minimize(NoisyDecay::new(), start, options).unwrap();
    assert_eq!(
        early.termination,
        Some(LmTermination::StatisticallyConverged)
    );
    assert!(
        early.iterations < exact.iterations,
        "{} iterations, {} to rounding level",
        early.iterations,
        exact.iterations
    );
    // Standard errors at the rounding-level optimum: s²(JᵀJ)⁻¹ with s² = ‖r‖²/dof.
    let s2 = 2.0 * exact.cost / dof as f64;
    let cov = (exact.jacobian.transpose() * &exact.jacobian)
        .try_inverse()
        .unwrap()
        * s2;
    for i in 0..3 {
        let se = cov[(i, i)].sqrt();
        let moved = (early.param[i] - exact.param[i]).abs();
        // The stop is taken where the Gauss–Newton step predicts Δχ² ≤ chi2, which bounds each
        // parameter's distance by √chi2 standard errors; 10% slack for the quadratic model.
        assert!(
            moved <= 1.1 * chi2.sqrt() * se,
            "parameter {i} is {moved:.3e} from the optimum, SE {se:.3e}"
        );
    }
    assert!(early.cost >= exact.cost * (1.0 - 1e-12));
}

#[test]
fn statistical_stop_at_the_optimum_takes_no_step() {
    let exact = minimize(
        NoisyDecay::new(),
        DVector::from_vec(vec![1.0, 0.5, 0.0]),
        LmOptions::default(),
    )
    .unwrap();
    let options = LmOptions {
        dof: 197,
        chi2: 1e-3,
        ..LmOptions::default()
    };
    let again = minimize(NoisyDecay::new(), exact.param.clone(), options).unwrap();
    assert_eq!(
        again.termination,
        Some(LmTermination::StatisticallyConverged)
    );
    assert_eq!(again.iterations, 0);
    assert_eq!(again.param, exact.param);
}

/// y = 2 e^(−0.3 t) with a ±2% ripple, fitted by r = a e^(−b t) − y (a nonzero residual, so the
/// run ends by the cost test rather than at an exact zero).
struct Decay {
    t: Vec<f64>,
    y: Vec<f64>,
}

impl Decay {
    fn new() -> Decay {
        let t: Vec<f64> = (0..20).map(|k| 0.5 * k as f64).collect();
        let y = t
            .iter()
            .enumerate()
            .map(|(k, t)| 2.0 * (-0.3 * t).exp() * (1.0 + 0.02 * (k as f64 * 1.7).sin()))
            .collect();
        Decay { t, y }
    }
}

impl Operator for Decay {
    type Param = DVector<f64>;
    type Output = DVector<f64>;
    fn apply(&self, x: &DVector<f64>) -> Result<DVector<f64>, ArgminError> {
        Ok(DVector::from_iterator(
            self.t.len(),
            self.t
                .iter()
                .zip(&self.y)
                .map(|(t, y)| x[0] * (-x[1] * t).exp() - y),
        ))
    }
}

impl Jacobian for Decay {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;
    fn jacobian(&self, x: &DVector<f64>) -> Result<DMatrix<f64>, ArgminError> {
        let mut j = DMatrix::zeros(self.t.len(), 2);
        for (k, t) in self.t.iter().enumerate() {
            let e = (-x[1] * t).exp();
            j[(k, 0)] = e;
            j[(k, 1)] = -x[0] * t * e;
        }
        Ok(j)
    }
}

/// With the lazy final linearisation a run that ends by the cost test takes the same steps to
/// the same point and cost (bit for bit: the same trials, accepted alike) and skips exactly the
/// one Jacobian at its end, which its final state then does not pretend to have.
#[test]
fn lazy_final_linearization_skips_only_the_last_jacobian() {
    let run = |lazy_final: bool| {
        let options = LmOptions {
            // Loose enough that the last step gains more than the cost's rounding noise (a
            // noise-level step is judged by a linearisation there, which the lazy end keeps).
            ftol: 1e-5,
            lazy_final,
            ..LmOptions::default()
        };
        minimize(Decay::new(), DVector::from_vec(vec![1.0, 0.1]), options).unwrap()
    };
    let (plain, lazy) = (run(false), run(true));
    assert_eq!(plain.termination, Some(LmTermination::CostConverged));
    assert_eq!(lazy.termination, Some(LmTermination::CostConverged));
    assert_eq!(lazy.param, plain.param);
    assert_eq!(lazy.cost.to_bits(), plain.cost.to_bits());
    assert_eq!(lazy.iterations, plain.iterations);
    assert_eq!(lazy.jacobian_evals + 1, plain.jacobian_evals);
    assert_eq!(
        lazy.jacobian.shape(),
        (0, 0),
        "no Jacobian at the final point"
    );
    assert_eq!(plain.jacobian.shape(), (20, 2));
}
