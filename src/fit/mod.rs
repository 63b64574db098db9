//! The fit (`hairfit fit`, `hairfit demo`): least squares of the Marschner model to samples, with
//! exact AD Jacobians, bounds by smooth transforms, per-channel scale by variable projection,
//! robust losses, a seeded parallel multi-start, LM polish, and uncertainties in natural units.
//!
//! Pipeline ([`fit`]): choose effects → free parameters → Latin-hypercube starts → short LM runs
//! on a subsample (parallel over starts) → optional global stage → LM polish of the best few on
//! all data → covariance, warnings, residual statistics, curves ([`output`] writes them).

pub mod args;
pub mod auto;
pub mod bounds;
pub mod demo;
pub mod design;
pub mod gof;
pub mod loss;
pub mod output;
pub mod problem;
pub mod solve;

use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

pub use auto::{choose_effects, AutoChoice};
pub use loss::Loss;
pub use output::{CurveRow, FitJson};
pub use problem::{Evaluator, FitData, Forward, ModelForward, ScaleMode, Space};
pub use solve::RunStatus;

use crate::data::Dataset;
use crate::error::{Error, Result};
use crate::model::{Effects, Measurement, ModelConfig, ParamName, Params, RootMode};
use bounds::{report_factor, typical_range, Bound};
use solve::{is_cancelled, run_local, LocalRun};

/// Runner-ups of the multi-start are polished on all data only within this many χ² units of the
/// best subsample cost (25: a 5-standard-error gap along one direction).
pub const POLISH_CHI2: f64 = 25.0;

/// How the lobes/effects of the fit are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EffectsChoice {
    /// Inspect the data's geometry ([`choose_effects`]).
    Auto,
    /// Every lobe and effect.
    All,
    /// Exactly these (from `--lobes/--no-glints/--no-eccentricity`).
    Explicit(Effects),
}

/// Optional global stage between the multi-start and the polish.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Global {
    #[default]
    None,
    /// argmin's Nelder–Mead on the subsample cost, from the best multi-start point.
    NelderMead,
    /// argmin's particle swarm on the subsample cost over the start box (seeded).
    Pso,
}

impl std::str::FromStr for Global {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "none" => Ok(Global::None),
            "nelder-mead" | "neldermead" | "nm" => Ok(Global::NelderMead),
            "pso" => Ok(Global::Pso),
            other => Err(Error::Other(format!(
                "unknown global stage `{other}`: use none, pso or nelder-mead"
            ))),
        }
    }
}

/// Everything a fit needs besides the data.
#[derive(Debug, Clone)]
pub struct FitOptions {
    pub space: Space,
    pub loss: Loss,
    /// Robust-loss scale C (in normalised residual units).
    pub loss_scale: f64,
    /// Number of multi-start points.
    pub starts: usize,
    pub seed: u64,
    pub global: Global,
    /// `--fix NAME=VALUE` (MODEL.md JSON names, degrees for `*_deg`).
    pub fix: Vec<String>,
    /// `--free eta`.
    pub free_eta: bool,
    pub effects: EffectsChoice,
    pub mode: RootMode,
    /// What the values are: `scale·S`, or radiance `scale·S·cos θ_i`.
    pub measurement: Measurement,
    /// Samples used by the multi-start stage (all when the data has fewer).
    pub subsample: usize,
    /// How many of the best multi-start results are polished on all data.
    pub polish: usize,
    /// LM iteration (trial step) limits of a start and of a polish run.
    pub start_iters: u64,
    pub polish_iters: u64,
    /// Set (e.g. by Ctrl-C) to stop at the next iteration and keep the best so far.
    pub cancel: Option<Arc<AtomicBool>>,
    /// Show a progress bar on a terminal.
    pub progress: bool,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            space: Space::Log,
            loss: Loss::L2,
            loss_scale: 1.0,
            starts: 16,
            seed: 1,
            global: Global::None,
            fix: Vec::new(),
            free_eta: false,
            effects: EffectsChoice::Auto,
            mode: RootMode::Cubic,
            measurement: Measurement::S,
            subsample: 2000,
            polish: 2,
            start_iters: 40,
            polish_iters: 300,
            cancel: None,
            progress: false,
        }
    }
}

/// Samples of a loaded [`Dataset`].
pub fn fit_data(ds: &Dataset) -> FitData {
    let angles = (0..ds.len())
        .map(|i| crate::model::Angles {
            theta_i: ds.theta_i[i],
            phi_i: ds.phi_i[i],
            theta_r: ds.theta_r[i],
            phi_r: ds.phi_r[i],
        })
        .collect();
    FitData {
        channels: ds.channels.clone(),
        angles,
        values: ds.radiance.clone(),
        sigma: ds.sigma.clone(),
        weight: ds.weight.clone(),
        line: ds.source_line.clone(),
    }
}

/// Every parameter name in output order for `nc` channels.
pub fn all_parameters(nc: usize) -> Vec<ParamName> {
    let mut v = vec![ParamName::Eta];
    v.extend((0..nc).map(ParamName::SigmaA));
    v.extend([
        ParamName::AlphaR,
        ParamName::BetaR,
        ParamName::KG,
        ParamName::WC,
        ParamName::Eccentricity,
        ParamName::DeltaEtaPrime,
        ParamName::DeltaHM,
    ]);
    v
}

/// Parse `--fix NAME=VALUE` items into natural-unit values (`sigma_a=v` fixes every channel).
pub fn parse_fixes(items: &[String], nc: usize) -> Result<Vec<(ParamName, f64)>> {
    let mut out = Vec::new();
    for item in items {
        let (name, value) = item.split_once('=').ok_or_else(|| {
            Error::Other(format!(
                "--fix `{item}`: write NAME=VALUE, e.g. --fix eccentricity=1 or --fix alpha_r_deg=-7"
            ))
        })?;
        let name = name.trim();
        let v: f64 = value.trim().parse().map_err(|_| {
            Error::Other(format!(
                "--fix `{item}`: `{}` is not a number",
                value.trim()
            ))
        })?;
        let names: Vec<ParamName> = if name == "sigma_a" {
            (0..nc).map(ParamName::SigmaA).collect()
        } else {
            match all_parameters(nc)
                .into_iter()
                .find(|p| p.json_name() == name)
            {
                Some(p) => vec![p],
                None => {
                    let known: Vec<String> =
                        all_parameters(nc).iter().map(|p| p.json_name()).collect();
                    return Err(Error::Other(format!(
                        "--fix `{item}`: unknown parameter `{name}`; use one of sigma_a, {}",
                        known.join(", ")
                    )));
                }
            }
        };
        for p in names {
            let x = v / report_factor(p);
            let b = Bound::of(p);
            if !v.is_finite() || b.clamp(x) != x {
                return Err(Error::Parameter {
                    name: p.json_name(),
                    value: v,
                    message: format!("--fix value is outside the valid range {}", bound_text(p)),
                });
            }
            out.push((p, x));
        }
    }
    Ok(out)
}

/// The valid range of `p` in reporting units, for messages.
fn bound_text(p: ParamName) -> String {
    let f = report_factor(p);
    match Bound::of(p) {
        Bound::Free => "(-inf, inf)".into(),
        Bound::Lower(lo) => format!("[{}, inf)", lo * f),
        Bound::Both(lo, hi) => format!("[{}, {}]", lo * f, hi * f),
    }
}

/// Per-stage solver record (fit.json `trace`).
#[derive(Debug, Clone, Serialize)]
pub struct StageTrace {
    pub stage: String,
    pub iterations: u64,
    pub cost: f64,
    pub wall_s: f64,
    /// Cost per iteration of the run that won this stage.
    pub history: Vec<f64>,
}

/// The result of [`fit`], ready to write.
#[derive(Debug, Clone)]
pub struct FitOutcome {
    pub json: FitJson,
    pub params: Params<f64>,
    pub curves: Vec<CurveRow>,
}

/// The model's parameters that a fit under `effects` varies (before `--fix`).
pub fn free_parameters(effects: &Effects, nc: usize, free_eta: bool) -> Vec<ParamName> {
    effects
        .parameters(nc)
        .into_iter()
        .filter(|p| match p {
            ParamName::Eta => free_eta,
            ParamName::DeltaEtaPrime | ParamName::DeltaHM => false,
            _ => true,
        })
        .collect()
}

/// Fit `data` (from file `file`, loader report `load_report`) with `opts`.
pub fn fit(
    data: &FitData,
    file: &str,
    load_report: serde_json::Value,
    opts: &FitOptions,
) -> Result<FitOutcome> {
    let t0 = Instant::now();
    let nc = data.n_channels();
    if data.is_empty() || nc == 0 {
        return Err(Error::Other(format!(
            "{file}: no samples to fit (check the loader report)"
        )));
    }
    let mut warnings = Vec::new();

    // Effects.
    let (effects, effects_choice, reasons) = match opts.effects {
        EffectsChoice::Auto => {
            let c = choose_effects(data, opts.mode);
            (c.effects, "auto", c.reasons)
        }
        EffectsChoice::All => (Effects::default(), "all", vec!["--effects all".into()]),
        EffectsChoice::Explicit(e) => (
            e,
            "explicit",
            vec!["--lobes/--no-glints/--no-eccentricity".into()],
        ),
    };
    let config = ModelConfig {
        mode: opts.mode,
        effects,
    };
    let forward = ModelForward {
        config,
        measurement: opts.measurement,
    };

    // Free parameters and the base (fixed) values.
    let fixes = parse_fixes(&opts.fix, nc)?;
    let mut base = bounds::reference_params(nc);
    for &(p, x) in &fixes {
        base.set(p, x);
    }
    let free: Vec<ParamName> = free_parameters(&effects, nc, opts.free_eta)
        .into_iter()
        .filter(|p| !fixes.iter().any(|(f, _)| f == p))
        .collect();
    for p in free_parameters(&Effects::default(), nc, opts.free_eta) {
        if !effects.parameters(nc).contains(&p) && !fixes.iter().any(|(f, _)| *f == p) {
            warnings.push(format!(
                "{}: not fitted (the effects in play do not depend on it; see options.effects_reasons)",
                p.json_name()
            ));
        }
    }

    // Evaluators on all data and on the multi-start subsample.
    let (ev_full, floored) = Evaluator::new(
        &forward,
        data,
        opts.space,
        opts.loss,
        opts.loss_scale,
        base.clone(),
        free.clone(),
    )?;
    for (c, &k) in floored.count.iter().enumerate() {
        if k > 0 {
            warnings.push(format!(
                "channel {}: {k} value(s) not significantly positive (<= 0, or below {} sigma) cannot be logged; they are fitted as linear residuals (y - s*S)/sigma{} inside the log-space fit. Consider --space linear",
                data.channels[c],
                problem::LOG_MIN_SNR,
                if data.sigma.is_some() {
                    String::new()
                } else {
                    format!(" with sigma = {:.4e} (half the smallest positive value)", floored.floor[c])
                }
            ));
        }
    }
    let sub_idx = design::subsample(
        data.len(),
        opts.subsample.max(1),
        opts.seed ^ 0x5b5b_0000_0001,
    );
    let sub_data = data.subset(&sub_idx);
    let (ev_sub, _) = Evaluator::new(
        &forward,
        &sub_data,
        opts.space,
        opts.loss,
        opts.loss_scale,
        base.clone(),
        free.clone(),
    )?;

    // Start design in natural units, then internal (+ explicit log-scales from the projection).
    let ranges: Vec<(f64, f64)> = free.iter().map(|&p| typical_range(p)).collect();
    let starts = design::latin_hypercube(opts.starts.max(1), &ranges, opts.seed);
    let to_u = |ev: &Evaluator<'_, ModelForward>, x: &[f64]| -> Vec<f64> {
        let mut u = ev.internal(x);
        if ev.explicit_scale {
            let ones = vec![1.0; x.len()];
            let e = ev.evaluate(x, &ones, ScaleMode::Projected, false);
            u.extend(e.scale.iter().map(|s| s.max(1e-300).ln()));
        }
        u
    };
    let bar = progress_bar(opts, opts.starts.max(1) + opts.polish.max(1));

    let mut trace = Vec::new();
    let ts = Instant::now();
    let runs: Vec<LocalRun> = starts
        .par_iter()
        .map(|x0| {
            // After Ctrl-C, starts not yet begun are skipped rather than initialised on the data
            // (each costs a Jacobian evaluation before it would see the flag).
            if is_cancelled(&opts.cancel) {
                let mut u = ev_sub.internal(x0);
                u.resize(ev_sub.n_params(), 0.0);
                return LocalRun {
                    u,
                    cost: f64::INFINITY,
                    iterations: 0,
                    history: Vec::new(),
                    status: RunStatus::Interrupted,
                    wall_s: 0.0,
                };
            }
            let r = run_local(&ev_sub, &to_u(&ev_sub, x0), opts.start_iters, &opts.cancel);
            bar.inc(1);
            r
        })
        .collect();
    let mut order: Vec<usize> = (0..runs.len()).collect();
    order.sort_by(|&a, &b| runs[a].cost.total_cmp(&runs[b].cost).then(a.cmp(&b)));
    trace.push(StageTrace {
        stage: "multistart".into(),
        iterations: runs.iter().map(|r| r.iterations).sum(),
        cost: runs[order[0]].cost,
        wall_s: ts.elapsed().as_secs_f64(),
        history: runs[order[0]].history.clone(),
    });
    // The best few *distinct* minima: starts that reached the same point (within 1e-3 of every
    // typical range) are polished once, so the full-data stage is not spent twice on one basin.
    let mut candidates: Vec<Vec<f64>> = Vec::new();
    let mut chosen_x: Vec<Vec<f64>> = Vec::new();
    for &k in &order {
        if candidates.len() >= opts.polish.max(1) {
            break;
        }
        let x = ev_sub.natural(&runs[k].u[..free.len()]);
        let same = chosen_x.iter().any(|y| {
            x.iter()
                .zip(y)
                .zip(&ranges)
                .all(|((a, b), (lo, hi))| (a - b).abs() <= 1e-3 * (hi - lo))
        });
        // A runner-up whose subsample cost is worse by more than POLISH_CHI2 χ² units would
        // need that much improvement from data it has not seen: skip its full-data polish.
        let best_cost = runs[order[0]].cost;
        let dof_sub = ev_sub
            .n_residuals()
            .saturating_sub(ev_sub.n_params())
            .max(1) as f64;
        let far = best_cost > 0.0 && (runs[k].cost - best_cost) * dof_sub / best_cost > POLISH_CHI2;
        if !same && (!far || candidates.is_empty()) {
            chosen_x.push(x);
            candidates.push(runs[k].u.clone());
        }
    }

    if opts.global == Global::NelderMead && !is_cancelled(&opts.cancel) {
        let tg = Instant::now();
        let (u, cost, iters, history) =
            solve::nelder_mead(&ev_sub, &candidates[0], 200 * free.len() as u64);
        trace.push(StageTrace {
            stage: "global-nelder-mead".into(),
            iterations: iters,
            cost,
            wall_s: tg.elapsed().as_secs_f64(),
            history,
        });
        candidates.insert(0, u);
    }
    if opts.global == Global::Pso && !is_cancelled(&opts.cancel) {
        let tg = Instant::now();
        // The swarm's box is the start design's box in internal coordinates (plus ±3 in ln s
        // around the projected scale when the scale is explicit).
        let lo_x: Vec<f64> = ranges.iter().map(|r| r.0).collect();
        let hi_x: Vec<f64> = ranges.iter().map(|r| r.1).collect();
        let (mut lo, mut hi) = (ev_sub.internal(&lo_x), ev_sub.internal(&hi_x));
        for (a, b) in lo.iter_mut().zip(hi.iter_mut()) {
            if a > b {
                std::mem::swap(a, b);
            }
        }
        if ev_sub.explicit_scale {
            let mid: Vec<f64> = lo_x.iter().zip(&hi_x).map(|(a, b)| 0.5 * (a + b)).collect();
            for ls in to_u(&ev_sub, &mid)[free.len()..].iter() {
                lo.push(ls - 3.0);
                hi.push(ls + 3.0);
            }
        }
        let (u, cost, iters, history) = solve::particle_swarm(&ev_sub, &lo, &hi, 24, 60, opts.seed);
        trace.push(StageTrace {
            stage: "global-pso".into(),
            iterations: iters,
            cost,
            wall_s: tg.elapsed().as_secs_f64(),
            history,
        });
        candidates.insert(0, u);
    }

    // Polish on all data; keep the best.
    let tp = Instant::now();
    let mut best: Option<LocalRun> = None;
    let mut polish_iters = 0;
    for u0 in &candidates {
        if is_cancelled(&opts.cancel) && best.is_some() {
            break;
        }
        let r = run_local(&ev_full, u0, opts.polish_iters, &opts.cancel);
        polish_iters += r.iterations;
        bar.inc(1);
        if best.as_ref().is_none_or(|b| r.cost < b.cost) {
            best = Some(r);
        }
    }
    bar.finish_and_clear();
    let best = best.expect("at least one candidate is polished");
    trace.push(StageTrace {
        stage: "polish".into(),
        iterations: polish_iters,
        cost: best.cost,
        wall_s: tp.elapsed().as_secs_f64(),
        history: best.history.clone(),
    });
    // An infinite cost (e.g. linear-space residuals of values near 1e300 overflow when squared)
    // means no step was ever accepted: say so instead of reporting the start as converged.
    let overflowed = !best.cost.is_finite();
    if overflowed {
        let big = data.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        warnings.push(format!(
            "the cost is not finite at any point tried ({} space, largest |value| {big:.3e}): the residuals overflow, so the parameters are the start values, not a fit; use --space log or rescale the data",
            opts.space
        ));
    }
    let status = if is_cancelled(&opts.cancel) {
        RunStatus::Interrupted
    } else if overflowed {
        RunStatus::Failed
    } else {
        best.status
    };

    let options = serde_json::json!({
        "space": opts.space,
        "loss": opts.loss,
        "loss_scale": opts.loss_scale,
        "starts": opts.starts,
        "seed": opts.seed,
        "global": opts.global,
        "subsample": sub_idx.len(),
        "polish": opts.polish,
        "start_iters": opts.start_iters,
        "polish_iters": opts.polish_iters,
        "mode": opts.mode,
        "measurement": opts.measurement,
        "fixed": fixes.iter().map(|(p, x)| (p.json_name(), serde_json::json!(x * report_factor(*p)))).collect::<serde_json::Map<_, _>>(),
        "freed": if opts.free_eta { vec!["eta"] } else { vec![] },
        "free_parameters": free.iter().map(|p| p.json_name()).collect::<Vec<_>>(),
        "effects_choice": effects_choice,
        "effects_reasons": reasons,
        "scale": if ev_full.explicit_scale { "explicit (robust loss)" } else { "variable projection" },
        "log_floored": floored,
    });
    output::assemble(output::Assembly {
        data,
        file,
        load_report,
        config,
        ev: &ev_full,
        u: &best.u,
        status,
        options,
        warnings,
        trace,
        started: t0,
    })
}

/// A progress bar on stderr when asked for (indicatif hides it when stderr is not a terminal).
fn progress_bar(opts: &FitOptions, len: usize) -> indicatif::ProgressBar {
    if !opts.progress {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("fit {bar:30} {pos}/{len} runs {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

/// `get` re-exported for callers that index parameters by name.
pub fn param(p: &Params<f64>, name: ParamName) -> f64 {
    p.get(name)
}
