//! The block elimination: each block's own columns by a small Householder QR, then the Schur
//! complement onto the shared columns ([`Factor`]), its solves, and the damped LM step on it.

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

use super::system::{BlockSystem, MERGE};

/// One block's rows of the triangle of `[M; √λ I]`, own columns first: `[P | B | β]`.
#[derive(Debug, Clone)]
pub(super) struct Pivot {
    /// `L × L` upper triangle on the block's own columns.
    pub(super) p: DMatrix<f64>,
    /// `L × shared`.
    pub(super) b: DMatrix<f64>,
    /// `L` transformed residuals.
    beta: DVector<f64>,
}

/// The triangle of `[M; √λ I]` with every block's own columns ordered first:
/// `R = [[P, B], [0, R_s]]`, `P` block diagonal, and `[β; β_s] = Qᵀ[t; 0]`.
#[derive(Debug, Clone)]
pub(super) struct Factor {
    pub(super) pivots: Vec<Pivot>,
    /// `shared × shared` upper triangle of the Schur complement.
    pub(super) rs: DMatrix<f64>,
    beta_s: DVector<f64>,
}

/// The R factor of `a` (Householder QR), padded with zero rows to at least `ncols - 1` rows (the
/// last column is a right-hand side).
fn triangle(a: DMatrix<f64>, min_rows: usize) -> DMatrix<f64> {
    let w = a.ncols();
    let r = if a.nrows() == 0 { a } else { a.qr().r() };
    if r.nrows() >= min_rows {
        return r;
    }
    let mut padded = DMatrix::zeros(min_rows, w);
    padded.rows_mut(0, r.nrows()).copy_from(&r);
    padded
}

/// Stack `parts` under `top` and reduce to a triangle.
fn stack(top: DMatrix<f64>, parts: &[DMatrix<f64>], min_rows: usize) -> DMatrix<f64> {
    let w = top.ncols();
    let n: usize = top.nrows() + parts.iter().map(|p| p.nrows()).sum::<usize>();
    let mut s = DMatrix::zeros(n, w);
    s.rows_mut(0, top.nrows()).copy_from(&top);
    let mut row = top.nrows();
    for p in parts {
        s.rows_mut(row, p.nrows()).copy_from(p);
        row += p.nrows();
    }
    triangle(s, min_rows)
}

impl Factor {
    /// Factor `[M; √λ I]` of a (column-scaled) system.
    pub(super) fn of(sys: &BlockSystem, lambda: f64) -> Factor {
        let s = sys.shared.len();
        let sl = lambda.sqrt();
        let parts: Vec<(Pivot, DMatrix<f64>)> = sys
            .blocks
            .par_iter()
            .map(|b| {
                let l = b.local.len();
                let k = b.matrix.nrows();
                let mut a = DMatrix::zeros(k + l, l + s + 1);
                a.view_mut((0, 0), (k, l))
                    .copy_from(&b.matrix.columns(s, l));
                a.view_mut((0, l), (k, s))
                    .copy_from(&b.matrix.columns(0, s));
                a.view_mut((0, l + s), (k, 1)).copy_from(&b.rhs);
                for q in 0..l {
                    a[(k + q, q)] = sl;
                }
                let r = triangle(a, l + s + 1);
                let pivot = Pivot {
                    p: r.view((0, 0), (l, l)).into_owned(),
                    b: r.view((0, l), (l, s)).into_owned(),
                    beta: r.view((0, l + s), (l, 1)).column(0).into_owned(),
                };
                let rest = r.view((l, l), (r.nrows() - l, s + 1)).into_owned();
                (pivot, rest)
            })
            .collect();
        let mut acc = DMatrix::zeros(0, s + 1);
        let mut pivots = Vec::with_capacity(parts.len());
        let mut pending = Vec::with_capacity(MERGE);
        for (pivot, rest) in parts {
            pivots.push(pivot);
            pending.push(rest);
            if pending.len() == MERGE {
                acc = stack(acc, &pending, 0);
                pending.clear();
            }
        }
        let mut damping = DMatrix::zeros(s, s + 1);
        for q in 0..s {
            damping[(q, q)] = sl;
        }
        pending.push(damping);
        let r = stack(acc, &pending, s + 1);
        Factor {
            pivots,
            rs: r.view((0, 0), (s, s)).into_owned(),
            beta_s: r.view((0, s), (s, 1)).column(0).into_owned(),
        }
    }

    /// The minimiser `z` of `‖M z + t‖² + λ‖z‖²`: `R z = −β` by back substitution, shared first.
    pub(super) fn solve(&self, sys: &BlockSystem) -> DVector<f64> {
        let mut z = DVector::zeros(sys.ncols);
        let zs = solve_upper(&self.rs, &(-&self.beta_s));
        for (k, &j) in sys.shared.iter().enumerate() {
            z[j] = zs[k];
        }
        for (pv, b) in self.pivots.iter().zip(&sys.blocks) {
            let rhs = -(&pv.beta + &pv.b * &zs);
            let zl = solve_upper(&pv.p, &rhs);
            for (q, &j) in b.local.iter().enumerate() {
                z[j] = zl[q];
            }
        }
        z
    }

    /// `zᵀ(MᵀM + λI)⁻¹z = ‖R⁻ᵀz‖²`, the slope of Moré's secular equation.
    pub(super) fn slope(&self, sys: &BlockSystem, z: &DVector<f64>) -> f64 {
        let s = sys.shared.len();
        let mut rhs_s = DVector::from_iterator(s, sys.shared.iter().map(|&j| z[j]));
        let mut total = 0.0;
        for (pv, b) in self.pivots.iter().zip(&sys.blocks) {
            let zl = DVector::from_iterator(b.local.len(), b.local.iter().map(|&j| z[j]));
            let q = solve_lower_transposed(&pv.p, &zl);
            total += q.norm_squared();
            rhs_s -= pv.b.tr_mul(&q);
        }
        total + solve_lower_transposed(&self.rs, &rhs_s).norm_squared()
    }
}

/// `x` with `R x = b` for upper-triangular `R`; components with a zero pivot are 0.
fn solve_upper(r: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    let n = r.nrows();
    let mut x = DVector::zeros(n);
    for i in (0..n).rev() {
        let mut v = b[i];
        for k in i + 1..n {
            v -= r[(i, k)] * x[k];
        }
        x[i] = if r[(i, i)] != 0.0 { v / r[(i, i)] } else { 0.0 };
    }
    x
}

/// `x` with `Rᵀ x = b` for upper-triangular `R`; components with a zero pivot are 0.
fn solve_lower_transposed(r: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    let n = r.nrows();
    let mut x = DVector::zeros(n);
    for i in 0..n {
        let mut v = b[i];
        for k in 0..i {
            v -= r[(k, i)] * x[k];
        }
        x[i] = if r[(i, i)] != 0.0 { v / r[(i, i)] } else { 0.0 };
    }
    x
}

/// A trial step of a block system in scaled coordinates (see `step::TrialStep`).
pub(in crate::lm) fn block_trust_region_step(
    scaled: &BlockSystem,
    delta: f64,
    lambda_guess: f64,
    rows: usize,
) -> crate::lm::step::TrialStep {
    // The Gauss–Newton step is taken at a damping floor of (rounding level)² instead of the dense
    // path's truncated SVD: directions with σ below it are damped rather than dropped, and
    // such a step is too long for the trust radius anyway, so λ > 0 takes over.
    let fro = scaled
        .blocks
        .iter()
        .map(|b| b.matrix.norm_squared())
        .sum::<f64>()
        .sqrt();
    let cutoff = fro * f64::EPSILON * rows.max(scaled.ncols) as f64;
    let floor = cutoff * cutoff;
    let sg = scaled.gradient().norm();
    let (lambda, z) = crate::lm::step::secular_search(delta, lambda_guess, sg, |lambda| {
        let f = Factor::of(scaled, lambda.max(floor));
        let z = f.solve(scaled);
        let slope_at = z.clone();
        (z, move || f.slope(scaled, &slope_at))
    });
    crate::lm::step::TrialStep {
        jp2: scaled.apply_norm2(&z),
        z,
        lambda,
    }
}
