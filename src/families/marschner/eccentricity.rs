//! Eccentric cross-section: the effective index `η*(φ_h)` that TRT alone sees.

use num_dual::DualNum;

use super::{instrument, Angles};

/// `η* = ((η*_1 + η*_2) + cos(2φ_h)(η*_1 − η*_2))/2` with `η*_1 = 2(η−1)a² − η + 2`,
/// `η*_2 = 2(η−1)a⁻² − η + 2`; equals η for a = 1.
#[inline]
pub fn eccentric_index<T: DualNum<f64>>(eta: &T, a: &T, phi_h: f64) -> T {
    eccentric_index_at(&eccentric_terms(eta, a), phi_h)
}

/// The parameter-only part of [`eccentric_index`]: `(η*_1 + η*_2, η*_1 − η*_2)`.
#[inline]
pub fn eccentric_terms<T: DualNum<f64>>(eta: &T, a: &T) -> (T, T) {
    let a2 = a.clone() * a.clone();
    let k = (eta.clone() - 1.0) * 2.0;
    let base = -eta.clone() + 2.0;
    let e1 = k.clone() * a2.clone() + base.clone();
    let e2 = k / a2 + base;
    (e1.clone() + e2.clone(), e1 - e2)
}

/// [`eccentric_index`] from its [`eccentric_terms`] (same operations, same value).
#[inline]
pub fn eccentric_index_at<T: DualNum<f64>>((sum, diff): &(T, T), phi_h: f64) -> T {
    instrument::count_eccentricity();
    (sum.clone() + diff.clone() * (2.0 * phi_h).cos()) * 0.5
}

/// Spread (max − min) of `cos 2φ_h = cos(φ_i + φ_r)` over `angles`: eccentricity acts through it,
/// so a small spread leaves `a` indistinguishable from a change of η. 0 for no angles.
pub fn cos_2phi_h_spread(angles: &[Angles]) -> f64 {
    let (lo, hi) = angles
        .iter()
        .map(|a| (a.phi_i + a.phi_r).cos())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
            (lo.min(c), hi.max(c))
        });
    if hi >= lo {
        hi - lo
    } else {
        0.0
    }
}
