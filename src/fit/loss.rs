//! Robust losses (Ceres conventions: `ρ(s)` of the squared residual `s = r²`, scaled by `C`),
//! and the data-driven choice of `C` (`--loss-scale auto`: a tuning constant times a robust
//! estimate of the residuals' noise level).
//!
//! The generic LM minimises `½‖r̃‖²`, so the loss enters as the square-root residual
//! `r̃ = sign(r)·sqrt(ρ_C(r²))` with exact Jacobian rows `dr̃ = ρ′·r/r̃ · dr`: `½‖r̃‖²` is then
//! exactly the robust cost. (Ceres' corrector rescales by `√ρ′` but keeps the cost separately; an
//! argmin solver only sees `½‖r‖²`, so that form would optimise a different function.)

pub use crate::files::settings::{Loss, LossScale};

/// Noise level of residuals that may hold outliers: `1.4826·MAD` (the standard deviation for
/// Gaussian residuals, unmoved by up to half the values being outliers). Non-finite residuals
/// are skipped; `None` when nothing is left or the spread is zero.
pub fn noise_mad(residuals: &[f64]) -> Option<f64> {
    let mut r: Vec<f64> = residuals
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    if r.is_empty() {
        return None;
    }
    let median = |v: &mut Vec<f64>| {
        let mid = v.len() / 2;
        *v.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    let m = median(&mut r);
    let mut dev: Vec<f64> = r.iter().map(|v| (v - m).abs()).collect();
    let mad = 1.4826 * median(&mut dev);
    (mad.is_finite() && mad > 0.0).then_some(mad)
}

impl Loss {
    /// Every loss.
    pub const ALL: [Loss; 4] = [Loss::L2, Loss::Huber, Loss::Cauchy, Loss::SoftL1];

    /// The loss scale as a multiple of the noise σ that keeps 95% of least squares' efficiency
    /// on Gaussian residuals (Huber's 1.345, Cauchy's 2.385; soft-l1 is a smooth Huber and takes
    /// Huber's constant) while an outlier many σ out keeps little pull.
    pub fn tuning(&self) -> f64 {
        match self {
            Loss::L2 => 1.0,
            Loss::Huber | Loss::SoftL1 => 1.345,
            Loss::Cauchy => 2.385,
        }
    }

    /// `(ρ(s), ρ′(s))` of the unit-scale loss.
    fn rho(&self, s: f64) -> (f64, f64) {
        match self {
            Loss::L2 => (s, 1.0),
            Loss::Huber => {
                if s <= 1.0 {
                    (s, 1.0)
                } else {
                    let r = s.sqrt();
                    (2.0 * r - 1.0, 1.0 / r)
                }
            }
            Loss::Cauchy => ((1.0 + s).ln(), 1.0 / (1.0 + s)),
            Loss::SoftL1 => {
                let t = (1.0 + s).sqrt();
                (2.0 * (t - 1.0), 1.0 / t)
            }
        }
    }

    /// `(r̃, dr̃/dr, ρ′)` for residual `r` with loss scale `c`: `ρ_C(s) = C²ρ(s/C²)`.
    pub fn apply(&self, r: f64, c: f64) -> (f64, f64, f64) {
        if *self == Loss::L2 {
            return (r, 1.0, 1.0);
        }
        let c2 = c * c;
        let (rho, drho) = self.rho(r * r / c2);
        let rt = r.signum() * (c2 * rho).max(0.0).sqrt();
        // r̃ ≈ r near 0, where ρ′ → 1: the ratio ρ′ r / r̃ tends to 1.
        let factor = if rt.abs() > 1e-300 {
            drho * r / rt
        } else {
            1.0
        };
        (rt, factor, drho)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_are_refused() {
        for loss in Loss::ALL {
            assert_eq!(loss.to_string().parse::<Loss>().unwrap(), loss);
        }
        assert_eq!(" Soft_L1 ".parse::<Loss>().unwrap(), Loss::SoftL1);
        let msg = "tukey".parse::<Loss>().unwrap_err().to_string();
        assert!(msg.contains("unknown loss `tukey`"), "{msg}");
    }

    #[test]
    fn loss_scale_parses_auto_and_positive_numbers_only() {
        assert_eq!("Auto".parse::<LossScale>().unwrap(), LossScale::Auto);
        assert_eq!("0.05".parse::<LossScale>().unwrap(), LossScale::Fixed(0.05));
        for bad in ["0", "-1", "nan", "inf", "x"] {
            assert!(bad.parse::<LossScale>().is_err(), "{bad}");
        }
    }

    #[test]
    fn mad_noise_ignores_a_minority_of_outliers() {
        // -2..=2 repeated (median absolute deviation 1) plus 10% of values at 1000: the MAD
        // stays 1, so exactly 1.4826 (a standard deviation would be ~300).
        let mut r: Vec<f64> = (0..900).map(|i| (i % 5) as f64 - 2.0).collect();
        r.extend([1000.0; 100]);
        let s = noise_mad(&r).unwrap();
        assert!((s - 1.4826).abs() < 1e-12, "{s}");
        assert_eq!(noise_mad(&[0.0; 5]), None);
    }

    #[test]
    fn square_root_residual_reproduces_the_cost_and_its_derivative() {
        for loss in [Loss::L2, Loss::Huber, Loss::Cauchy, Loss::SoftL1] {
            for r in [-5.0, -0.3, 0.2, 1.5, 40.0] {
                let c = 0.7;
                let (rt, f, _) = loss.apply(r, c);
                let (rho, _) = loss.rho(r * r / (c * c));
                // ½r̃² is the robust cost exactly (up to rounding, hence 1e-12 relative).
                assert!((rt * rt - c * c * rho).abs() <= 1e-12 * (1.0 + rt * rt));
                let h = 1e-6;
                let fd = (loss.apply(r + h, c).0 - loss.apply(r - h, c).0) / (2.0 * h);
                // Central difference, O(h²) truncation plus O(ε/h) rounding: 1e-6 is ample.
                assert!((fd - f).abs() < 1e-6, "{loss} r={r}: {fd} vs {f}");
            }
        }
    }
}
