//! Longitudinal scattering `M_p`: Chiang's roughness-to-variance map and cuticle tilt on θ_r around
//! d'Eon's lobe ([`crate::families::shared::longitudinal`]).

use num_dual::DualNum;

use crate::families::shared::longitudinal::{lobe_variance, longitudinal_lobe, rotated_exit};

/// Tilt of the exit inclination per lobe, in units of α: `θ'_p = θ_r + TILT[p]·α`
/// (R −2α, TT +α, TRT +4α, residual 0).
pub const TILT: [f64; 4] = [-2.0, 1.0, 4.0, 0.0];

/// `v₀ = (0.726β_m + 0.812β_m² + 3.7β_m²⁰)²`.
#[inline]
pub fn base_variance<T: DualNum<f64>>(beta_m: &T) -> T {
    let b = beta_m.clone();
    let root = b.clone() * 0.726 + b.powi(2) * 0.812 + b.powi(20) * 3.7;
    root.powi(2)
}

/// `(sin θ'_p, |cos θ'_p|)` with `θ'_p = θ_r + TILT[p]·α`.
#[inline]
pub fn tilted_exit<T: DualNum<f64>>(p: usize, theta_r: f64, alpha: &T) -> (T, T) {
    rotated_exit(theta_r, alpha, TILT[p])
}

/// `M_p(θ_i, θ_r)` for lobe p with the tilt on θ_r.
#[inline]
pub fn longitudinal<T: DualNum<f64>>(p: usize, theta_i: f64, theta_r: f64, alpha: &T, v0: &T) -> T {
    let (sin_i, cos_i) = theta_i.sin_cos();
    let (sin_e, cos_e) = tilted_exit(p, theta_r, alpha);
    longitudinal_lobe(sin_i, cos_i, &sin_e, &cos_e, &lobe_variance(p, v0))
}
