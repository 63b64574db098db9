//! Longitudinal scattering `M_p(θ_h) = g(θ_h − α_p; β_p)` and the derived lobe shifts/widths.

use num_dual::DualNum;

/// `1/√(2π)`.
pub const INV_SQRT_TAU: f64 = 0.398_942_280_401_432_7;

/// Unit-area Gaussian `g(x; s) = exp(−x²/(2s²)) / (s√(2π))`.
#[inline]
pub fn gaussian<T: DualNum<f64>>(x: T, s: &T) -> T {
    gaussian_inv(x, &s.recip())
}

/// [`gaussian`] from `1/s`: no division, for a width shared by a batch (`1/s` computed once).
#[inline]
pub fn gaussian_inv<T: DualNum<f64>>(x: T, inv_s: &T) -> T {
    let z = x * inv_s.clone();
    (z.clone() * z * (-0.5)).exp() * inv_s.clone() * INV_SQRT_TAU
}

/// Lobe shift and width `(α_p, β_p)`: `α_TT = −α_R/2, α_TRT = −3α_R/2, β_TT = β_R/2, β_TRT = 2β_R`.
#[inline]
pub fn lobe_shape<T: DualNum<f64>>(p: usize, alpha_r: &T, beta_r: &T) -> (T, T) {
    match p {
        0 => (alpha_r.clone(), beta_r.clone()),
        1 => (alpha_r.clone() * (-0.5), beta_r.clone() * 0.5),
        _ => (alpha_r.clone() * (-1.5), beta_r.clone() * 2.0),
    }
}

/// `M_p(θ_h)`.
#[inline]
pub fn longitudinal<T: DualNum<f64>>(p: usize, theta_h: f64, alpha_r: &T, beta_r: &T) -> T {
    let (alpha, beta) = lobe_shape(p, alpha_r, beta_r);
    gaussian(-alpha + theta_h, &beta)
}
