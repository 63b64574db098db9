//! The named stages of [`super::fit`]: choose the model's effects, choose the free parameters,
//! the seeded multi-start on a subsample, the optional global stage, the polish on all data,
//! the final status, and the record of the options used.

use std::time::Instant;

use rayon::prelude::*;

pub use super::fixes::FreeSet;
use super::problem::{self, Evaluator, FitData, FitParam, Forward};
use super::solve::{self, is_cancelled, run_local, LocalRun};
use super::{FitOptions, Global};
use crate::files::{
    EffectsSource, FitStatus, Floored, OptionsRecord, ScaleMethod, StageTiming, TraceStage,
};

/// How the family's effects or terms were chosen and why (fit.json `options.effects_choice`
/// and `effects_reasons`).
pub struct ModelChoice {
    pub effects_choice: EffectsSource,
    pub reasons: Vec<String>,
}

/// Warn about values a log-space fit takes as linear residuals.
pub fn warn_floored(data: &FitData, floored: &Floored, warnings: &mut Vec<String>) {
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
}

/// The solver stages run so far: fit.json's `trace` and timing.json's wall times, and the
/// progress bar the runs tick.
pub struct StageLog {
    pub trace: Vec<TraceStage>,
    pub times: Vec<StageTiming>,
    pub bar: indicatif::ProgressBar,
}

impl StageLog {
    /// An empty log ticking `bar`.
    pub fn new(bar: indicatif::ProgressBar) -> StageLog {
        StageLog {
            trace: Vec::new(),
            times: Vec::new(),
            bar,
        }
    }

    /// Record a finished stage.
    pub fn record(
        &mut self,
        stage: &str,
        iterations: u64,
        cost: f64,
        started: Instant,
        history: Vec<f64>,
    ) {
        self.trace.push(TraceStage {
            stage: stage.into(),
            iterations,
            cost: crate::files::finite(cost),
            history,
        });
        self.times.push(StageTiming {
            stage: stage.into(),
            wall_s: started.elapsed().as_secs_f64(),
        });
    }
}

/// Internal solver coordinates of natural point `x` (plus the explicit log-scales, started at
/// the median of ln(y/S), when the scale is explicit).
fn to_internal<F: Forward>(ev: &Evaluator<'_, F>, x: &[f64]) -> Vec<f64> {
    let mut u = ev.internal(x);
    if ev.explicit_scale {
        // The median, not the projected mean: a robust loss's outliers drag the mean.
        u.extend(ev.median_log_scale(x));
    }
    u
}

/// Short LM runs from the starts on the subsample (parallel), recorded as stage `stage`;
/// returns the runs and their order by cost. The starts run in batches of
/// [`FitOptions::agreeing_starts`] in design order, and the stage ends after a batch once every
/// run so far ended at the best point ([`same_point`]): on a landscape where that many starts
/// from across the design box all fall into one basin, the rest would land there too (each of
/// the demos' 16 starts does). Any disagreement runs the whole design.
pub fn multistart<F: Forward>(
    stage: &str,
    ev_sub: &Evaluator<'_, F>,
    starts: &[Vec<f64>],
    opts: &FitOptions,
    log: &mut StageLog,
) -> (Vec<LocalRun>, Vec<usize>) {
    let ts = Instant::now();
    let bar = &log.bar;
    let batch = match opts.agreeing_starts {
        0 => starts.len(),
        k => k,
    };
    let ranges: Vec<(f64, f64)> = ev_sub.free.iter().map(|p| p.typical_range()).collect();
    let mut runs: Vec<LocalRun> = Vec::with_capacity(starts.len());
    for chunk in starts.chunks(batch.max(1)) {
        runs.par_extend(chunk.par_iter().map(|x0| {
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
                    status: FitStatus::Interrupted,
                    wall_s: 0.0,
                };
            }
            let r = run_local(
                ev_sub,
                &to_internal(ev_sub, x0),
                opts.start_iters,
                &opts.cancel,
            );
            bar.inc(1);
            r
        }));
        if runs.len() < starts.len() && all_at_best(ev_sub, &runs, &ranges) {
            bar.inc((starts.len() - runs.len()) as u64);
            break;
        }
    }
    let mut order: Vec<usize> = (0..runs.len()).collect();
    order.sort_by(|&a, &b| runs[a].cost.total_cmp(&runs[b].cost).then(a.cmp(&b)));
    log.record(
        stage,
        runs.iter().map(|r| r.iterations).sum(),
        runs[order[0]].cost,
        ts,
        runs[order[0]].history.clone(),
    );
    (runs, order)
}

/// Two natural points within 1e-3 of every typical range of each other: one minimum.
fn same_point(x: &[f64], y: &[f64], ranges: &[(f64, f64)]) -> bool {
    x.iter()
        .zip(y)
        .zip(ranges)
        .all(|((a, b), (lo, hi))| (a - b).abs() <= 1e-3 * (hi - lo))
}

/// True when the best run's cost is finite and every run ended at its point.
fn all_at_best<F: Forward>(
    ev_sub: &Evaluator<'_, F>,
    runs: &[LocalRun],
    ranges: &[(f64, f64)],
) -> bool {
    let nf = ev_sub.free.len();
    let Some(best) = runs.iter().min_by(|a, b| a.cost.total_cmp(&b.cost)) else {
        return false;
    };
    if !best.cost.is_finite() {
        return false;
    }
    let xb = ev_sub.natural(&best.u[..nf]);
    runs.iter()
        .all(|r| r.cost.is_finite() && same_point(&ev_sub.natural(&r.u[..nf]), &xb, ranges))
}

/// The best few *distinct* minima: starts that reached the same point (within 1e-3 of every
/// typical range) are polished once, so the full-data stage is not spent twice on one basin.
pub fn distinct_candidates<F: Forward>(
    ev_sub: &Evaluator<'_, F>,
    runs: &[LocalRun],
    order: &[usize],
    ranges: &[(f64, f64)],
    polish: usize,
) -> Vec<Vec<f64>> {
    let nf = ev_sub.free.len();
    let mut candidates: Vec<Vec<f64>> = Vec::new();
    let mut chosen_x: Vec<Vec<f64>> = Vec::new();
    let best_cost = runs[order[0]].cost;
    let dof_sub = ev_sub
        .n_residuals()
        .saturating_sub(ev_sub.n_params())
        .max(1) as f64;
    for &k in order {
        if candidates.len() >= polish.max(1) {
            break;
        }
        let x = ev_sub.natural(&runs[k].u[..nf]);
        let same = chosen_x.iter().any(|y| same_point(&x, y, ranges));
        // A runner-up whose subsample cost is worse by more than POLISH_CHI2 χ² units would
        // need that much improvement from data it has not seen: skip its full-data polish.
        let far = best_cost > 0.0
            && (runs[k].cost - best_cost) * dof_sub / best_cost > super::POLISH_CHI2;
        if !same && (!far || candidates.is_empty()) {
            chosen_x.push(x);
            candidates.push(runs[k].u.clone());
        }
    }
    candidates
}

/// The optional global stage on the subsample; its result is polished first.
pub fn global_stage<F: Forward>(
    ev_sub: &Evaluator<'_, F>,
    candidates: &mut Vec<Vec<f64>>,
    ranges: &[(f64, f64)],
    opts: &FitOptions,
    log: &mut StageLog,
) {
    if opts.global == Global::None || is_cancelled(&opts.cancel) {
        return;
    }
    let tg = Instant::now();
    let nf = ev_sub.free.len();
    let (stage, (u, cost, iters, history)) = match opts.global {
        Global::NelderMead => (
            "global-nelder-mead",
            solve::nelder_mead(ev_sub, &candidates[0], 200 * nf as u64),
        ),
        _ => {
            // The swarm's box is the start design's box in internal coordinates (plus ±3 in
            // ln s around the projected scale when the scale is explicit).
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
                for ls in to_internal(ev_sub, &mid)[nf..].iter() {
                    lo.push(ls - 3.0);
                    hi.push(ls + 3.0);
                }
            }
            (
                "global-pso",
                solve::particle_swarm(ev_sub, &lo, &hi, 24, 60, opts.seed),
            )
        }
    };
    log.record(stage, iters, cost, tg, history);
    candidates.insert(0, u);
}

/// LM polish of every candidate on `ev_screen` (a subsample far larger than the multi-start's):
/// the best run's end point, the only one then polished on all data.
pub fn screen<F: Forward>(
    ev_screen: &Evaluator<'_, F>,
    candidates: &[Vec<f64>],
    opts: &FitOptions,
    log: &mut StageLog,
) -> Vec<f64> {
    let t = Instant::now();
    let runs: Vec<LocalRun> = candidates
        .iter()
        .map(|u0| run_local(ev_screen, u0, opts.polish_iters, &opts.cancel))
        .collect();
    let iterations = runs.iter().map(|r| r.iterations).sum();
    let best = runs
        .into_iter()
        .min_by(|a, b| a.cost.total_cmp(&b.cost))
        .expect("at least one candidate is screened");
    log.record("screen", iterations, best.cost, t, best.history.clone());
    best.u
}

/// LM polish of every candidate on all data; the best run.
pub fn polish<F: Forward>(
    ev_full: &Evaluator<'_, F>,
    candidates: &[Vec<f64>],
    opts: &FitOptions,
    log: &mut StageLog,
) -> LocalRun {
    let bar = &log.bar;
    let tp = Instant::now();
    let mut best: Option<LocalRun> = None;
    let mut iterations = 0;
    for u0 in candidates {
        if is_cancelled(&opts.cancel) && best.is_some() {
            break;
        }
        let solver = solve::local_solver(solve::residual_dof(ev_full));
        let r = solve::run_lm(
            ev_full,
            u0,
            solver,
            opts.polish_iters,
            &opts.cancel,
            Some(bar),
        );
        iterations += r.iterations;
        bar.inc(1);
        if best.as_ref().is_none_or(|b| r.cost < b.cost) {
            best = Some(r);
        }
    }
    bar.finish_and_clear();
    let best = best.expect("at least one candidate is polished");
    log.record("polish", iterations, best.cost, tp, best.history.clone());
    best
}

/// `--loss-scale auto`, refined: the loss scale from the robust fit's own residuals (tuning
/// constant × 1.4826·MAD), then a polish from `best` with it. Skipped when cancelled or when the
/// scale moves by less than 1%.
pub fn rescale_loss<F: Forward>(
    ev_full: &mut Evaluator<'_, F>,
    best: LocalRun,
    opts: &FitOptions,
    log: &mut StageLog,
) -> LocalRun {
    let e = ev_full.eval_internal(&best.u, false);
    let Some(noise) = super::loss::noise_mad(&e.raw) else {
        return best;
    };
    let c = opts.loss.tuning() * noise;
    if is_cancelled(&opts.cancel) || (c / ev_full.loss_scale - 1.0).abs() < 0.01 {
        return best;
    }
    let tp = Instant::now();
    ev_full.loss_scale = c;
    let r = run_local(ev_full, &best.u, opts.polish_iters, &opts.cancel);
    log.record(
        "polish-rescaled",
        r.iterations,
        r.cost,
        tp,
        r.history.clone(),
    );
    r
}

/// How the fit ended: interrupted, failed (no finite cost anywhere), or as the polish ended.
pub fn final_status(
    best: &LocalRun,
    data: &FitData,
    opts: &FitOptions,
    warnings: &mut Vec<String>,
) -> FitStatus {
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
    if is_cancelled(&opts.cancel) {
        FitStatus::Interrupted
    } else if overflowed {
        FitStatus::Failed
    } else {
        best.status
    }
}

/// fit.json's record of every option the fit used.
pub fn options_record<P: FitParam>(
    opts: &FitOptions,
    choice: &ModelChoice,
    set: &FreeSet<P>,
    subsample: usize,
    explicit_scale: bool,
    floored: Floored,
) -> OptionsRecord {
    OptionsRecord {
        curves: opts.curves.unwrap_or_default(),
        curves_reason: String::new(),
        effects_choice: choice.effects_choice,
        effects_reasons: choice.reasons.clone(),
        fixed: set
            .fixes
            .iter()
            .map(|(p, x)| (p.json_name(), x * p.report_factor()))
            .collect(),
        free_parameters: set.free.iter().map(|p| p.json_name()).collect(),
        freed: if opts.free_eta {
            vec!["eta".into()]
        } else {
            vec![]
        },
        global: opts.global,
        intervals: opts.intervals.to_string(),
        intervals_reason: String::new(),
        load: None,
        log_floored: floored,
        loss: opts.loss,
        loss_scale: match opts.loss_scale {
            super::LossScale::Fixed(c) => c,
            super::LossScale::Auto => 1.0,
        },
        loss_scale_auto: opts.loss_scale == super::LossScale::Auto,
        measurement: opts.measurement,
        mode: opts.model.config.mode,
        polish: opts.polish,
        polish_iters: opts.polish_iters,
        scale: if explicit_scale {
            ScaleMethod::Explicit
        } else {
            ScaleMethod::VariableProjection
        },
        seed: opts.seed,
        space: opts.space,
        start_iters: opts.start_iters,
        starts: opts.starts,
        starts_run: None,
        subsample,
    }
}

/// A progress bar on stderr when asked for (indicatif hides it when stderr is not a terminal).
pub fn progress_bar(opts: &FitOptions, len: usize) -> indicatif::ProgressBar {
    if !opts.progress {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("fit {bar:30} {pos}/{len} runs {elapsed} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}
