//! Bravais indices `η'`, `η''` and the refracted inclination `cos θ_t` for one index of refraction.

use num_dual::DualNum;

/// The indices a lobe's azimuthal problem sees at `θ_d`.
#[derive(Debug, Clone)]
pub struct Bravais<T> {
    /// `η' = sqrt(η² − sin²θ_d) / cos θ_d`.
    pub eta_p: T,
    /// `η'' = η² cos θ_d / sqrt(η² − sin²θ_d)`.
    pub eta_pp: T,
    /// `cos θ_t = sqrt(1 − sin²θ_d / η²) = sqrt(η² − sin²θ_d) / η`.
    pub cos_theta_t: T,
}

/// Bravais indices and `cos θ_t` for index `eta` at `θ_d` (given as its sine and cosine).
#[inline]
pub fn bravais_indices<T: DualNum<f64>>(eta: &T, sin_td: f64, cos_td: f64) -> Bravais<T> {
    let s2 = sin_td * sin_td;
    let eta2 = eta.clone() * eta.clone();
    let root = (eta2.clone() - s2).sqrt();
    Bravais {
        eta_p: root.clone() / cos_td,
        eta_pp: eta2 * cos_td / root.clone(),
        // The root η' needs anyway, over η: one division instead of a reciprocal and a sqrt.
        cos_theta_t: root / eta.clone(),
    }
}
