//! Fresnel reflectance with the Bravais indices, and the attenuation `A(p, h)`.

use num_dual::DualNum;

use super::chain::ModelNum;

/// Fresnel `F(γ_i)` for `h = sin γ_i` with `cos γ_i` and `cos γ_t = sqrt(1 − h²/η'²)` given:
/// `(r_s² + r_p²)/2`. The internal reflection `F(1/η', 1/η'', γ_t)` is the same value.
#[inline]
pub fn fresnel<T: DualNum<f64>>(eta_p: &T, eta_pp: &T, cos_gi: &T, cos_gt: &T) -> T {
    let a = eta_p.clone() * cos_gt.clone();
    let b = eta_pp.clone() * cos_gi.clone();
    // r_s = n_s/d_s, r_p = n_p/d_p over one common denominator: one division, not two.
    let (n_s, d_s) = (cos_gi.clone() - a.clone(), cos_gi.clone() + a);
    let (n_p, d_p) = (b.clone() - cos_gt.clone(), b + cos_gt.clone());
    let (s, q) = (n_s * d_p.clone(), n_p * d_s.clone());
    let d = d_s * d_p;
    (s.clone() * s + q.clone() * q) / (d.clone() * d) * 0.5
}

/// `cos γ_t = sqrt(1 − (h/η')²)`, the exact refracted angle (used in both root modes).
#[inline]
pub fn cos_gamma_t<T: DualNum<f64>>(h: &T, eta_p: &T) -> T {
    let x = h.clone() / eta_p.clone();
    (-(x.clone() * x) + 1.0).sqrt()
}

/// Fresnel part of the attenuation: `F` for p = 0, `(1 − F)² F^{p−1}` for p ≥ 1.
#[inline]
pub fn fresnel_attenuation<T: DualNum<f64>>(p: usize, f: T) -> T {
    match p {
        0 => f,
        1 => {
            let t = -f + 1.0;
            t.clone() * t
        }
        _ => {
            let t = -f.clone() + 1.0;
            t.clone() * t * f.powi(p as i32 - 1)
        }
    }
}

/// Absorption `T(h)^p = exp(−2 p σ_a cos γ_t / cos θ_t)` (corrected chord `2 cos γ_t`).
#[inline]
pub fn absorption<T: DualNum<f64>>(p: usize, sigma_a: &T, chord_over_cos_tt: &T) -> T {
    (sigma_a.clone() * chord_over_cos_tt.clone() * (-(p as f64))).exp()
}

/// `base · T(h)^p`, the same value as `base * absorption(p, sigma_a, chord)` with the
/// derivative by the chain rule in f64 (one exp of the real part, no dual arithmetic).
#[inline]
pub fn absorbed<T: ModelNum>(p: usize, base: &T, sigma_a: &T, chord_over_cos_tt: &T) -> T {
    let (b, s, c) = (base.re(), sigma_a.re(), chord_over_cos_tt.re());
    let e = (s * c * (-(p as f64))).exp();
    let k = -(p as f64) * b * e;
    T::linear(
        b * e,
        &[(e, base), (k * c, sigma_a), (k * s, chord_over_cos_tt)],
    )
}

/// `2 cos γ_t / cos θ_t`: the path length through the fiber per unit radius, per internal segment.
#[inline]
pub fn chord<T: DualNum<f64>>(cos_gt: &T, cos_theta_t: &T) -> T {
    cos_gt.clone() * 2.0 / cos_theta_t.clone()
}
