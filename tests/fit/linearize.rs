//! The accumulated linearisation (per-channel QR over chunks, compressed σ_a seeding, projected
//! scale applied afterwards) carries the same information as the dense AD Jacobian: `MᵀM = JᵀJ`,
//! `Mᵀt = Jᵀr̃`, `‖t‖ = ‖r̃‖`, in every space, loss and scale mode; it is bit-identical for any
//! thread count, and its size does not grow with the number of samples.

use crate::support;
use hairfit::families::marschner::fit::forward::MarschnerForward;
use hairfit::families::marschner::parameters::fitted_parameters;
use hairfit::families::marschner::parameters::reference_params;
use hairfit::families::marschner::{Effects, ModelConfig};
use hairfit::fit::{Evaluator, Loss, ScaleMode, Space};
use hairfit::geometry::Measurement;
use nalgebra::{DMatrix, DVector};

const NC: usize = 3;

fn forward() -> MarschnerForward {
    MarschnerForward {
        config: ModelConfig::default(),
        measurement: Measurement::S,
    }
}

/// Data with 700 samples (three chunks, the last one partial); in log space every 7th value is 0
/// so linear-fallback rows take part.
fn data(samples: usize, zeros: bool) -> hairfit::fit::FitData {
    let truth = support::fit::random_params(4, NC);
    let angles = support::fit::random_sphere(samples, 4);
    let mut d = support::fit::data(&truth, &angles, 0.05, 4);
    if zeros {
        for (k, v) in d.values.iter_mut().enumerate() {
            if k % 7 == 3 {
                *v = 0.0;
            }
        }
    }
    d
}

/// `|a − b| ≤ tol·√(a_ii b_jj)` entrywise: QR and direct products round differently, by ~1e-15
/// of the matrix's scale; 1e-9 is far above that and far below any missing term.
fn assert_gram_close(a: &DMatrix<f64>, b: &DMatrix<f64>, what: &str) {
    assert_eq!(a.shape(), b.shape(), "{what}");
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            let s = (a[(i, i)].abs() * a[(j, j)].abs()).sqrt().max(1e-300);
            assert!(
                (a[(i, j)] - b[(i, j)]).abs() <= 1e-9 * s,
                "{what} ({i},{j}): {} vs {}",
                a[(i, j)],
                b[(i, j)]
            );
        }
    }
}

fn check(space: Space, loss: Loss, fixed: bool) {
    let d = data(700, space == Space::Log);
    let fwd = forward();
    let free = fitted_parameters(&Effects::default(), NC, true);
    let (ev, _) = Evaluator::new(&fwd, &d, space, loss, 0.5, reference_params(NC), free).unwrap();
    let p = support::fit::random_params(104, NC);
    let x: Vec<f64> = ev.free.iter().map(|&n| p.get(n)).collect();
    let (dense, lin) = if fixed {
        let col: Vec<f64> = (0..x.len()).map(|j| 1.0 + 0.1 * j as f64).collect();
        let scale = [0.7, 1.3, 2.0];
        (
            ev.evaluate(&x, &col, ScaleMode::FixedNatural(&scale), true),
            ev.linearize(&x, &col, ScaleMode::FixedNatural(&scale), None)
                .unwrap(),
        )
    } else {
        let mut u = ev.internal(&x);
        if ev.explicit_scale {
            u.extend([0.3, -0.2, 0.1]);
        }
        assert!(
            (ev.cost_internal(&u, None).unwrap() / ev.eval_internal(&u, false).cost() - 1.0).abs()
                < 1e-12
        );
        let lin = ev.linearize_internal(&u, None, None).unwrap();
        // The LM passes the trial's scale to the linearisation at the same point: exactly the
        // scale the linearisation finds itself, so the system is the same to the bit.
        let (_, trial_scale) = ev.cost_and_scale(&u, None).unwrap();
        let reused = ev.linearize_internal(&u, Some(trial_scale), None).unwrap();
        assert_eq!(lin.matrix(), reused.matrix());
        assert_eq!(lin.rhs(), reused.rhs());
        (ev.eval_internal(&u, true), lin)
    };
    let m = dense.residual.len();
    let j = DMatrix::from_row_slice(m, dense.n_cols, dense.jacobian.as_deref().unwrap());
    let r = DVector::from_column_slice(&dense.residual);
    let what = format!("{space} {loss} fixed={fixed}");
    assert_eq!(lin.rows, m);
    assert_gram_close(
        &(j.tr_mul(&j)),
        &(lin.matrix().tr_mul(&lin.matrix())),
        &what,
    );
    let (g, gl) = (j.tr_mul(&r), lin.matrix().tr_mul(&lin.rhs()));
    let jn = j.tr_mul(&j);
    for k in 0..g.len() {
        // Same scale argument as the Gram matrix: |Jᵀr|_k ≤ ‖J_k‖‖r‖.
        let s = (jn[(k, k)] * r.norm_squared()).sqrt().max(1e-300);
        assert!(
            (g[k] - gl[k]).abs() <= 1e-9 * s,
            "{what} gradient {k}: {} vs {}",
            g[k],
            gl[k]
        );
    }
    assert!(
        (lin.rhs().norm() / r.norm() - 1.0).abs() < 1e-12,
        "{what} residual norm"
    );
    for (a, b) in lin.scale.iter().zip(&dense.scale) {
        assert!((a / b - 1.0).abs() < 1e-12, "{what} scale {a} vs {b}");
    }
}

#[test]
fn projected_log_scale_with_fallback_rows_matches_the_dense_jacobian() {
    check(Space::Log, Loss::L2, false);
}

#[test]
fn projected_linear_scale_matches_the_dense_jacobian() {
    check(Space::Linear, Loss::L2, false);
}

#[test]
fn explicit_scale_under_a_robust_loss_matches_the_dense_jacobian() {
    check(Space::Log, Loss::Cauchy, false);
    check(Space::Linear, Loss::Huber, false);
}

#[test]
fn fixed_scale_columns_for_standard_errors_match_the_dense_jacobian() {
    check(Space::Log, Loss::L2, true);
    check(Space::Linear, Loss::SoftL1, true);
}

#[test]
fn linearisation_is_identical_for_any_thread_count_and_its_size_does_not_grow_with_samples() {
    let fwd = forward();
    let free = fitted_parameters(&Effects::default(), NC, true);
    let run = |samples: usize, threads: usize| {
        let d = data(samples, false);
        let (ev, _) = Evaluator::new(
            &fwd,
            &d,
            Space::Log,
            Loss::L2,
            0.5,
            reference_params(NC),
            free.clone(),
        )
        .unwrap();
        let u = ev.internal(
            &ev.free
                .iter()
                .map(|&n| support::fit::random_params(104, NC).get(n))
                .collect::<Vec<_>>(),
        );
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            (
                ev.linearize_internal(&u, None, None).unwrap(),
                ev.cost_internal(&u, None).unwrap(),
            )
        })
    };
    let (one, c1) = run(1500, 1);
    let (two, c2) = run(1500, 2);
    assert_eq!(one.matrix().as_slice(), two.matrix().as_slice());
    assert_eq!(one.rhs().as_slice(), two.rhs().as_slice());
    assert_eq!(c1.to_bits(), c2.to_bits());
    // Each channel keeps one triangle of (free columns + 2) rows, however many samples there are:
    // memory is linear in channels and independent of samples.
    let width = one.matrix().ncols() + 2;
    let (small, _) = run(300, 2);
    assert!(
        one.matrix().nrows() <= NC * width,
        "{} rows",
        one.matrix().nrows()
    );
    assert_eq!(small.matrix().nrows(), one.matrix().nrows());
}

/// Extra columns reduced alongside (the `--mode exact` evidence projects with them) keep every
/// inner product: `MᵀE = Jᵀe`, `EᵀE = eᵀe`, `tᵀE = r̃ᵀe`; tolerance as for the Gram matrix.
#[test]
fn extra_columns_keep_their_inner_products_with_the_jacobian() {
    let d = data(700, true);
    let fwd = forward();
    let free = fitted_parameters(&Effects::default(), NC, true);
    let (ev, _) = Evaluator::new(
        &fwd,
        &d,
        Space::Log,
        Loss::Cauchy,
        0.5,
        reference_params(NC),
        free,
    )
    .unwrap();
    let p = support::fit::random_params(105, NC);
    let x: Vec<f64> = ev.free.iter().map(|&n| p.get(n)).collect();
    let ones = vec![1.0; x.len()];
    let scale = [0.7, 1.3, 2.0];
    let dense = ev.evaluate(&x, &ones, ScaleMode::FixedNatural(&scale), true);
    let m = dense.residual.len();
    let e1: Vec<f64> = (0..m)
        .map(|k| ((k * 37 % 101) as f64 - 50.0) / 7.0)
        .collect();
    let e2: Vec<f64> = dense.raw.iter().map(|v| v.clamp(-3.0, 3.0)).collect();
    let lin = ev
        .linearize_with(
            &x,
            &ones,
            ScaleMode::FixedNatural(&scale),
            &[&e1, &e2],
            None,
        )
        .unwrap();
    let j = DMatrix::from_row_slice(m, dense.n_cols, dense.jacobian.as_deref().unwrap());
    let mut full = DMatrix::zeros(m, dense.n_cols + 3);
    full.columns_mut(0, dense.n_cols).copy_from(&j);
    full.set_column(dense.n_cols, &DVector::from_column_slice(&dense.residual));
    full.set_column(dense.n_cols + 1, &DVector::from_column_slice(&e1));
    full.set_column(dense.n_cols + 2, &DVector::from_column_slice(&e2));
    let mut reduced = DMatrix::zeros(lin.matrix().nrows(), dense.n_cols + 3);
    reduced
        .columns_mut(0, dense.n_cols)
        .copy_from(&lin.matrix());
    reduced.set_column(dense.n_cols, &lin.rhs());
    reduced
        .columns_mut(dense.n_cols + 1, 2)
        .copy_from(&lin.extra);
    assert_gram_close(
        &full.tr_mul(&full),
        &reduced.tr_mul(&reduced),
        "[J r e1 e2]",
    );
}
