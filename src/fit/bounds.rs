//! Free-parameter bookkeeping: which parameters a fit varies, their bounds, their typical search
//! ranges (MODEL.md) and the MINUIT-style smooth transforms that keep every iterate inside bounds.

use std::f64::consts::FRAC_1_SQRT_2;

use crate::model::{ParamName, Params};

/// Smallest positive angle allowed for an open lower bound at 0 (β_R, w_c), radians: 0.01°.
const TINY_ANGLE: f64 = 0.01 * std::f64::consts::PI / 180.0;
/// Margin that keeps an open lower bound (a > 1/√2, η > 1) strictly open.
const OPEN_MARGIN: f64 = 1e-6;

/// The bounds of one parameter in its natural (model, radian) units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// Unbounded: the identity transform.
    Free,
    /// `x ≥ lo`: `x = lo − 1 + sqrt(u² + 1)`.
    Lower(f64),
    /// `lo ≤ x ≤ hi`: `x = lo + (hi − lo)(sin u + 1)/2`.
    Both(f64, f64),
}

impl Bound {
    /// The bounds MODEL.md and the fit's domain give `name` (natural units, radians).
    pub fn of(name: ParamName) -> Bound {
        match name {
            ParamName::Eta => Bound::Both(1.0 + OPEN_MARGIN, 2.5),
            // Upper limits far beyond MODEL.md's typical ranges (σ_a = 50 already removes all
            // transmitted light): they only stop a direction the data leave flat from running
            // away, so the solver converges and the covariance names the parameter.
            ParamName::SigmaA(_) => Bound::Both(0.0, 50.0),
            ParamName::KG => Bound::Both(0.0, 100.0),
            ParamName::AlphaR => Bound::Free,
            ParamName::BetaR => Bound::Both(TINY_ANGLE, 30f64.to_radians()),
            ParamName::WC => Bound::Both(TINY_ANGLE, 60f64.to_radians()),
            ParamName::Eccentricity => Bound::Both(FRAC_1_SQRT_2 + OPEN_MARGIN, 1.0),
            ParamName::DeltaEtaPrime | ParamName::DeltaHM => Bound::Lower(1e-6),
        }
    }

    /// Natural value of internal `u` (MINUIT transform).
    pub fn to_natural(&self, u: f64) -> f64 {
        match *self {
            Bound::Free => u,
            Bound::Lower(lo) => lo - 1.0 + (u * u + 1.0).sqrt(),
            Bound::Both(lo, hi) => lo + (hi - lo) * (u.sin() + 1.0) / 2.0,
        }
    }

    /// `dx/du` of the transform at `u`.
    pub fn derivative(&self, u: f64) -> f64 {
        match *self {
            Bound::Free => 1.0,
            Bound::Lower(_) => u / (u * u + 1.0).sqrt(),
            Bound::Both(lo, hi) => (hi - lo) * u.cos() / 2.0,
        }
    }

    /// Internal `u` of a natural value (clamped into the bounds first).
    pub fn to_internal(&self, x: f64) -> f64 {
        match *self {
            Bound::Free => x,
            Bound::Lower(lo) => {
                let t = x.max(lo) - lo + 1.0;
                (t * t - 1.0).max(0.0).sqrt()
            }
            Bound::Both(lo, hi) => (2.0 * (x.clamp(lo, hi) - lo) / (hi - lo) - 1.0).asin(),
        }
    }

    /// Clamp a natural value into the bounds.
    pub fn clamp(&self, x: f64) -> f64 {
        match *self {
            Bound::Free => x,
            Bound::Lower(lo) => x.max(lo),
            Bound::Both(lo, hi) => x.clamp(lo, hi),
        }
    }

    /// True when `x` sits on a bound (relative to the bound's span or magnitude).
    pub fn at_bound(&self, x: f64) -> bool {
        let near = |b: f64, span: f64| (x - b).abs() <= 1e-7 * span.max(1e-12);
        match *self {
            Bound::Free => false,
            Bound::Lower(lo) => near(lo, lo.abs().max(1e-3)),
            Bound::Both(lo, hi) => near(lo, hi - lo) || near(hi, hi - lo),
        }
    }
}

/// MODEL.md's typical range of `name` in natural units (radians for angles): the start design box.
pub fn typical_range(name: ParamName) -> (f64, f64) {
    match name {
        ParamName::Eta => (1.5, 1.6),
        ParamName::SigmaA(_) => (0.05, 2.0),
        ParamName::AlphaR => ((-10f64).to_radians(), (-5f64).to_radians()),
        ParamName::BetaR => (5f64.to_radians(), 10f64.to_radians()),
        ParamName::KG => (0.5, 5.0),
        ParamName::WC => (10f64.to_radians(), 25f64.to_radians()),
        ParamName::Eccentricity => (0.85, 1.0),
        ParamName::DeltaEtaPrime => (0.2, 0.4),
        ParamName::DeltaHM => (0.4, 0.6),
    }
}

/// True for parameters stored in radians and reported in degrees.
pub fn is_angle(name: ParamName) -> bool {
    matches!(name, ParamName::AlphaR | ParamName::BetaR | ParamName::WC)
}

/// Factor from natural units to reporting units (degrees for angles).
pub fn report_factor(name: ParamName) -> f64 {
    if is_angle(name) {
        180.0 / std::f64::consts::PI
    } else {
        1.0
    }
}

/// Read parameter `name` from `p`.
pub fn get<T: Clone>(p: &Params<T>, name: ParamName) -> T {
    match name {
        ParamName::Eta => p.eta.clone(),
        ParamName::SigmaA(c) => p.sigma_a[c].clone(),
        ParamName::AlphaR => p.alpha_r.clone(),
        ParamName::BetaR => p.beta_r.clone(),
        ParamName::KG => p.k_g.clone(),
        ParamName::WC => p.w_c.clone(),
        ParamName::Eccentricity => p.eccentricity.clone(),
        ParamName::DeltaEtaPrime => p.delta_eta_prime.clone(),
        ParamName::DeltaHM => p.delta_h_m.clone(),
    }
}

/// Set parameter `name` in `p`.
pub fn set<T>(p: &mut Params<T>, name: ParamName, v: T) {
    match name {
        ParamName::Eta => p.eta = v,
        ParamName::SigmaA(c) => p.sigma_a[c] = v,
        ParamName::AlphaR => p.alpha_r = v,
        ParamName::BetaR => p.beta_r = v,
        ParamName::KG => p.k_g = v,
        ParamName::WC => p.w_c = v,
        ParamName::Eccentricity => p.eccentricity = v,
        ParamName::DeltaEtaPrime => p.delta_eta_prime = v,
        ParamName::DeltaHM => p.delta_h_m = v,
    }
}

/// Map `f` over every field of a parameter set (e.g. lift f64 to a dual number type).
pub fn map_params<T, U>(p: &Params<T>, f: impl Fn(&T) -> U) -> Params<U> {
    Params {
        eta: f(&p.eta),
        sigma_a: p.sigma_a.iter().map(&f).collect(),
        alpha_r: f(&p.alpha_r),
        beta_r: f(&p.beta_r),
        k_g: f(&p.k_g),
        w_c: f(&p.w_c),
        eccentricity: f(&p.eccentricity),
        delta_eta_prime: f(&p.delta_eta_prime),
        delta_h_m: f(&p.delta_h_m),
    }
}

/// The midpoint of every typical range: a neutral reference parameter set with `n` channels.
pub fn reference_params(n_channels: usize) -> Params<f64> {
    let mid = |n: ParamName| {
        let (a, b) = typical_range(n);
        0.5 * (a + b)
    };
    Params {
        eta: crate::params::DEFAULT_ETA,
        sigma_a: vec![0.4; n_channels],
        alpha_r: mid(ParamName::AlphaR),
        beta_r: mid(ParamName::BetaR),
        k_g: 1.0,
        w_c: mid(ParamName::WC),
        eccentricity: crate::params::DEFAULT_ECCENTRICITY,
        delta_eta_prime: crate::params::DEFAULT_DELTA_ETA_PRIME,
        delta_h_m: crate::params::DEFAULT_DELTA_H_M,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transforms_round_trip_and_stay_inside() {
        for b in [
            Bound::Free,
            Bound::Lower(0.0),
            Bound::Both(FRAC_1_SQRT_2, 1.0),
        ] {
            for x in [0.75, 0.8, 0.99] {
                // 1e-12: asin/sin and sqrt round trips lose a few ulps of the span only.
                assert!(
                    (b.to_natural(b.to_internal(x)) - x).abs() < 1e-12,
                    "{b:?} {x}"
                );
            }
            for u in [-1e3, -3.0, -1.0, 0.0, 0.5, 2.0, 1e3] {
                let x = b.to_natural(u);
                assert_eq!(b.clamp(x), x, "{b:?} u={u} leaves the bounds");
                // Central difference vs analytic derivative; 1e-6 is the O(h²) error for h=1e-4.
                let h = 1e-4;
                let fd = (b.to_natural(u + h) - b.to_natural(u - h)) / (2.0 * h);
                assert!((fd - b.derivative(u)).abs() < 1e-6, "{b:?} u={u}");
            }
        }
    }
}
