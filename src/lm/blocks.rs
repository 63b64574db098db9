//! Block-structured linearisations and their block elimination. Many columns belong to one block
//! of rows only (a channel's own `σ_a` and scale); a few are shared by every block. The damped
//! LM system and the covariance are solved by eliminating each block's own columns with a small
//! Householder QR of that block (a Schur complement onto the shared columns that never forms the
//! normal matrix, so the conditioning is not squared), then one QR of the shared rows: time and
//! memory `O(blocks · shared²)` instead of `O(blocks²)`.
//!
//! Determinism: blocks are factored in parallel but each independently, and merged in block
//! order, so results do not depend on the thread count.

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Rows of one block: `[shared columns | its own columns]` and their residuals.
#[derive(Debug, Clone)]
pub struct Block {
    /// Solver indices of the block's own columns (in the order of its matrix's last columns).
    pub local: Vec<usize>,
    /// `rows × (shared + local)`.
    pub matrix: DMatrix<f64>,
    /// Residuals (or their reduced form `t`) of the block's rows.
    pub rhs: DVector<f64>,
}

/// A linearisation `(M, t)` stored by blocks: `M`'s rows are the blocks' rows, each zero outside
/// the shared columns and the block's own ones.
#[derive(Debug, Clone)]
pub struct BlockSystem {
    /// Number of solver columns.
    pub ncols: usize,
    /// Solver indices of the shared columns (in the order of every block's first columns).
    pub shared: Vec<usize>,
    pub blocks: Vec<Block>,
}

/// Blocks merged per round when stacking shared rows: bounds the rows held before a QR.
const MERGE: usize = 64;

impl BlockSystem {
    /// Number of rows of `M`.
    pub fn nrows(&self) -> usize {
        self.blocks.iter().map(|b| b.matrix.nrows()).sum()
    }

    /// Whether every entry of `M` and `t` is finite.
    pub fn all_finite(&self) -> bool {
        self.blocks
            .iter()
            .all(|b| b.matrix.iter().all(|v| v.is_finite()) && b.rhs.iter().all(|v| v.is_finite()))
    }

    /// Solver index of column `k` of block `b`'s matrix.
    fn index(&self, b: &Block, k: usize) -> usize {
        let s = self.shared.len();
        if k < s {
            self.shared[k]
        } else {
            b.local[k - s]
        }
    }

    /// Euclidean norm of each column of `M`.
    pub fn column_norms(&self) -> DVector<f64> {
        let mut sq = vec![0.0; self.ncols];
        for b in &self.blocks {
            for (k, col) in b.matrix.column_iter().enumerate() {
                sq[self.index(b, k)] += col.norm_squared();
            }
        }
        DVector::from_iterator(self.ncols, sq.into_iter().map(f64::sqrt))
    }

    /// `Mᵀt`.
    pub fn gradient(&self) -> DVector<f64> {
        let mut g = DVector::zeros(self.ncols);
        for b in &self.blocks {
            for (k, col) in b.matrix.column_iter().enumerate() {
                g[self.index(b, k)] += col.dot(&b.rhs);
            }
        }
        g
    }

    /// `‖M z‖²`.
    pub fn apply_norm2(&self, z: &DVector<f64>) -> f64 {
        self.blocks
            .iter()
            .map(|b| {
                let zb = DVector::from_iterator(
                    b.matrix.ncols(),
                    (0..b.matrix.ncols()).map(|k| z[self.index(b, k)]),
                );
                (&b.matrix * zb).norm_squared()
            })
            .sum()
    }

    /// The same system with column `j` divided by `d[j]`.
    pub fn scale_columns(&self, d: &DVector<f64>) -> BlockSystem {
        let blocks = self
            .blocks
            .iter()
            .map(|b| {
                let mut m = b.matrix.clone();
                for (k, mut col) in m.column_iter_mut().enumerate() {
                    col /= d[self.index(b, k)];
                }
                Block {
                    local: b.local.clone(),
                    matrix: m,
                    rhs: b.rhs.clone(),
                }
            })
            .collect();
        BlockSystem {
            ncols: self.ncols,
            shared: self.shared.clone(),
            blocks,
        }
    }

    /// Dense `(M, t)`, rows in block order (for small systems and tests).
    pub fn to_dense(&self) -> (DMatrix<f64>, DVector<f64>) {
        let n = self.nrows();
        let mut m = DMatrix::zeros(n, self.ncols);
        let mut t = DVector::zeros(n);
        let mut row = 0;
        for b in &self.blocks {
            for i in 0..b.matrix.nrows() {
                for k in 0..b.matrix.ncols() {
                    m[(row, self.index(b, k))] = b.matrix[(i, k)];
                }
                t[row] = b.rhs[i];
                row += 1;
            }
        }
        (m, t)
    }
}

/// One block's rows of the triangle of `[M; √λ I]`, own columns first: `[P | B | β]`.
#[derive(Debug, Clone)]
struct Pivot {
    /// `L × L` upper triangle on the block's own columns.
    p: DMatrix<f64>,
    /// `L × shared`.
    b: DMatrix<f64>,
    /// `L` transformed residuals.
    beta: DVector<f64>,
}

/// The triangle of `[M; √λ I]` with every block's own columns ordered first:
/// `R = [[P, B], [0, R_s]]`, `P` block diagonal, and `[β; β_s] = Qᵀ[t; 0]`.
#[derive(Debug, Clone)]
struct Factor {
    pivots: Vec<Pivot>,
    /// `shared × shared` upper triangle of the Schur complement.
    rs: DMatrix<f64>,
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
    fn of(sys: &BlockSystem, lambda: f64) -> Factor {
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
    fn solve(&self, sys: &BlockSystem) -> DVector<f64> {
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
    fn slope(&self, sys: &BlockSystem, z: &DVector<f64>) -> f64 {
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
pub(super) fn block_trust_region_step(
    scaled: &BlockSystem,
    delta: f64,
    lambda_guess: f64,
    rows: usize,
) -> super::step::TrialStep {
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
    let (lambda, z) = super::step::secular_search(delta, lambda_guess, sg, |lambda| {
        let f = Factor::of(scaled, lambda.max(floor));
        let z = f.solve(scaled);
        let slope_at = z.clone();
        (z, move || f.slope(scaled, &slope_at))
    });
    super::step::TrialStep {
        jp2: scaled.apply_norm2(&z),
        z,
        lambda,
    }
}

/// Where a solver column sits in a block system.
#[derive(Debug, Clone, Copy)]
enum Place {
    Shared(usize),
    Local(usize, usize),
}

/// One block's part of the covariance (column-scaled): `G = P⁺B` and `H = G C_ss`.
#[derive(Debug, Clone)]
struct BlockPart {
    /// `P⁺P⁺ᵀ`, `L × L`.
    own: DMatrix<f64>,
    g: DMatrix<f64>,
    h: DMatrix<f64>,
}

/// Parameter covariance of a block system, stored by blocks: the shared block and per block its
/// coupling to the shared columns, so memory is `O(blocks · shared²)`; any entry (including
/// between two blocks' own columns) is computed on demand in `O(shared)`.
#[derive(Debug, Clone)]
pub struct BlockCovariance {
    /// `s² = SS / dof`.
    pub residual_variance: f64,
    /// Estimate of `σ_max/σ_min` of the column-scaled `M` from the block triangles (a lower
    /// bound of the dense condition number; infinite if a pivot is zero).
    pub condition_number: f64,
    /// Number of directions dropped by the cutoff.
    pub rank_deficiency: usize,
    /// Per column: weight of its unit vector in the dropped directions (null space).
    pub null_weights: Vec<f64>,
    /// Per column: at least 10% of its weight lies in dropped directions.
    pub undetermined: Vec<bool>,
    places: Vec<Place>,
    /// Shared columns, and each block's own ones (solver indices).
    shared: Vec<usize>,
    locals: Vec<Vec<usize>>,
    norms: DVector<f64>,
    /// Shared block `(R_sᵀR_s)⁺` (column-scaled).
    c_ss: DMatrix<f64>,
    parts: Vec<BlockPart>,
}

/// Pseudo-inverse of a small square matrix with singular values below `cut` dropped, and the
/// dropped right singular vectors (rows).
fn pinv(a: &DMatrix<f64>, cut: f64) -> (DMatrix<f64>, Vec<DVector<f64>>) {
    let n = a.ncols();
    if n == 0 {
        return (DMatrix::zeros(0, 0), Vec::new());
    }
    let svd = a.clone().svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        unreachable!("SVD was asked for U and Vᵀ")
    };
    let mut inv = DMatrix::zeros(n, n);
    let mut dropped = Vec::new();
    for (k, &s) in svd.singular_values.iter().enumerate() {
        let v = v_t.row(k).transpose();
        if s > cut {
            inv += &v * u.column(k).transpose() / s;
        } else {
            dropped.push(v);
        }
    }
    (inv, dropped)
}

/// Largest and smallest singular value of a small square matrix.
fn sv_range(a: &DMatrix<f64>) -> (f64, f64) {
    if a.ncols() == 0 {
        return (0.0, f64::INFINITY);
    }
    let s = a.clone().singular_values();
    (s.max(), s.min())
}

/// Covariance `s²(MᵀM)⁺` of a block system with `s² = residual_ss/dof`, columns scaled to unit
/// norm and directions with `σ ≤ rcond·σ_max` dropped (as [`super::covariance_with_rcond`]).
/// `None` if `dof == 0`, the system is empty or not finite.
pub fn block_covariance(
    sys: &BlockSystem,
    residual_ss: f64,
    dof: usize,
    rcond: f64,
) -> Option<BlockCovariance> {
    let n = sys.ncols;
    if dof == 0 || n == 0 || sys.nrows() == 0 || !residual_ss.is_finite() || !sys.all_finite() {
        return None;
    }
    let norms = sys.column_norms().map(|c| if c > 0.0 { c } else { 1.0 });
    let scaled = sys.scale_columns(&norms);
    let f = Factor::of(&scaled, 0.0);
    let (mut smax, mut smin) = sv_range(&f.rs);
    for pv in &f.pivots {
        let mut whole = DMatrix::zeros(pv.p.nrows(), pv.p.ncols() + pv.b.ncols());
        whole.columns_mut(0, pv.p.ncols()).copy_from(&pv.p);
        whole
            .columns_mut(pv.p.ncols(), pv.b.ncols())
            .copy_from(&pv.b);
        if whole.nrows() > 0 {
            smax = smax.max(whole.singular_values().max());
            smin = smin.min(sv_range(&pv.p).1);
        }
    }
    let cut = rcond * smax;
    let (rs_inv, rs_null) = pinv(&f.rs, cut);
    let c_ss = &rs_inv * rs_inv.transpose();
    let mut rank_deficiency = rs_null.len();
    let mut weights = vec![0.0; n];
    let mut parts = Vec::with_capacity(f.pivots.len());
    for (pv, b) in f.pivots.iter().zip(&scaled.blocks) {
        let (p_inv, p_null) = pinv(&pv.p, cut);
        rank_deficiency += p_null.len();
        for v in &p_null {
            for (q, &j) in b.local.iter().enumerate() {
                weights[j] += v[q] * v[q];
            }
        }
        let g = &p_inv * &pv.b;
        let h = &g * &c_ss;
        parts.push(BlockPart {
            own: &p_inv * p_inv.transpose(),
            g,
            h,
        });
    }
    // A dropped shared direction v extends to the blocks' own columns as −G v (exact null
    // vector of R when the pivots are regular).
    for v in &rs_null {
        let ext: Vec<DVector<f64>> = parts.iter().map(|p| -(&p.g * v)).collect();
        let norm2 = v.norm_squared() + ext.iter().map(|e| e.norm_squared()).sum::<f64>();
        for (k, &j) in scaled.shared.iter().enumerate() {
            weights[j] += v[k] * v[k] / norm2;
        }
        for (e, b) in ext.iter().zip(&scaled.blocks) {
            for (q, &j) in b.local.iter().enumerate() {
                weights[j] += e[q] * e[q] / norm2;
            }
        }
    }
    let mut places = vec![Place::Shared(0); n];
    for (k, &j) in sys.shared.iter().enumerate() {
        places[j] = Place::Shared(k);
    }
    for (bi, b) in sys.blocks.iter().enumerate() {
        for (q, &j) in b.local.iter().enumerate() {
            places[j] = Place::Local(bi, q);
        }
    }
    Some(BlockCovariance {
        residual_variance: residual_ss / dof as f64,
        condition_number: if smin > 0.0 && rank_deficiency == 0 {
            smax / smin
        } else {
            f64::INFINITY
        },
        rank_deficiency,
        undetermined: weights.iter().map(|&w| w >= 0.1).collect(),
        null_weights: weights,
        places,
        shared: sys.shared.clone(),
        locals: sys.blocks.iter().map(|b| b.local.clone()).collect(),
        norms,
        c_ss,
        parts,
    })
}

impl BlockCovariance {
    /// Number of columns.
    pub fn len(&self) -> usize {
        self.places.len()
    }

    /// True for a system without columns.
    pub fn is_empty(&self) -> bool {
        self.places.is_empty()
    }

    /// Covariance entry `(i, j)` in the system's units.
    pub fn entry(&self, i: usize, j: usize) -> f64 {
        let scaled = match (self.places[i], self.places[j]) {
            (Place::Shared(a), Place::Shared(b)) => self.c_ss[(a, b)],
            (Place::Local(bl, q), Place::Shared(k)) | (Place::Shared(k), Place::Local(bl, q)) => {
                -self.parts[bl].h[(q, k)]
            }
            (Place::Local(b1, q1), Place::Local(b2, q2)) => {
                let cross = self.parts[b1].h.row(q1).dot(&self.parts[b2].g.row(q2));
                if b1 == b2 {
                    self.parts[b1].own[(q1, q2)] + cross
                } else {
                    cross
                }
            }
        };
        scaled * self.residual_variance / (self.norms[i] * self.norms[j])
    }

    /// The columns that share a block with column `j`: the shared ones and, for a block's own
    /// column, that block's (the correlations a caller can scan without `O(columns²)` work).
    pub fn neighbours(&self, j: usize) -> Vec<usize> {
        let mut out = self.shared.clone();
        if let Place::Local(b, _) = self.places[j] {
            out.extend(&self.locals[b]);
        }
        out
    }

    /// Correlation `(i, j)`: 1 on the diagonal, 0 where a variance is zero.
    pub fn correlation(&self, i: usize, j: usize) -> f64 {
        if i == j {
            return 1.0;
        }
        let d = (self.entry(i, i) * self.entry(j, j)).sqrt();
        if d > 0.0 {
            self.entry(i, j) / d
        } else {
            0.0
        }
    }
}

/// The part of `e` (one value per row of `M`, rows in block order) orthogonal to `M`'s columns:
/// `e − M z` with `z` the least-squares fit of `e`, directions with `σ < rcond·σ_max` of the
/// column-scaled `M` damped out (Tikhonov at `(rcond·σ_max)²` instead of a truncated SVD).
pub fn orthogonal_part(sys: &BlockSystem, e: &DVector<f64>, rcond: f64) -> DVector<f64> {
    let norms = sys.column_norms().map(|c| if c > 0.0 { c } else { 1.0 });
    let mut scaled = sys.scale_columns(&norms);
    let mut row = 0;
    for b in &mut scaled.blocks {
        let k = b.rhs.len();
        b.rhs = -e.rows(row, k).into_owned();
        row += k;
    }
    // Unit columns: σ_max is between 1 and √ncols.
    let z = Factor::of(&scaled, rcond * rcond).solve(&scaled);
    let mut out = e.clone();
    let mut row = 0;
    for b in &scaled.blocks {
        let zb = DVector::from_iterator(
            b.matrix.ncols(),
            (0..b.matrix.ncols()).map(|k| z[scaled.index(b, k)]),
        );
        let fit = &b.matrix * zb;
        for i in 0..fit.len() {
            out[row + i] -= fit[i];
        }
        row += fit.len();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two shared columns, `nb` blocks with one or two own columns each, pseudo-random entries.
    fn system(nb: usize, seed: u64) -> BlockSystem {
        let mut state = seed;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let s = 2;
        let mut col = s;
        let blocks = (0..nb)
            .map(|b| {
                let l = 1 + b % 2;
                let local: Vec<usize> = (col..col + l).collect();
                col += l;
                let rows = 3 + b % 3;
                Block {
                    local,
                    matrix: DMatrix::from_fn(rows, s + l, |_, _| next()),
                    rhs: DVector::from_fn(rows, |_, _| next()),
                }
            })
            .collect();
        BlockSystem {
            ncols: col,
            shared: vec![0, 1],
            blocks,
        }
    }

    #[test]
    fn damped_solve_matches_the_dense_normal_equations() {
        let sys = system(7, 3);
        let (m, t) = sys.to_dense();
        for lambda in [0.0, 1e-3, 0.5, 10.0] {
            let f = Factor::of(&sys, lambda);
            let z = f.solve(&sys);
            let h = m.tr_mul(&m) + DMatrix::identity(sys.ncols, sys.ncols) * lambda;
            let expect = -h.clone().lu().solve(&m.tr_mul(&t)).unwrap();
            // A well-conditioned 12-column system: both solves are accurate to ~1e-14.
            assert!(
                (&z - &expect).norm() < 1e-10 * expect.norm(),
                "λ = {lambda}"
            );
            let slope = expect.dot(&h.lu().solve(&expect).unwrap());
            assert!((f.slope(&sys, &z) / slope - 1.0).abs() < 1e-10);
        }
        assert!(
            (sys.apply_norm2(&DVector::repeat(sys.ncols, 1.0))
                - (&m * DVector::repeat(sys.ncols, 1.0)).norm_squared())
            .abs()
                < 1e-12
        );
    }

    #[test]
    fn undamped_step_predicts_the_dense_gauss_newton_decrease() {
        let sys = system(7, 5);
        let (m, t) = sys.to_dense();
        let rows = m.nrows();
        // Dense Gauss–Newton: ‖M p‖² with M p the projection of −t onto M's column space.
        let p = m.clone().svd(true, true).solve(&t, 1e-14).unwrap();
        let dense = (&m * p).norm_squared();
        let step = block_trust_region_step(&sys, f64::INFINITY, 0.0, rows);
        assert_eq!(step.lambda, 0.0);
        // A well-conditioned random system: agreement to rounding of its ~20 columns.
        assert!(
            (step.jp2 - dense).abs() <= 1e-12 * dense,
            "{} vs {dense}",
            step.jp2
        );
    }

    #[test]
    fn block_covariance_matches_the_dense_covariance() {
        let sys = system(9, 11);
        let (m, _) = sys.to_dense();
        let dense = super::super::covariance(&m, 2.0, 5).unwrap();
        let block = block_covariance(&sys, 2.0, 5, super::super::DEFAULT_RCOND).unwrap();
        let scale = dense.matrix.abs().max();
        for i in 0..sys.ncols {
            for j in 0..sys.ncols {
                // Condition ~10 and 15 columns: both agree to ~1e-14 relative to the largest.
                assert!((block.entry(i, j) - dense.matrix[(i, j)]).abs() < 1e-10 * scale);
            }
        }
        assert_eq!(block.rank_deficiency, 0);
        assert!(block.undetermined.iter().all(|u| !u));
    }

    #[test]
    fn orthogonal_part_is_orthogonal_to_every_column() {
        let sys = system(6, 8);
        let (m, _) = sys.to_dense();
        let e = DVector::from_fn(m.nrows(), |i, _| (i as f64).sin());
        let perp = orthogonal_part(&sys, &e, 1e-10);
        // Well conditioned: MᵀM z = Mᵀe holds to rounding (the 1e-20 damping is negligible).
        assert!(m.tr_mul(&perp).norm() < 1e-10 * e.norm());
        assert!(perp.norm() > 0.1 * e.norm());
    }

    #[test]
    fn block_covariance_flags_a_shared_column_copied_into_a_block() {
        let mut sys = system(4, 5);
        // Block 0's own column equals shared column 1: only their sum is determined, and a
        // dropped shared direction carries both.
        let b = &mut sys.blocks[0];
        let s1 = b.matrix.column(1).into_owned();
        b.matrix.set_column(2, &s1);
        for other in sys.blocks.iter_mut().skip(1) {
            other.matrix.column_mut(1).fill(0.0);
        }
        let cov = block_covariance(&sys, 1.0, 3, super::super::DEFAULT_RCOND).unwrap();
        assert!(cov.rank_deficiency >= 1);
        assert!(
            cov.undetermined[1] && cov.undetermined[2],
            "{:?}",
            cov.null_weights
        );
        assert!(!cov.undetermined[0]);
    }
}
