//! The Chiang demo's true parameters (`hairfit demo --model chiang`, the cost ledger): CHIANG.md's
//! ranges, the Marschner demo's brown-ish absorption, R toward the root (`alpha` < 0).

use super::ChiangParams;

/// The Chiang demo's true parameters (α in radians).
pub fn demo_truth() -> ChiangParams<f64> {
    ChiangParams {
        eta: 1.55,
        sigma_a: vec![0.25, 0.45, 0.8],
        beta_m: 0.25,
        beta_n: 0.35,
        alpha: (-2.5f64).to_radians(),
    }
}
