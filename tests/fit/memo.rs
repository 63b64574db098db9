//! The evaluator's memo of recent model passes: a pass at a point already evaluated runs no model
//! evaluation, what it returns is exactly what the model gives (bit for bit against an evaluator
//! that keeps nothing), and a different point never reads another's pass. For the Chiang family
//! with η fixed the gradients ride along with every value pass, so the linearisation after a
//! trial, the standard errors' linearisation and the residual pass at the end are all free.

use crate::support;
use std::sync::atomic::{AtomicUsize, Ordering};

use hairfit::families::chiang::fit::ChiangForward;
use hairfit::families::chiang::{ChiangModel, ChiangParamName, ChiangParams};
use hairfit::families::marschner::fit::forward::MarschnerForward;
use hairfit::families::marschner::parameters::fitted_parameters;
use hairfit::families::marschner::parameters::reference_params;
use hairfit::families::marschner::{Effects, ModelConfig};
use hairfit::fit::{Evaluator, FitData, FitParam, Forward, Loss, ParamSet, ScaleMode, Space};
use hairfit::geometry::{Angles, Measurement};

/// A forward model that counts the samples it evaluates, by kind of pass.
struct Counting<F> {
    inner: F,
    values: AtomicUsize,
    gradients: AtomicUsize,
}

impl<F> Counting<F> {
    fn new(inner: F) -> Self {
        Counting {
            inner,
            values: AtomicUsize::new(0),
            gradients: AtomicUsize::new(0),
        }
    }
    /// Samples evaluated so far: (values, gradients).
    fn counts(&self) -> (usize, usize) {
        (
            self.values.load(Ordering::SeqCst),
            self.gradients.load(Ordering::SeqCst),
        )
    }
}

impl<F: Forward> Forward for Counting<F> {
    type Param = F::Param;
    fn values(&self, p: &ParamSet<F>, angles: &[Angles], out: &mut [f64]) {
        self.values.fetch_add(angles.len(), Ordering::SeqCst);
        self.inner.values(p, angles, out)
    }
    fn gradients(
        &self,
        p: &ParamSet<F>,
        free: &[F::Param],
        angles: &[Angles],
        out: &mut [f64],
        grad: &mut [f64],
    ) {
        self.gradients.fetch_add(angles.len(), Ordering::SeqCst);
        self.inner.gradients(p, free, angles, out, grad)
    }
    fn gradients_compressed(
        &self,
        p: &ParamSet<F>,
        shared: &[F::Param],
        local: &[Option<F::Param>],
        angles: &[Angles],
        out: &mut [f64],
        grad: &mut [f64],
    ) {
        self.gradients.fetch_add(angles.len(), Ordering::SeqCst);
        self.inner
            .gradients_compressed(p, shared, local, angles, out, grad)
    }
    fn cheap_gradients(&self, free: &[F::Param]) -> bool {
        self.inner.cheap_gradients(free)
    }
    fn measurement(&self) -> Measurement {
        self.inner.measurement()
    }
}

/// Data from `forward` at `truth` on random directions, with a deterministic ±3% ripple.
fn data<F: Forward>(forward: &F, truth: &ParamSet<F>, nc: usize, n: usize) -> FitData {
    let angles = support::fit::random_sphere(n, 11);
    let mut values = vec![0.0; n * nc];
    forward.values(truth, &angles, &mut values);
    for (k, v) in values.iter_mut().enumerate() {
        *v *= 1.0 + 0.03 * ((k * 7919 % 13) as f64 / 6.0 - 1.0);
    }
    FitData {
        channels: (0..nc).map(|c| format!("c{c}")).collect(),
        angles,
        values,
        sigma: None,
        weight: None,
        line: Vec::new(),
    }
}

/// What a fit's passes at one point give: the trial's cost and scale, the solver's
/// linearisation after it, the residual pass, and the standard errors' linearisation.
struct Passes {
    cost: f64,
    scale: Vec<f64>,
    solver: (Vec<f64>, Vec<f64>),
    residual: Vec<f64>,
    fixed: (Vec<f64>, Vec<f64>),
}

fn passes<F: Forward>(ev: &Evaluator<'_, F>, x: &[f64]) -> Passes {
    let u = ev.internal(x);
    let (cost, scale) = ev.cost_and_scale(&u, None).unwrap();
    let lin = ev
        .linearize_internal(&u, Some(scale.clone()), None)
        .unwrap();
    let residual = ev.eval_internal(&u, false).residual;
    // As the fit's standard errors: at the solver point's natural values (the round trip
    // through the bounds' transform need not return `x` to the bit).
    let at = ev.natural(&u);
    let col: Vec<f64> = (0..x.len()).map(|j| 1.0 + 0.1 * j as f64).collect();
    let natural: Vec<f64> = scale.iter().map(|s| s.exp()).collect();
    let fixed = ev
        .linearize(&at, &col, ScaleMode::FixedNatural(&natural), None)
        .unwrap();
    let flat = |l: &hairfit::fit::problem::Linearization| {
        (l.matrix().as_slice().to_vec(), l.rhs().as_slice().to_vec())
    };
    Passes {
        cost,
        scale,
        solver: flat(&lin),
        residual,
        fixed: flat(&fixed),
    }
}

fn assert_same(a: &Passes, b: &Passes, what: &str) {
    assert_eq!(a.cost.to_bits(), b.cost.to_bits(), "{what}: cost");
    assert_eq!(a.scale, b.scale, "{what}: scale");
    assert_eq!(a.solver, b.solver, "{what}: solver linearisation");
    assert_eq!(a.residual, b.residual, "{what}: residuals");
    assert_eq!(a.fixed, b.fixed, "{what}: fixed-scale linearisation");
}

/// 700 samples: three chunks, the last one partial.
const N: usize = 700;

/// A log-space least-squares evaluator over `d`; `limit`: its memo's budget in bytes (None: the
/// default).
fn evaluator<'a, F: Forward>(
    forward: &'a F,
    d: &'a FitData,
    base: ParamSet<F>,
    free: Vec<F::Param>,
    limit: Option<usize>,
) -> Evaluator<'a, F> {
    let (ev, _) = Evaluator::new(forward, d, Space::Log, Loss::L2, 1.0, base, free).unwrap();
    match limit {
        Some(bytes) => ev.with_memo_limit(bytes),
        None => ev,
    }
}

#[test]
fn chiang_passes_at_one_point_run_the_model_once() {
    let nc = 2;
    let forward = Counting::new(ChiangForward {
        model: ChiangModel::default(),
        measurement: Measurement::S,
    });
    let truth = ChiangParams {
        eta: 1.55,
        sigma_a: vec![0.3, 0.9],
        beta_m: 0.2,
        beta_n: 0.35,
        alpha: 2f64.to_radians(),
    };
    let d = data(&forward.inner, &truth, nc, N);
    let free = vec![
        ChiangParamName::SigmaA(0),
        ChiangParamName::SigmaA(1),
        ChiangParamName::BetaM,
        ChiangParamName::BetaN,
        ChiangParamName::Alpha,
    ];
    let x: Vec<f64> = free.iter().map(|&p| p.get(&truth) * 1.02).collect();
    let new = |limit| evaluator(&forward, &d, truth.clone(), free.clone(), limit);
    let kept = passes(&new(None), &x);
    // η fixed: the trial's value pass computes the gradients too, and nothing after it runs
    // the model again.
    assert_eq!(forward.counts(), (0, N), "one gradient pass, no value pass");

    let before = forward.counts();
    let plain = passes(&new(Some(0)), &x);
    let (v, g) = forward.counts();
    assert!(
        v - before.0 >= 2 * N && g - before.1 >= 2 * N,
        "without the memo every pass runs the model: {:?}",
        (v - before.0, g - before.1)
    );
    assert_same(&kept, &plain, "chiang");
}

#[test]
fn marschner_passes_reuse_the_gradient_and_value_passes() {
    let nc = 3;
    let forward = Counting::new(MarschnerForward {
        config: ModelConfig::default(),
        measurement: Measurement::S,
    });
    let truth = support::fit::random_params(5, nc);
    let d = data(&forward.inner, &truth, nc, N);
    let free = fitted_parameters(&Effects::default(), nc, true);
    let x: Vec<f64> = free.iter().map(|&p| p.get(&truth) * 1.01 + 1e-3).collect();
    let ev = evaluator(&forward, &d, reference_params(nc), free.clone(), None);
    let kept = passes(&ev, &x);
    // Gradients are not cheap here: one value pass (the trial) and one gradient pass (the
    // solver's linearisation); the residual pass and the fixed-scale linearisation reuse them.
    assert_eq!(forward.counts(), (N, N));

    // A different point runs the model again.
    let mut y = x.clone();
    y[0] *= 1.0 + 1e-9;
    let u = ev.internal(&y);
    ev.cost_and_scale(&u, None).unwrap();
    assert_eq!(
        forward.counts(),
        (2 * N, N),
        "no pass is read at another point"
    );

    let ev0 = evaluator(&forward, &d, reference_params(nc), free, Some(0));
    let plain = passes(&ev0, &x);
    assert_same(&kept, &plain, "marschner");
}
