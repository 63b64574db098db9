//! The covariance of a block system's solution ([`BlockCovariance`]) from the block factors,
//! and the part of a vector outside the system's column space.

use nalgebra::{DMatrix, DVector};

use super::factor::Factor;
use super::system::BlockSystem;

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
