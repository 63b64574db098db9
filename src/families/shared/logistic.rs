//! The trimmed logistic of pbrt-v4's azimuthal lobe `N_p` (Chiang et al. 2016): the map from
//! azimuthal roughness β_n to its scale `s`, its normalisation over [−π, π] and its value.

use std::f64::consts::FRAC_PI_2;

use num_dual::DualNum;

/// `s = √(π/8)(0.265β_n + 1.194β_n² + 5.372β_n²²)`.
#[inline]
pub fn logistic_scale<T: DualNum<f64>>(beta_n: &T) -> T {
    const SQRT_PI_OVER_8: f64 = 0.626_657_068_657_750_1;
    let b = beta_n.clone();
    (b.clone() * 0.265 + b.powi(2) * 1.194 + b.powi(22) * 5.372) * SQRT_PI_OVER_8
}

/// `1/(s·tanh(π/(2s)))`: the logistic's normalisation trimmed to [−π, π].
#[inline]
pub fn trimmed_logistic_norm<T: DualNum<f64>>(s: &T) -> T {
    (s.clone() * (s.recip() * FRAC_PI_2).tanh()).recip()
}

/// `ℓ(x) = e^{−|x|/s} / (s(1 + e^{−|x|/s})² tanh(π/2s))`, x already wrapped to [−π, π];
/// `norm` from [`trimmed_logistic_norm`].
#[inline]
pub fn trimmed_logistic<T: DualNum<f64>>(x: &T, inv_s: &T, norm: &T) -> T {
    let a = if x.re() < 0.0 { -x.clone() } else { x.clone() };
    let e = (-(a * inv_s.clone())).exp();
    let d = e.clone() + 1.0;
    e * norm.clone() / (d.clone() * d)
}
