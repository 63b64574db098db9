//! What the data determine about the fitted parameters: covariance and correlation from the
//! Jacobian at the solution, and the weight of each parameter in the Jacobian's null space.

use nalgebra::{DMatrix, DVector};

use super::blocks::BlockCovariance;
use super::step::{column_norms, svd_with_projection, ScaledSvd};

/// Default relative singular-value cutoff for [`covariance`]: directions of the column-scaled
/// Jacobian with `σ < 1e-10·σ_max` have variance over 1e20 times the best-determined direction,
/// and their σ carries a relative rounding error of `eps/1e-10 ≈ 2e-6` — the data does not
/// determine them.
pub const DEFAULT_RCOND: f64 = 1e-10;

/// Fraction of a parameter's (unit) weight in `V` that may fall into discarded directions
/// before it is flagged as not determined by the data.
const UNDETERMINED_WEIGHT: f64 = 0.1;

/// Parameter covariance with a report of the directions the data does not determine.
#[derive(Debug, Clone)]
pub struct Covariance {
    /// `s² (JᵀJ)⁺`, the (pseudo-)inverse restricted to the retained directions.
    pub matrix: DMatrix<f64>,
    /// `s² = SS / dof`, the residual variance.
    pub residual_variance: f64,
    /// `σ_max/σ_min` of the column-scaled Jacobian (infinite if a σ is zero).
    pub condition_number: f64,
    /// Number of directions dropped by the cutoff.
    pub rank_deficiency: usize,
    /// Per parameter: true if at least 10% of its weight lies in dropped directions.
    pub undetermined: Vec<bool>,
}

/// Covariance `s² (JᵀJ)⁻¹` with `s² = residual_ss/dof`, via the SVD of the column-scaled
/// Jacobian with cutoff [`DEFAULT_RCOND`]. `None` if `dof == 0`, or `J` is empty or not finite.
pub fn covariance(jacobian: &DMatrix<f64>, residual_ss: f64, dof: usize) -> Option<Covariance> {
    covariance_with_rcond(jacobian, residual_ss, dof, DEFAULT_RCOND)
}

/// [`covariance`] with an explicit relative singular-value cutoff `rcond`.
pub fn covariance_with_rcond(
    jacobian: &DMatrix<f64>,
    residual_ss: f64,
    dof: usize,
    rcond: f64,
) -> Option<Covariance> {
    let (m, n) = jacobian.shape();
    if dof == 0 || n == 0 || m == 0 || !residual_ss.is_finite() {
        return None;
    }
    if jacobian.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let ScaledColumns { norms, sigma, v_t } = scale_and_factor(jacobian);
    let smax = sigma.max();
    let smin = sigma.min();
    // Thin SVD of an m×n matrix with m < n has only m singular values: the rest are zero.
    let missing = n - sigma.len();
    let condition_number = if smin > 0.0 && missing == 0 {
        smax / smin
    } else {
        f64::INFINITY
    };
    let s2 = residual_ss / dof as f64;
    let mut inner = DMatrix::zeros(n, n);
    let mut rank_deficiency = missing;
    for (k, &s) in sigma.iter().enumerate() {
        if s > rcond * smax {
            let vk = v_t.row(k).transpose();
            inner += &vk * vk.transpose() / (s * s);
        } else {
            rank_deficiency += 1;
        }
    }
    let dropped_weight = dropped_weights(&sigma, &v_t, n, rcond);
    let mut matrix = inner * s2;
    for i in 0..n {
        for j in 0..n {
            matrix[(i, j)] /= norms[i] * norms[j];
        }
    }
    Some(Covariance {
        matrix,
        residual_variance: s2,
        condition_number,
        rank_deficiency,
        undetermined: dropped_weight
            .iter()
            .map(|&w| w >= UNDETERMINED_WEIGHT)
            .collect(),
    })
}

/// Per column of `jacobian`, the weight (squared component) of its unit vector in the numerical
/// null space of the column-scaled Jacobian: directions with `σ ≤` [`DEFAULT_RCOND`]`·σ_max`, and
/// those a short Jacobian (fewer rows than columns) cannot have. All zeros for an empty or
/// non-finite Jacobian.
pub fn null_space_weights(jacobian: &DMatrix<f64>) -> Vec<f64> {
    let n = jacobian.ncols();
    if n == 0 || jacobian.nrows() == 0 || jacobian.iter().any(|v| !v.is_finite()) {
        return vec![0.0; n];
    }
    let ScaledColumns { sigma, v_t, .. } = scale_and_factor(jacobian);
    dropped_weights(&sigma, &v_t, n, DEFAULT_RCOND)
}

/// The SVD of a Jacobian whose columns are scaled to unit norm, so that a singular-value cutoff
/// does not depend on the parameters' units.
struct ScaledColumns {
    /// Column norms (1 for a zero column).
    norms: DVector<f64>,
    sigma: DVector<f64>,
    v_t: DMatrix<f64>,
}

/// Scale `jacobian`'s columns to unit norm and factor it.
fn scale_and_factor(jacobian: &DMatrix<f64>) -> ScaledColumns {
    let norms = column_norms(jacobian).map(|c| if c > 0.0 { c } else { 1.0 });
    let mut scaled = jacobian.clone();
    for (j, mut col) in scaled.column_iter_mut().enumerate() {
        col /= norms[j];
    }
    let rows = scaled.nrows();
    let ScaledSvd { sigma, v_t, .. } = svd_with_projection(scaled, &DVector::zeros(rows));
    ScaledColumns { norms, sigma, v_t }
}

/// Per parameter, the weight of its unit vector in the directions dropped by the cutoff
/// `σ ≤ rcond·σ_max`, plus (thin SVD with fewer σ than the `n` parameters) the directions the
/// SVD does not compute: 1 minus the weight in the computed rows.
fn dropped_weights(sigma: &DVector<f64>, v_t: &DMatrix<f64>, n: usize, rcond: f64) -> Vec<f64> {
    let smax = sigma.max();
    let mut weight = vec![0.0; n];
    for (k, &s) in sigma.iter().enumerate() {
        if s <= rcond * smax {
            for (j, w) in weight.iter_mut().enumerate() {
                *w += v_t[(k, j)] * v_t[(k, j)];
            }
        }
    }
    if sigma.len() < n {
        for (j, w) in weight.iter_mut().enumerate() {
            let kept: f64 = (0..sigma.len()).map(|k| v_t[(k, j)].powi(2)).sum();
            *w += (1.0 - kept).max(0.0);
        }
    }
    weight
}

/// The covariance of a linearisation as a fit reports it: dense (with its correlation matrix)
/// for a small system, by blocks ([`BlockCovariance`]) for one whose dense form would grow as
/// the square of its blocks.
#[derive(Debug, Clone)]
pub enum ParameterCovariance {
    Dense { cov: Covariance, corr: DMatrix<f64> },
    Blocks(BlockCovariance),
}

impl ParameterCovariance {
    /// From a dense covariance, with its correlation matrix.
    pub fn dense(cov: Covariance) -> ParameterCovariance {
        let corr = correlation(&cov.matrix);
        ParameterCovariance::Dense { cov, corr }
    }

    /// Variance of column `j`.
    pub fn variance(&self, j: usize) -> f64 {
        match self {
            ParameterCovariance::Dense { cov, .. } => cov.matrix[(j, j)],
            ParameterCovariance::Blocks(b) => b.entry(j, j),
        }
    }

    /// Correlation between columns `i` and `j`.
    pub fn correlation(&self, i: usize, j: usize) -> f64 {
        match self {
            ParameterCovariance::Dense { corr, .. } => corr[(i, j)],
            ParameterCovariance::Blocks(b) => b.correlation(i, j),
        }
    }

    /// Whether at least 10% of column `j`'s weight lies in dropped directions.
    pub fn undetermined(&self, j: usize) -> bool {
        match self {
            ParameterCovariance::Dense { cov, .. } => cov.undetermined[j],
            ParameterCovariance::Blocks(b) => b.undetermined[j],
        }
    }

    /// Columns worth scanning for strong correlations with `j`: all (dense), or the shared ones
    /// and `j`'s own block's (blocks, see [`BlockCovariance::neighbours`]).
    pub fn neighbours(&self, j: usize) -> Vec<usize> {
        match self {
            ParameterCovariance::Dense { cov, .. } => (0..cov.matrix.ncols()).collect(),
            ParameterCovariance::Blocks(b) => b.neighbours(j),
        }
    }
}

/// Correlation matrix `C_ij = cov_ij / √(cov_ii cov_jj)`; entries with a zero variance are 0
/// off the diagonal and 1 on it.
pub fn correlation(cov: &DMatrix<f64>) -> DMatrix<f64> {
    let n = cov.nrows();
    DMatrix::from_fn(n, n, |i, j| {
        if i == j {
            return 1.0;
        }
        let d = (cov[(i, i)] * cov[(j, j)]).sqrt();
        if d > 0.0 {
            cov[(i, j)] / d
        } else {
            0.0
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `y = a + b x` on x = 0..3: Jᵀ J = [[4, 6], [6, 14]], so (JᵀJ)⁻¹ = [[14, -6], [-6, 4]]/20.
    fn line_jacobian() -> DMatrix<f64> {
        DMatrix::from_row_slice(4, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0, 1.0, 3.0])
    }

    #[test]
    fn covariance_of_a_straight_line_matches_the_closed_form() {
        let ss = 0.7;
        let cov = covariance(&line_jacobian(), ss, 2).expect("full rank, dof > 0");
        let s2 = ss / 2.0;
        let expected = DMatrix::from_row_slice(2, 2, &[14.0, -6.0, -6.0, 4.0]) * (s2 / 20.0);
        // A 4×2 SVD with condition ~5 is accurate to a few ulps; 1e-13 leaves margin.
        assert!((&cov.matrix - &expected).abs().max() < 1e-13 * expected.abs().max());
        assert_eq!(cov.rank_deficiency, 0);
        assert_eq!(cov.undetermined, vec![false, false]);
        assert!(cov.condition_number.is_finite() && cov.condition_number > 1.0);
        let corr = correlation(&cov.matrix);
        let r = -6.0 / (14.0f64 * 4.0).sqrt();
        assert!((corr[(0, 1)] - r).abs() < 1e-13);
        assert!((corr[(1, 0)] - r).abs() < 1e-13);
        assert_eq!(corr[(0, 0)], 1.0);
    }

    #[test]
    fn covariance_flags_parameters_the_data_cannot_separate() {
        // Third column is twice the second: only b1 + 2 b2 is determined.
        let j = DMatrix::from_row_slice(
            4,
            3,
            &[1.0, 0.0, 0.0, 1.0, 1.0, 2.0, 1.0, 2.0, 4.0, 1.0, 3.0, 6.0],
        );
        let cov = covariance(&j, 1.0, 1).expect("dof > 0");
        assert_eq!(cov.rank_deficiency, 1);
        assert_eq!(cov.undetermined, vec![false, true, true]);
        assert!(cov.condition_number > 1e10);
        assert!(cov.matrix.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn null_space_weights_name_the_dependent_columns() {
        // Columns 2 and 3 are equal: the null direction is (0, 1, -1)/√2, half of each one's
        // weight. Rounding of a 4×3 SVD is ~1e-16, so 1e-12 is ample.
        let j = DMatrix::from_row_slice(
            4,
            3,
            &[1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 1.0, 3.0, 3.0],
        );
        let w = null_space_weights(&j);
        assert!(w[0].abs() < 1e-12 && (w[1] - 0.5).abs() < 1e-12 && (w[2] - 0.5).abs() < 1e-12);
        assert_eq!(null_space_weights(&line_jacobian()), vec![0.0, 0.0]);
        // One row, two columns: one direction is missing from the thin SVD.
        let short = null_space_weights(&DMatrix::from_row_slice(1, 2, &[1.0, 1.0]));
        assert!((short[0] - 0.5).abs() < 1e-12 && (short[1] - 0.5).abs() < 1e-12);
    }

    #[test]
    fn covariance_is_independent_of_parameter_units() {
        // Rescaling a parameter by 1e6 rescales its column; the scaled SVD must not drop it.
        let mut j = line_jacobian();
        j.column_mut(1).scale_mut(1e-6);
        let cov = covariance(&j, 0.7, 2).expect("full rank");
        assert_eq!(cov.rank_deficiency, 0);
        let base = covariance(&line_jacobian(), 0.7, 2).expect("full rank");
        // Var(b') = 1e12 Var(b) exactly in exact arithmetic; rounding is a few ulps.
        assert!((cov.matrix[(1, 1)] / base.matrix[(1, 1)] / 1e12 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn covariance_needs_degrees_of_freedom() {
        assert!(covariance(&line_jacobian(), 1.0, 0).is_none());
        assert!(covariance(&DMatrix::zeros(0, 0), 1.0, 1).is_none());
    }
}
