//! The trust-region step of Levenberg–Marquardt: the SVD of the scaled Jacobian and Moré's
//! secular equation for the damping `λ` that fits the step to the trust radius.

use nalgebra::{DMatrix, DVector};

/// SVD of the scaled Jacobian `J D⁻¹ = U Σ Vᵀ`, with `g = Uᵀ r`, kept until the next Jacobian.
#[derive(Debug, Clone)]
pub(super) struct ScaledSvd {
    pub(super) sigma: DVector<f64>,
    pub(super) v_t: DMatrix<f64>,
    pub(super) g: DVector<f64>,
}

/// A trial step in scaled coordinates `z = D p`, with what the ratio test needs.
#[derive(Debug, Clone)]
pub(super) struct TrialStep {
    /// Scaled step `z = D p`.
    pub(super) z: DVector<f64>,
    /// Damping `λ` that produced it.
    pub(super) lambda: f64,
    /// `‖J p‖²`.
    pub(super) jp2: f64,
}

/// SVD `A = U Σ Vᵀ` with `g = Uᵀ r`. For tall `A` (m > n) it first reduces `A = Q R` by
/// Householder QR and factors the n×n `R`: same backward stability, and ~10× faster than a
/// direct SVD when m ≫ n because `U` is never formed at m×n.
pub(super) fn svd_with_projection(a: DMatrix<f64>, r: &DVector<f64>) -> ScaledSvd {
    let (m, n) = a.shape();
    let (small, rhs) = if m > n {
        let qr = a.qr();
        let mut qtr = r.clone();
        qr.q_tr_mul(&mut qtr);
        (qr.unpack_r(), qtr.rows(0, n).into_owned())
    } else {
        (a, r.clone())
    };
    let svd = small.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        unreachable!("SVD was asked for U and Vᵀ")
    };
    ScaledSvd {
        sigma: svd.singular_values,
        v_t,
        g: u.tr_mul(&rhs),
    }
}

/// Euclidean norm of each column of `a`.
pub(super) fn column_norms(a: &DMatrix<f64>) -> DVector<f64> {
    DVector::from_iterator(a.ncols(), a.column_iter().map(|c| c.norm()))
}

/// Norm of the scaled gradient `‖D⁻¹ Jᵀ r‖` from the gradient `Jᵀr`.
pub(super) fn scaled_gradient(gradient: &DVector<f64>, diag: &DVector<f64>) -> f64 {
    gradient.component_div(diag).norm()
}

/// [`gradient_cosine`] from the gradient `Jᵀr` (for a block linearisation).
pub(super) fn gradient_cosine_of(
    gradient: &DVector<f64>,
    col_norms: &DVector<f64>,
    rn: f64,
) -> f64 {
    gradient
        .iter()
        .zip(col_norms.iter())
        .filter(|(_, &c)| c > 0.0)
        .map(|(g, &c)| (g / (c * rn)).abs())
        .fold(0.0, f64::max)
}

/// MINPACK's gradient test: `max_j |J_jᵀ r| / (‖J_j‖ ‖r‖)`, the largest cosine between the
/// residual vector and a Jacobian column.
/// `rn` is `‖r‖` (a reduced linearisation's `t` may be shorter than `r`, never longer).
pub(super) fn gradient_cosine(
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    col_norms: &DVector<f64>,
    rn: f64,
) -> f64 {
    j.column_iter()
        .zip(col_norms.iter())
        .filter(|(_, &c)| c > 0.0)
        .map(|(col, &c)| (col.dot(r) / (c * rn)).abs())
        .fold(0.0, f64::max)
}

/// Relative singular-value cutoff below which a direction counts as rank-deficient in the
/// Gauss–Newton step: rounding in the SVD perturbs each σ by about `eps·σ_max·max(m,n)`.
pub(super) fn gauss_newton_cutoff(svd: &ScaledSvd, rows: usize) -> f64 {
    let smax = svd.sigma.max();
    smax * f64::EPSILON * rows.max(svd.sigma.len()) as f64
}

/// The damped scaled step `w = -(Σ² + λ)⁻¹ Σ g` in the SVD basis (Moré 1978, eq. 3.3).
pub(super) fn damped_coefficients(svd: &ScaledSvd, lambda: f64, cutoff: f64) -> DVector<f64> {
    svd.sigma.zip_map(&svd.g, |s, g| {
        if lambda == 0.0 && s <= cutoff {
            0.0
        } else {
            -s * g / (s * s + lambda)
        }
    })
}

/// `Σ σ²g²/(σ²+λ)³ = -½ d‖z‖²/dλ`, the slope the secular-equation Newton step needs.
pub(super) fn secular_slope(svd: &ScaledSvd, lambda: f64) -> f64 {
    svd.sigma
        .zip_map(&svd.g, |s, g| {
            let d = s * s + lambda;
            s * s * g * g / (d * d * d)
        })
        .sum()
}

/// Moré's secular equation `‖z(λ)‖ = Δ` to within 10% by safeguarded Newton on `1/‖z‖`, for
/// any factorisation: `at(λ)` gives the scaled step `z(λ)` and a closure for `-½ d‖z‖²/dλ`;
/// `sg` is `‖Jᵀr‖` scaled (`λ ≤ sg/Δ` brackets the root). `(0, z(0))` when the Gauss–Newton
/// step already fits.
pub(super) fn secular_search<S: FnOnce() -> f64>(
    delta: f64,
    lambda_guess: f64,
    sg: f64,
    mut at: impl FnMut(f64) -> (DVector<f64>, S),
) -> (f64, DVector<f64>) {
    let (mut z, _) = at(0.0);
    let mut lambda = 0.0;
    if z.norm() > 1.1 * delta {
        let (mut lo, mut hi) = (0.0, sg / delta);
        lambda = if lambda_guess > lo && lambda_guess < hi {
            lambda_guess
        } else {
            1e-3 * hi
        };
        for _ in 0..60 {
            let (zl, slope) = at(lambda);
            z = zl;
            let zn = z.norm();
            if (zn - delta).abs() <= 0.1 * delta {
                break;
            }
            if zn > delta {
                lo = lambda;
            } else {
                hi = lambda;
            }
            let newton = lambda + (zn - delta) / delta * zn * zn / slope();
            lambda = if newton > lo && newton < hi && newton.is_finite() {
                newton
            } else if lo > 0.0 {
                (lo * hi).sqrt()
            } else {
                0.5 * (lo + hi)
            };
        }
    }
    (lambda, z)
}

/// The LM step whose scaled length fits the trust radius `delta` to within 10% (Moré's secular
/// equation `‖z(λ)‖ = Δ`, solved by safeguarded Newton on `1/‖z‖`); `λ = 0` if the Gauss–Newton
/// step already fits.
pub(super) fn trust_region_step(
    svd: &ScaledSvd,
    delta: f64,
    lambda_guess: f64,
    rows: usize,
) -> TrialStep {
    let cutoff = gauss_newton_cutoff(svd, rows);
    let sg = svd.sigma.component_mul(&svd.g).norm();
    let (lambda, w) = secular_search(delta, lambda_guess, sg, |lambda| {
        let w = damped_coefficients(svd, lambda, cutoff);
        (w, move || secular_slope(svd, lambda))
    });
    let jp2 = svd.sigma.component_mul(&w).norm_squared();
    TrialStep {
        z: svd.v_t.tr_mul(&w),
        lambda,
        jp2,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn secular_step_fits_the_trust_radius() {
        let svd = ScaledSvd {
            sigma: DVector::from_vec(vec![3.0, 1e-3]),
            v_t: DMatrix::identity(2, 2),
            g: DVector::from_vec(vec![1.0, 1.0]),
        };
        // Gauss–Newton step has length ~1000, far outside Δ = 0.5.
        let step = trust_region_step(&svd, 0.5, 0.0, 5);
        assert!(step.lambda > 0.0);
        // Moré accepts |‖z‖ - Δ| ≤ 0.1 Δ.
        assert!((step.z.norm() - 0.5).abs() <= 0.05);
        let inside = trust_region_step(&svd, 1e4, 0.0, 5);
        assert_eq!(inside.lambda, 0.0);
    }
}
