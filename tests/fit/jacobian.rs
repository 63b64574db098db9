//! The fit's exact Jacobian (AD through the model, the bound transforms, the variable projection
//! and the robust loss) against central finite differences of its own residual vector.

use crate::support;
use hairfit::families::marschner::fit::forward::MarschnerForward;
use hairfit::families::marschner::parameters::fitted_parameters;
use hairfit::families::marschner::parameters::reference_params;
use hairfit::families::marschner::{Effects, ModelConfig, RootMode};
use hairfit::fit::{Evaluator, Loss, Space};
use hairfit::geometry::Measurement;

fn check(space: Space, loss: Loss, mode: RootMode, seed: u64) {
    check_with(space, loss, mode, seed, false, Measurement::S)
}

/// `zeros`: every 7th value is 0 and every 11th negative, so log space has linear-fallback rows.
fn check_with(
    space: Space,
    loss: Loss,
    mode: RootMode,
    seed: u64,
    zeros: bool,
    measurement: Measurement,
) {
    let truth = support::fit::random_params(seed, 3);
    let angles = support::fit::random_sphere(60, seed);
    let mut data = support::fit::data(&truth, &angles, 0.05, seed);
    if zeros {
        for (k, v) in data.values.iter_mut().enumerate() {
            if k % 7 == 3 {
                *v = 0.0;
            } else if k % 11 == 5 {
                *v = -0.5 * v.abs();
            }
        }
    }
    let fwd = MarschnerForward {
        config: ModelConfig {
            mode,
            effects: Effects::default(),
        },
        measurement,
    };
    let free = fitted_parameters(&Effects::default(), 3, true);
    let (ev, _) = Evaluator::new(&fwd, &data, space, loss, 0.5, reference_params(3), free).unwrap();
    // An interior point away from the truth: residuals are O(1), so every term of the chain
    // rule (projection included) is exercised.
    let x: Vec<f64> = {
        let p = support::fit::random_params(seed + 100, 3);
        ev.free.iter().map(|&n| p.get(n)).collect()
    };
    let mut u = ev.internal(&x);
    if ev.explicit_scale {
        u.extend([0.3, -0.2, 0.1]);
    }
    let e = ev.eval_internal(&u, true);
    let j = e.jacobian.as_ref().unwrap();
    let n = e.n_cols;
    assert_eq!(n, u.len());
    for k in 0..n {
        // h = 1e-6 in internal units: central-difference truncation O(h²·r‴) ≈ 1e-12 and rounding
        // O(ε·|r|/h) ≈ 1e-10 relative to the residual scale.
        let h = 1e-6;
        let mut up = u.clone();
        up[k] += h;
        let mut um = u.clone();
        um[k] -= h;
        let rp = ev.eval_internal(&up, false).residual;
        let rm = ev.eval_internal(&um, false).residual;
        let col_scale = (0..rp.len())
            .map(|i| j[i * n + k].abs())
            .fold(1e-3, f64::max);
        for i in 0..rp.len() {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            let ad = j[i * n + k];
            // 1e-5 of the column's largest entry: FD error (above) plus cubic-mode root kinks
            // are far below it, while a wrong chain-rule term is O(1) of the column.
            assert!(
                (fd - ad).abs() <= 1e-5 * col_scale,
                "{space:?} {loss:?} {mode:?} seed {seed}: d r[{i}] / d u[{k}] ({}) AD {ad} vs FD {fd}",
                ev.free.get(k).map_or("scale".into(), |p| p.json_name())
            );
        }
    }
}

#[test]
fn jacobian_matches_finite_differences_in_log_space() {
    check(Space::Log, Loss::L2, RootMode::Cubic, 1);
    check(Space::Log, Loss::L2, RootMode::Exact, 2);
}

#[test]
fn jacobian_matches_finite_differences_in_linear_space() {
    check(Space::Linear, Loss::L2, RootMode::Cubic, 3);
}

#[test]
fn jacobian_matches_finite_differences_with_robust_losses_and_explicit_scale() {
    check(Space::Log, Loss::Cauchy, RootMode::Cubic, 4);
    check(Space::Linear, Loss::Huber, RootMode::Cubic, 5);
    check(Space::Log, Loss::SoftL1, RootMode::Cubic, 6);
}

#[test]
fn jacobian_matches_finite_differences_with_linear_fallback_rows_in_log_space() {
    check_with(
        Space::Log,
        Loss::L2,
        RootMode::Cubic,
        7,
        true,
        Measurement::S,
    );
    check_with(
        Space::Log,
        Loss::Huber,
        RootMode::Exact,
        8,
        true,
        Measurement::S,
    );
}

#[test]
fn jacobian_matches_finite_differences_for_radiance_data() {
    // The cos θ_i factor rides on values and gradients alike (|θ_i| up to 85°: factors down to
    // 0.09), through the projection, a robust loss and linear-fallback rows.
    let r = Measurement::Radiance;
    check_with(Space::Log, Loss::L2, RootMode::Cubic, 9, false, r);
    check_with(Space::Linear, Loss::L2, RootMode::Cubic, 10, false, r);
    check_with(Space::Log, Loss::Cauchy, RootMode::Cubic, 11, true, r);
}
