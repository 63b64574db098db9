//! What every export target fits to: the source fit's `S` over its measured directions plus a
//! dense sphere ([`MappingTarget`]), the per-channel floor of the log residual, and the
//! project's Levenberg–Marquardt run ([`least_squares`]) each target's mapping uses.

use argmin::core::{Executor, Jacobian, Operator, State};
use nalgebra::{DMatrix, DVector};

use super::source::SourceFit;
use crate::error::{Error, Result};
use crate::geometry::Angles;
use crate::lm::LevenbergMarquardt;

/// Floor of the log residual, relative to the channel's largest source value.
pub const FLOOR_FRACTION: f64 = 1e-3;

/// LM trial steps per start.
pub const MAX_ITERATIONS: u64 = 60;

/// The sphere every mapping covers besides the measured directions: θ_i, θ_r from −75° to 75°
/// in 15° steps and φ from 0° to 180° in 15° (S is even in φ): 11 × 11 × 13 = 1573 directions.
pub fn dense_sphere() -> Vec<Angles> {
    let thetas: Vec<f64> = (-5..=5).map(|k| 15.0 * k as f64).collect();
    let mut out = Vec::with_capacity(1573);
    for &ti in &thetas {
        for &tr in &thetas {
            for k in 0..=12 {
                out.push(Angles::from_degrees(ti, 0.0, tr, 15.0 * k as f64));
            }
        }
    }
    out
}

/// What every mapping fits: the source's `S` at its measured directions followed by the dense
/// sphere, with each channel's floor for the log residual.
pub struct MappingTarget {
    pub angles: Vec<Angles>,
    /// `S` of the source, `target[k·n + c]`.
    pub target: Vec<f64>,
    /// Per channel: [`FLOOR_FRACTION`] × the channel's largest source value.
    pub floor: Vec<f64>,
    pub n_sphere: usize,
}

impl MappingTarget {
    /// The target of `source`; an `S` that is not finite and non-negative everywhere is an error.
    pub fn new(source: &SourceFit) -> Result<MappingTarget> {
        let sphere = dense_sphere();
        let mut angles = source.measured.clone();
        angles.extend_from_slice(&sphere);
        let n = source.model.n_channels();
        let target = source.model.scattering(&angles);
        if target.iter().any(|s| !s.is_finite() || *s < 0.0) {
            return Err(Error::Other(format!(
                "{}: the fitted model's S is not finite and non-negative everywhere; refit",
                source.dir.display()
            )));
        }
        Ok(MappingTarget {
            floor: channel_floor(&target, n),
            angles,
            target,
            n_sphere: sphere.len(),
        })
    }
}

/// Each channel's floor `f_c`: [`FLOOR_FRACTION`] × its largest value (`values[k·n + c]`).
pub fn channel_floor(values: &[f64], n: usize) -> Vec<f64> {
    (0..n)
        .map(|c| {
            let peak = values
                .iter()
                .skip(c)
                .step_by(n)
                .copied()
                .fold(0.0, f64::max);
            (FLOOR_FRACTION * peak).max(f64::MIN_POSITIVE)
        })
        .collect()
}

/// `ln(v + f_c)` of every value (channel c = index mod n).
pub fn log_floored(values: &[f64], floor: &[f64], n: usize) -> Vec<f64> {
    values
        .iter()
        .enumerate()
        .map(|(k, s)| (s + floor[k % n]).ln())
        .collect()
}

/// `|ln(fitted + f_c) − ln(target + f_c)|` of every value.
pub fn log_errors(fitted: &[f64], target: &[f64], floor: &[f64], n: usize) -> Vec<f64> {
    log_floored(fitted, floor, n)
        .iter()
        .zip(log_floored(target, floor, n))
        .map(|(a, b)| (a - b).abs())
        .collect()
}

/// Root mean square.
pub fn rms(e: &[f64]) -> f64 {
    (e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt()
}

/// Largest value (0 for none).
pub fn max(e: &[f64]) -> f64 {
    e.iter().copied().fold(0.0, f64::max)
}

/// Run the project's Levenberg–Marquardt on `problem` from `x0` for at most `max_iters` trial
/// steps: the best point and the steps taken.
pub fn least_squares<P>(problem: P, x0: &[f64], max_iters: u64) -> Result<(DVector<f64>, u64)>
where
    P: Operator<Param = DVector<f64>, Output = DVector<f64>>
        + Jacobian<Param = DVector<f64>, Jacobian = DMatrix<f64>>,
{
    let res = Executor::new(problem, LevenbergMarquardt::new())
        .configure(|s| s.param(DVector::from_column_slice(x0)).max_iters(max_iters))
        .run()
        .map_err(|e| Error::Other(format!("mapping fit failed: {e}")))?;
    let state = res.state();
    let x = state
        .get_best_param()
        .or(state.get_param())
        .cloned()
        .ok_or_else(|| Error::Other("mapping fit returned no parameters".into()))?;
    Ok((x, state.get_iter()))
}
