//! The fit (`hairfit fit`, `hairfit demo`): least squares of a model family (each one type
//! behind [`family::FamilyFit`]) to samples, with
//! exact AD Jacobians, bounds by smooth transforms, per-channel scale by variable projection,
//! robust losses, a seeded parallel multi-start, LM polish, and uncertainties in natural units.
//!
//! Pipeline ([`fit`], its stages in [`stages`]): choose effects → free parameters →
//! Latin-hypercube starts → short LM runs on a subsample (parallel over starts) → optional
//! global stage → LM polish of the best few on all data → covariance, warnings, residual
//! statistics, curves and the assessment of the optimum ([`assemble`], a draft) → profile
//! intervals ([`profile`]) → the verdict, decided once ([`verdict::decide`], in
//! [`assemble::FitDraft::finish`]). The result is typed ([`FitOutcome`], formats from
//! [`crate::files`]) and not edited after: the caller writes it and hands it to the report.

pub mod assemble;
pub mod bounds;
pub mod design;
pub mod diagnostics;
pub mod evidence;
pub mod family;
pub mod fixes;
pub mod gof;
pub mod loss;
pub mod problem;
pub mod profile;
pub mod registry;
pub mod scan_design;
pub mod solve;
pub mod stages;
pub mod suggest;
pub mod verdict;

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

pub use diagnostics::POORLY_DETERMINED;
pub use family::FitInput;
pub use loss::{Loss, LossScale};
pub use problem::{Evaluator, FitData, FitParam, Forward, ParamSet, ScaleMode, Space};
pub use profile::Intervals;

pub use crate::files::settings::Global;

use crate::data::Dataset;
use crate::error::{Error, Result};
use crate::families::{FamilyParams, ModelFamily, ModelSetup};
use crate::files::{Curves, CurvesMode, FitJson, FitStatus, Floored, OptionsRecord, Timing};
use crate::geometry::Measurement;

/// Runner-ups of the multi-start are polished on all data only within this many χ² units of the
/// best subsample cost (25: a 5-standard-error gap along one direction).
pub const POLISH_CHI2: f64 = 25.0;

/// The screening subsample (when candidates compete before the full-data polish) is this many
/// times the multi-start's subsample; screening runs only on data over four times its size.
pub const SCREEN_FACTOR: usize = 25;

/// From this many rows (samples × channels) the polish on all data computes the gradients with
/// every trial step's values: it starts at the multi-start's optimum, so its steps are nearly
/// always accepted and linearised where they were tried, and the separate value pass (a fifth of
/// a Marschner gradient pass) is saved twice. Below it a rejected step's gradients would cost
/// more than the value passes save; above the memo's budget (a few hundred thousand rows) the
/// pass is not kept and each trial runs as before.
pub const FUSED_POLISH_MIN_ROWS: usize = 50_000;

/// Above this many rows (samples × channels) an interrupted fit writes the summary curves.
pub const INTERRUPTED_FULL_CURVES_ROWS: usize = 300_000;

/// `--curves auto` writes every row up to this many rows (samples × channels; ~240 MB of
/// curves.csv) and the summary above: a million-sample capture's full table is larger than its
/// data and takes longer to write than the fit takes.
pub const AUTO_FULL_CURVES_ROWS: usize = 1_000_000;

/// How the lobes/effects of the fit are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EffectsChoice {
    /// Inspect the data's geometry ([`choose_effects`]).
    Auto,
    /// Every lobe and effect.
    All,
    /// Exactly those of the family's configuration ([`FitOptions::model`], from
    /// `--lobes/--no-glints/--no-eccentricity`).
    Explicit,
}

/// Everything a fit needs besides the data.
#[derive(Debug, Clone)]
pub struct FitOptions {
    pub space: Space,
    pub loss: Loss,
    /// Robust-loss scale C (normalised residual units), or estimated from the residuals.
    pub loss_scale: LossScale,
    /// Number of multi-start points (the most run).
    pub starts: usize,
    /// The multi-start runs its starts in batches of this many and stops once every run so far
    /// ended at one point ([`stages::multistart`]); 0 runs every start.
    pub agreeing_starts: usize,
    pub seed: u64,
    pub global: Global,
    /// `--fix NAME=VALUE` (MODEL.md JSON names, degrees for `*_deg`).
    pub fix: Vec<String>,
    /// `--free eta`.
    pub free_eta: bool,
    pub effects: EffectsChoice,
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
    /// Profile-likelihood or linearised intervals (or profile when cheap).
    pub intervals: Intervals,
    /// The model family [`fit_family`] fits (`--model`).
    pub family: ModelFamily,
    /// What the command line configures of the family's model (`--mode`, `--terms`,
    /// `--width-nodes`, …); the fitted family reads its part.
    pub model: ModelSetup,
    /// How much of the curves the fit's directory gets (`--curves`); `None`: auto (full up to
    /// [`AUTO_FULL_CURVES_ROWS`] rows, the summary above).
    pub curves: Option<CurvesMode>,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            space: Space::Log,
            loss: Loss::L2,
            loss_scale: LossScale::Auto,
            starts: 16,
            agreeing_starts: 8,
            seed: 1,
            global: Global::None,
            fix: Vec::new(),
            free_eta: false,
            effects: EffectsChoice::Auto,
            measurement: Measurement::S,
            subsample: 2000,
            polish: 2,
            start_iters: 40,
            polish_iters: 300,
            cancel: None,
            progress: false,
            intervals: Intervals::Auto,
            family: ModelFamily::default(),
            model: ModelSetup::default(),
            curves: None,
        }
    }
}

/// Samples of a loaded [`Dataset`].
pub fn fit_data(ds: &Dataset) -> FitData {
    into_fit_data(ds.clone())
}

/// [`fit_data`] that takes the dataset, so its values are moved rather than copied (a million
/// samples × 3 channels hold ~100 MB that would otherwise live twice through the fit).
pub fn into_fit_data(ds: Dataset) -> FitData {
    let angles = angles_of(&ds);
    FitData {
        channels: ds.channels,
        angles,
        values: ds.radiance,
        sigma: ds.sigma,
        weight: ds.weight,
        line: ds.source_line,
    }
}

fn angles_of(ds: &Dataset) -> Vec<crate::geometry::Angles> {
    (0..ds.len())
        .map(|i| crate::geometry::Angles {
            theta_i: ds.theta_i[i],
            phi_i: ds.phi_i[i],
            theta_r: ds.theta_r[i],
            phi_r: ds.phi_r[i],
        })
        .collect()
}

/// A fit whose every row lies within this relative distance of the data (below 1e-9 of the
/// channel's peak, within this share of 1e-9·peak) reproduces them to rounding, not noise: float32
/// text rounds at 6e-8, Chiang's width quadrature at 1e-7 (so a fit with η free lands ~1e-9 from
/// data its own defaults made), while no camera or Monte Carlo estimate comes within 1e-5. The
/// verdict is then `good` and there is no statistical interval.
pub const EXACT_MISFIT: f64 = 1e-6;

/// The result of a fit: fit.json's content, the parameters (`P`: the family's parameter set,
/// or a parameter file of any family from `registry::fit_family`), the curves curves.csv gets (all
/// rows, the summary's, or none, as fit.json's `options.curves` says) and the run's wall-clock
/// times (timing.json).
#[derive(Debug, Clone)]
pub struct FitOutcome<P> {
    pub json: FitJson,
    pub params: P,
    pub curves: Curves,
    pub timing: Timing,
    /// ‖fit − data‖ / ‖data‖ over every row (NaN when a value is missing): near rounding for
    /// noise-free data.
    pub relative_misfit: f64,
    /// The largest row's |fit − data| / max(|data|, 1e-9 · its channel's peak) (NaN when a
    /// value is missing): at most [`EXACT_MISFIT`] when the model reproduces the data.
    pub worst_row_misfit: f64,
    /// The scan slices of `curves`' samples when the verdict found them on the same samples
    /// (full curves): the report draws them without searching again.
    pub curve_slices: Option<Arc<crate::slices::FoundSlices>>,
}

impl<P> FitOutcome<P> {
    /// The same outcome with its parameters mapped by `f`.
    pub fn map_params<Q>(self, f: impl FnOnce(&P) -> Q) -> FitOutcome<Q> {
        FitOutcome {
            params: f(&self.params),
            json: self.json,
            curves: self.curves,
            timing: self.timing,
            relative_misfit: self.relative_misfit,
            worst_row_misfit: self.worst_row_misfit,
            curve_slices: self.curve_slices,
        }
    }
}

/// Write the outcome's files into `dir` (fit.json, params.json, curves.csv as fit.json's
/// `options.curves` asks, timing.json).
pub fn write_outputs<P>(dir: &Path, out: &FitOutcome<P>) -> Result<()> {
    crate::files::write_fit_dir(dir, &out.json, written_curves(out).as_deref(), &out.timing)
}

/// The curves `curves.csv` gets under fit.json's `options.curves`: the outcome's (all rows, or
/// the summary's rows the fit built), or none.
pub fn written_curves<P>(out: &FitOutcome<P>) -> Option<std::borrow::Cow<'_, Curves>> {
    match out.json.options.curves {
        CurvesMode::Full | CurvesMode::Summary => Some(std::borrow::Cow::Borrowed(&out.curves)),
        CurvesMode::None => None,
    }
}

/// The number of channels of `data`, or an error when there is nothing to fit.
pub fn require_samples(data: &FitData, file: &str) -> Result<usize> {
    let nc = data.n_channels();
    if data.is_empty() || nc == 0 {
        return Err(Error::Other(format!(
            "{file}: no samples to fit (check the loader report)"
        )));
    }
    Ok(nc)
}

/// The options record of a run from the multi-start's subsample size, whether the scale is
/// explicit, and the floored values.
pub type OptionsOf<'a> = &'a dyn Fn(usize, bool, Floored) -> OptionsRecord;

/// One family's fit, as [`fit_with`] runs it through the shared stages.
pub struct FitRun<'a, F: Forward> {
    /// The samples, their file and loader report, the options and the start time.
    pub input: FitInput<'a>,
    pub forward: &'a F,
    /// A cheaper forward for the multi-start stages on the subsample, which only look for basins
    /// (the polish, intervals and everything reported use `forward`); None: `forward`.
    pub screening: Option<&'a F>,
    /// Fixed values (and start values of the free ones).
    pub base: ParamSet<F>,
    pub free: Vec<F::Param>,
    pub options: OptionsOf<'a>,
    /// What fit.json records of the family's configuration.
    pub records: crate::families::ModelRecords,
    pub all: Vec<F::Param>,
    pub why: assemble::WhyUndetermined<'a, F::Param>,
    pub params_file: fn(&ParamSet<F>) -> FamilyParams,
}

/// The stages every family's fit runs: multi-start on a subsample, optional global stage,
/// polish on all data, then the typed result.
pub fn fit_with<F: Forward>(
    run: FitRun<'_, F>,
    mut warnings: Vec<String>,
) -> Result<FitOutcome<ParamSet<F>>> {
    let FitInput { data, opts, .. } = run.input;
    let forward = run.forward;
    let screening = run.screening.unwrap_or(forward);
    let (mut ev_full, floored) =
        evaluator_for(forward, data, opts.space, opts.loss, &run.base, &run.free)?;
    stages::warn_floored(data, &floored, &mut warnings);
    let sub_idx = design::subsample(
        data.len(),
        opts.subsample.max(1),
        opts.seed ^ 0x5b5b_0000_0001,
    );
    let sub_data = data.subset(&sub_idx);
    let (mut ev_sub, _) = evaluator_for(
        screening, &sub_data, opts.space, opts.loss, &run.base, &run.free,
    )?;

    let ranges: Vec<(f64, f64)> = run.free.iter().map(|&p| p.typical_range()).collect();
    let mut starts = design::latin_hypercube(opts.starts.max(1), &ranges, opts.seed);
    let auto_scale = opts.loss != Loss::L2 && opts.loss_scale == LossScale::Auto;
    let runs_total = opts.starts.max(1) * if auto_scale { 2 } else { 1 } + opts.polish.max(1);
    let mut log = stages::StageLog::new(stages::progress_bar(opts, runs_total));
    // The loss scale: given, or the tuning constant times the noise level of a least-squares
    // multi-start's residuals (MAD, so the outliers a robust loss is for barely move it).
    let loss_scale = match opts.loss_scale {
        LossScale::Fixed(c) => c,
        LossScale::Auto if !auto_scale => 1.0,
        LossScale::Auto => {
            let (ev_l2, _) = evaluator_for(
                screening,
                &sub_data,
                opts.space,
                Loss::L2,
                &run.base,
                &run.free,
            )?;
            let (runs, order) =
                stages::multistart("loss-scale-l2", &ev_l2, &starts, opts, &mut log);
            let e = ev_l2.eval_internal(&runs[order[0]].u, false);
            // Its best point also starts the robust multi-start, first (outliers bias it, but it
            // lies in the right basin far more often than a design point).
            starts.insert(0, ev_l2.natural(&runs[order[0]].u[..run.free.len()]));
            loss::noise_mad(&e.raw).map_or(1.0, |s| opts.loss.tuning() * s)
        }
    };
    ev_full.loss_scale = loss_scale;
    ev_full.gradients_with_values = data.len() * data.n_channels() >= FUSED_POLISH_MIN_ROWS;
    ev_sub.loss_scale = loss_scale;
    let (runs, order) = stages::multistart("multistart", &ev_sub, &starts, opts, &mut log);
    let mut candidates = stages::distinct_candidates(&ev_sub, &runs, &order, &ranges, opts.polish);
    stages::global_stage(&ev_sub, &mut candidates, &ranges, opts, &mut log);
    // Large data: the candidates compete on a screening subsample and only the winner is
    // polished on all data (a full-data LM run costs seconds per million samples).
    let screen_size = SCREEN_FACTOR * opts.subsample.max(1);
    if candidates.len() > 1 && data.len() > 4 * screen_size {
        let idx = design::subsample(data.len(), screen_size, opts.seed ^ 0x5b5b_0000_0002);
        let screen_data = data.subset(&idx);
        let (mut ev_screen, _) = evaluator_for(
            forward,
            &screen_data,
            opts.space,
            opts.loss,
            &run.base,
            &run.free,
        )?;
        ev_screen.loss_scale = loss_scale;
        candidates = vec![stages::screen(&ev_screen, &candidates, opts, &mut log)];
    }
    let mut best = stages::polish(&ev_full, &candidates, opts, &mut log);
    if auto_scale {
        // Refine once from the robust fit's own residuals (outliers no longer bias the shape).
        best = stages::rescale_loss(&mut ev_full, best, opts, &mut log);
    }
    let status = stages::final_status(&best, data, opts, &mut warnings);

    let mut options = (run.options)(sub_idx.len(), ev_full.explicit_scale, floored);
    options.loss_scale = ev_full.loss_scale;
    options.starts_run = Some(runs.len());
    // After Ctrl-C the user wants the best parameters now: a large fit writes the summary
    // curves (what the report draws) instead of spending seconds per million rows on the rest.
    let rows = data.len() * data.n_channels();
    if opts.curves.is_none() && rows > AUTO_FULL_CURVES_ROWS {
        options.curves = CurvesMode::Summary;
        options.curves_reason = format!(
            "auto: {rows} rows (samples × channels) > {AUTO_FULL_CURVES_ROWS}; --curves full writes every row"
        );
    }
    if status == FitStatus::Interrupted
        && options.curves == CurvesMode::Full
        && rows > INTERRUPTED_FULL_CURVES_ROWS
    {
        options.curves = CurvesMode::Summary;
        warnings.push(format!(
            "interrupted: curves.csv holds the summary rows only ({rows} rows in full); rerun to completion for all of them"
        ));
    }
    let x_best = ev_full.natural(&best.u[..run.free.len()]);
    let draft = assemble::assemble(assemble::Assembly {
        data,
        file: run.input.file,
        load_report: run.input.load_report,
        records: run.records,
        all: run.all,
        why: run.why,
        params_file: run.params_file,
        ev: &ev_full,
        u: &best.u,
        status,
        options,
        warnings,
        trace: log.trace,
        stage_times: log.times,
        started: run.input.started,
    })?;
    let optimum = profile::Optimum {
        forward,
        data,
        space: opts.space,
        loss: opts.loss,
        loss_scale: ev_full.loss_scale,
        params: ev_full.params_at(&x_best),
        free: run.free.clone(),
        u: best.u.clone(),
        cost: best.cost,
        chi2_unit: 0.0,
        dof: 0,
        max_iters: opts.polish_iters,
        cancel: opts.cancel.clone(),
    };
    let intervals = profile::intervals(&draft.outcome, &draft.assessment, optimum, &best, opts)?;
    Ok(draft.finish(data, intervals, run.input.started))
}

/// An evaluator of `d` with the run's fixed values and free parameters (loss scale 1 until the
/// run sets it); a function rather than a closure so each call borrows its own data.
fn evaluator_for<'e, F: Forward>(
    forward: &'e F,
    d: &'e FitData,
    space: Space,
    loss: Loss,
    base: &ParamSet<F>,
    free: &[F::Param],
) -> Result<(Evaluator<'e, F>, Floored)> {
    Evaluator::new(forward, d, space, loss, 1.0, base.clone(), free.to_vec())
}
