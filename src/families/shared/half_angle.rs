//! The half angle between incidence and exit that the real-time families take their R Fresnel
//! at (Karis 2016, d'Eon 2011 as Frostbite/HDRP write it), in forms that do not cancel as the
//! two directions oppose.

use std::f64::consts::PI;

use crate::geometry::angles::wrap;

/// `cos(φ/2)` of φ taken to [−π, π] (≥ 0), from the half angle itself (no cancellation as
/// φ → π); even in φ to the bit.
pub fn half_phi_cosine(phi: f64) -> f64 {
    let folded = if phi.abs() <= PI {
        phi.abs()
    } else {
        wrap(phi).abs()
    };
    (0.5 * folded).cos().max(0.0)
}

/// `cos(∠(ω_i, ω_r)/2) = √(½ + ½ ω_i·ω_r) = √(sin²θ_h + cos θ_i cos θ_r cos²(φ/2))`: the
/// right-hand form has no cancellation where ω_i ≈ −ω_r (θ_i ≈ −θ_r, φ ≈ π).
pub fn half_angle_cosine(theta_i: f64, theta_r: f64, cos_half_phi: f64) -> f64 {
    let sin_h = (0.5 * (theta_i + theta_r)).sin();
    let c = cos_half_phi;
    (sin_h * sin_h + theta_i.cos() * theta_r.cos() * c * c)
        .clamp(0.0, 1.0)
        .sqrt()
}
