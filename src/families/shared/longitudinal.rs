//! d'Eon et al. 2011's longitudinal lobe `M`, in its stable exponentially scaled form, with what
//! every family that uses it shares: the per-lobe variance multipliers (pbrt-v4's, which Chiang
//! 2016 and d'Eon's fit here both take) and the exit inclination rotated by the cuticle tilt.

use num_dual::DualNum;

use super::bessel::i0e;

/// Variance multiplier per lobe: `v_p = VARIANCE_SCALE[p]·v₀`.
pub const VARIANCE_SCALE: [f64; 4] = [1.0, 0.25, 4.0, 4.0];

/// `v_p` for lobe p = 0..3.
#[inline]
pub fn lobe_variance<T: DualNum<f64>>(p: usize, v0: &T) -> T {
    v0.clone() * VARIANCE_SCALE[p]
}

/// `(sin θ', |cos θ'|)` with `θ' = θ_r + factor·α`: the exit inclination rotated by a multiple of
/// the cuticle tilt (each family its own multiples; d'Eon's M takes the rotated angle as is).
#[inline]
pub fn rotated_exit<T: DualNum<f64>>(theta_r: f64, alpha: &T, factor: f64) -> (T, T) {
    let (s, c) = (alpha.clone() * factor + theta_r).sin_cos();
    let c = if c.re() < 0.0 { -c } else { c };
    (s, c)
}

/// `M(a, b; v) = exp(−sin a sin b/v) I₀(cos a cos b/v) / (2v sinh(1/v))` in the stable form
/// `i0e(x)·exp((cos a cos b − sin a sin b − 1)/v) / (v(1 − e^{−2/v}))`.
/// The exponent is ≤ 0 (it is `(cos(a+b) − 1)/v` with `cos b ≥ 0`), so nothing overflows at small v.
#[inline]
pub fn longitudinal_lobe<T: DualNum<f64>>(
    sin_theta_i: f64,
    cos_theta_i: f64,
    sin_exit: &T,
    cos_exit: &T,
    v: &T,
) -> T {
    let inv_v = v.recip();
    let cc = cos_exit.clone() * cos_theta_i;
    let ss = sin_exit.clone() * sin_theta_i;
    let x = cc.clone() * inv_v.clone();
    let exponent = (cc - ss - 1.0) * inv_v.clone();
    // 1 − e^{−2/v} = −expm1(−2/v): exact for large v (β_m → 1), where 2/v is small.
    let norm = v.clone() * (-(inv_v * (-2.0)).exp_m1());
    i0e(&x) * exponent.exp() / norm
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ M cos θ_i dθ_i over (−π/2, π/2) = 1 for every exit inclination and variance
    /// (d'Eon's normalisation); 2000-node Gauss–Legendre resolves even v = 1e-3 (σ ≈ 0.03 rad).
    #[test]
    fn unit_area_over_incidence() {
        let gl = super::super::quadrature::GaussLegendre::new(2000);
        for v in [1e-3, 0.01, 0.3, 5.0, 100.0] {
            for theta_r in [-1.2f64, -0.3, 0.0, 0.7, 1.4] {
                let (s, c) = theta_r.sin_cos();
                let total: f64 = gl
                    .nodes
                    .iter()
                    .zip(&gl.weights)
                    .map(|(x, w)| {
                        let t = std::f64::consts::FRAC_PI_2 * x;
                        let (si, ci) = t.sin_cos();
                        std::f64::consts::FRAC_PI_2 * w * ci * longitudinal_lobe(si, ci, &s, &c, &v)
                    })
                    .sum();
                assert!((total - 1.0).abs() < 1e-12, "v {v}, θ_r {theta_r}: {total}");
            }
        }
    }
}
