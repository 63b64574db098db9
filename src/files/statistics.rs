//! The goodness-of-fit tests' results as fit.json's `goodness_of_fit` records them: the runs
//! test, the lag-1 autocorrelation and the lack-of-fit F test (computed by `fit::gof`).

use serde::{Deserialize, Serialize};

/// The Wald–Wolfowitz runs test of residual signs, pooled over slices: residuals of a model that
/// fits change sign at random along a scan; a systematic misfit gives long runs of one sign.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RunsTest {
    /// Runs observed, summed over slices.
    pub runs: usize,
    /// Runs expected for random signs with the same counts.
    pub expected: f64,
    /// (runs − expected)/sd: strongly negative means too few runs.
    pub z: f64,
    /// Lower-tail p-value: the chance of this few runs or fewer by chance.
    pub p_value: f64,
}

/// Lag-1 autocorrelation of residuals along slices, pooled: neighbours on a scan that fits are
/// uncorrelated; a smooth misfit makes them alike.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Autocorrelation {
    /// Σ r_t r_{t+1} / Σ r_t² over neighbouring pairs within slices.
    pub r1: f64,
    /// Neighbouring pairs used.
    pub pairs: usize,
    /// r1·√pairs, ~N(0, 1) for independent residuals.
    pub z: f64,
    /// Upper-tail p-value of z (positive correlation is the misfit signature).
    pub p_value: f64,
}

/// The lack-of-fit F test: residual scatter between repeated measurements of one direction
/// (pure error) against the misfit of the direction means (lack of fit).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LackOfFit {
    /// Σ over replicate groups of Σ (r − group mean)².
    pub ss_pure_error: f64,
    pub dof_pure_error: usize,
    /// Residual sum of squares minus the pure error.
    pub ss_lack_of_fit: f64,
    pub dof_lack_of_fit: usize,
    /// (SS_lof/dof_lof) / (SS_pe/dof_pe).
    pub f: f64,
    /// Upper-tail p-value of F.
    pub p_value: f64,
    /// The noise level the replicates show: √(SS_pe/dof_pe), in residual units.
    pub pure_error_sd: f64,
}
