//! The ledger's Jacobian section: exact forward-mode AD against central finite differences in
//! the solver's parameters, time per full Jacobian and the error of each column.

use crate::cost::{time_per_call, CostRow};
use crate::error::Result;
use crate::families::effects::{Effects, ModelConfig};
use crate::families::marschner::demo::demo_truth;
use crate::families::marschner::fit::forward::MarschnerForward;
use crate::families::marschner::parameters::fitted_parameters;
use crate::fit::{Evaluator, FitData, Loss, Space};
use crate::geometry::Measurement;

/// Jacobian section: exact forward-mode AD against central finite differences in the solver's
/// parameters, at the truth, on the synthetic data; error per column relative to the AD column.
pub(super) fn jacobian_rows(data: &FitData, quick: bool) -> Result<Vec<CostRow>> {
    let min_s = if quick { 0.1 } else { 1.0 };
    let truth = demo_truth();
    let nc = data.n_channels();
    let free = fitted_parameters(&Effects::default(), nc, false);
    let forward = MarschnerForward {
        config: ModelConfig::default(),
        measurement: Measurement::S,
    };
    let (ev, _) = Evaluator::new(
        &forward,
        data,
        Space::Log,
        Loss::L2,
        1.0,
        truth.clone(),
        free.clone(),
    )?;
    let x: Vec<f64> = free.iter().map(|&n| truth.get(n)).collect();
    let u = ev.internal(&x);
    let n = u.len();
    let m = ev.n_residuals();
    let mut ad = Vec::new();
    let t_ad = time_per_call(min_s, || {
        ad = ev.eval_internal(&u, true).jacobian.unwrap_or_default();
    });
    let cols = ev.eval_internal(&u, true).n_cols;
    let central = || {
        let mut j = vec![0.0; m * n];
        for k in 0..n {
            // Step ~ cbrt(machine epsilon) × scale: balances truncation and rounding error.
            let h = 6e-6 * u[k].abs().max(1.0);
            let mut up = u.clone();
            let mut dn = u.clone();
            up[k] += h;
            dn[k] -= h;
            let rp = ev.eval_internal(&up, false).residual;
            let rm = ev.eval_internal(&dn, false).residual;
            for i in 0..m {
                j[i * n + k] = (rp[i] - rm[i]) / (2.0 * h);
            }
        }
        j
    };
    let mut fd = Vec::new();
    let t_fd = time_per_call(min_s, || fd = central());
    let mut col_err = Vec::with_capacity(n);
    for k in 0..n {
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..m {
            let a = ad.get(i * cols + k).copied().unwrap_or(f64::NAN);
            num += (fd[i * n + k] - a).powi(2);
            den += a * a;
        }
        col_err.push((num / den.max(f64::MIN_POSITIVE)).sqrt());
    }
    let (worst, max) =
        col_err.iter().enumerate().fold(
            (0, 0.0f64),
            |(w, mx), (k, &e)| if e > mx { (k, e) } else { (w, mx) },
        );
    let rms = (col_err.iter().map(|e| e * e).sum::<f64>() / n.max(1) as f64).sqrt();
    Ok(vec![
        CostRow {
            section: "jacobian".into(),
            knob: "jacobian".into(),
            setting: "AD (forward mode)".into(),
            time_s: t_ad,
            error_max: 0.0,
            error_rms: 0.0,
            worst_at: "reference".into(),
            pareto: false,
        },
        CostRow {
            section: "jacobian".into(),
            knob: "jacobian".into(),
            setting: "central differences".into(),
            time_s: t_fd,
            error_max: max,
            error_rms: rms,
            worst_at: free.get(worst).map_or("scale".into(), |p| p.json_name()),
            pareto: false,
        },
    ])
}
