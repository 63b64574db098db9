//! The ledger's fit section: whole fits of seeded synthetic data (the demo's geometry, truth,
//! scale and noise) per setting of the fit's knobs — starts, global stage, sample count,
//! multi-start subsample — wall time against parameter-recovery error.

use std::time::Instant;

use crate::cost::{CostRow, COST_SEED};
use crate::demo::{demo_geometry, DEMO_NOISE, DEMO_SCALE};
use crate::error::Result;
use crate::families::effects::{Effects, ModelConfig};
use crate::families::marschner::demo::demo_truth;
use crate::families::marschner::fit::fit;
use crate::families::marschner::fit::synthetic::synthesize;
use crate::families::marschner::parameters::fitted_parameters;
use crate::families::marschner::parameters::typical_range;
use crate::fit::{EffectsChoice, FitData, FitOptions, Global};

/// The seeded synthetic data of the fit section (the demo's geometry, truth, scale and noise).
pub(super) fn synthetic_data() -> FitData {
    synthesize(
        &demo_truth(),
        &ModelConfig::default(),
        &demo_geometry(),
        &DEMO_SCALE,
        DEMO_NOISE,
        COST_SEED,
    )
}

/// Every `stride`-th sample of `data`.
fn every_nth(data: &FitData, stride: usize) -> FitData {
    let idx: Vec<usize> = (0..data.len()).step_by(stride.max(1)).collect();
    data.subset(&idx)
}

/// Fit section: one fit per setting; error = |estimate − truth| / width of MODEL.md's typical
/// range, over the free shape parameters.
pub(super) fn fit_rows(data: &FitData, quick: bool) -> Result<Vec<CostRow>> {
    let truth = demo_truth();
    let base = FitOptions {
        seed: COST_SEED,
        effects: EffectsChoice::All,
        starts: if quick { 4 } else { 16 },
        polish: if quick { 1 } else { 2 },
        ..FitOptions::default()
    };
    let mut settings: Vec<(&str, String, FitOptions, usize)> = Vec::new();
    let starts: &[usize] = if quick { &[1, 4] } else { &[1, 4, 16, 32] };
    for &s in starts {
        let o = FitOptions {
            starts: s,
            ..base.clone()
        };
        settings.push(("starts", format!("{s} starts"), o, 1));
    }
    for (name, global) in [
        ("Nelder-Mead", Global::NelderMead),
        ("particle swarm", Global::Pso),
    ] {
        settings.push((
            "global stage",
            format!("{name} global stage"),
            FitOptions {
                global,
                ..base.clone()
            },
            1,
        ));
    }
    let strides: &[usize] = if quick { &[4] } else { &[8, 4, 2] };
    for &k in strides {
        settings.push(("samples", format!("1/{k} of the samples"), base.clone(), k));
    }
    let subs: &[usize] = if quick { &[300] } else { &[300, 1000] };
    for &n in subs {
        settings.push((
            "multi-start subsample",
            format!("multi-start on {n} samples"),
            FitOptions {
                subsample: n,
                ..base.clone()
            },
            1,
        ));
    }
    let mut rows = Vec::new();
    for (knob, setting, opts, stride) in settings {
        let d = every_nth(data, stride);
        let t0 = Instant::now();
        let out = fit(&d, "synthetic", Default::default(), &opts)?;
        let wall = t0.elapsed().as_secs_f64();
        let free = fitted_parameters(&Effects::default(), d.n_channels(), false);
        let mut errs: Vec<(f64, String)> = free
            .iter()
            .map(|&p| {
                let (lo, hi) = typical_range(p);
                let e = (out.params.get(p) - truth.get(p)).abs() / (hi - lo);
                (if e.is_finite() { e } else { f64::INFINITY }, p.json_name())
            })
            .collect();
        errs.sort_by(|a, b| b.0.total_cmp(&a.0));
        let rms = (errs.iter().map(|e| e.0 * e.0).sum::<f64>() / errs.len().max(1) as f64).sqrt();
        rows.push(CostRow {
            section: "fit".into(),
            knob: knob.into(),
            setting: format!("{setting} (n={})", d.len()),
            time_s: wall,
            error_max: errs.first().map_or(0.0, |e| e.0),
            error_rms: rms,
            worst_at: errs.first().map_or(String::new(), |e| e.1.clone()),
            pareto: false,
        });
    }
    Ok(rows)
}
