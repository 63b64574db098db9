//! A smooth dielectric cylinder's optics, shared by the families that integrate over the fibre's
//! width: unpolarised Fresnel, the refraction fixed by the exit inclination (Bravais' η'),
//! one segment's transmittance, the attenuations `A_p` and the exit azimuth `Φ_p`.

use std::f64::consts::PI;

use num_dual::DualNum;

/// `Φ_p = 2pγ_t − 2γ_o + pπ`.
#[inline]
pub fn exit_azimuth<T: DualNum<f64>>(p: usize, gamma_o: f64, gamma_t: &T) -> T {
    let pf = p as f64;
    gamma_t.clone() * (2.0 * pf) + (pf * PI - 2.0 * gamma_o)
}

/// Unpolarised dielectric Fresnel reflectance from 1 into `eta` at incidence cosine `cos_i`.
#[inline]
pub fn fresnel<T: DualNum<f64>>(eta: &T, cos_i: f64) -> T {
    let sin2_t = eta.powi(2).recip() * (1.0 - cos_i * cos_i);
    let cos_t = (-sin2_t + 1.0).sqrt();
    let e_cos_i = eta.clone() * cos_i;
    let e_cos_t = eta.clone() * cos_t.clone();
    let r_parallel = (e_cos_i.clone() - cos_t.clone()) / (e_cos_i + cos_t.clone());
    let r_perpendicular = (-e_cos_t.clone() + cos_i) / (e_cos_t + cos_i);
    (r_parallel.powi(2) + r_perpendicular.powi(2)) * 0.5
}

/// Quantities fixed by θ_r and η: `η' = √(η² − sin²θ_r)/cosθ_r` and `cos θ_t = √(1 − sin²θ_r/η²)`.
#[derive(Debug, Clone)]
pub struct ExitRefraction<T> {
    pub eta_prime: T,
    pub cos_theta_t: T,
    pub cos_theta_r: f64,
}

impl<T: DualNum<f64>> ExitRefraction<T> {
    pub fn new(eta: &T, theta_r: f64) -> Self {
        let (s, c) = theta_r.sin_cos();
        let eta2 = eta.powi(2);
        ExitRefraction {
            eta_prime: (eta2.clone() - s * s).sqrt() / c,
            cos_theta_t: (-(eta2.recip() * (s * s)) + 1.0).sqrt(),
            cos_theta_r: c,
        }
    }
}

/// Internal transmittance of one segment, `T = exp(−σ_a·2cosγ_t/cosθ_t)`; `chord = 2cosγ_t/cosθ_t`.
#[inline]
pub fn transmittance<T: DualNum<f64>>(sigma_a: &T, chord: &T) -> T {
    (-(sigma_a.clone() * chord.clone())).exp()
}

/// `A₀ = F, A₁ = (1−F)²T, A₂ = A₁TF, A₃ = A₂TF/(1 − TF)` (A₃ = 0 if TF = 1).
#[inline]
pub fn attenuations<T: DualNum<f64>>(f: &T, t: &T) -> [T; 4] {
    let a0 = f.clone();
    let a1 = (-f.clone() + 1.0).powi(2) * t.clone();
    let tf = t.clone() * f.clone();
    let a2 = a1.clone() * tf.clone();
    let one_minus = -tf.clone() + 1.0;
    let a3 = if one_minus.re() == 0.0 {
        T::from(0.0)
    } else {
        a2.clone() * tf / one_minus
    };
    [a0, a1, a2, a3]
}
