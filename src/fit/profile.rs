//! Profile-likelihood intervals (MINOS-style): for each free parameter, pin it at values on each
//! side of the optimum, re-minimise the others with the fit's own LM runner, and find where the
//! cost has risen by Δχ² = 1 (68%) and Δχ² = 3.84 (95%). Unlike the linearised standard error,
//! the profile follows the cost's real shape: curved valleys, trade-offs and bounds.
//!
//! Δχ² is in the units the covariance uses: `Δχ² = 2Δcost/s²` with `s² = 2·cost/dof` at the
//! optimum (the residual variance; with a `sigma` column and a good fit it is ≈ 1), so for a
//! linear problem the 68% interval is exactly `value ± SE`.
//!
//! Each side's first re-fit is at the linearised SE, started on the linearised profile path (the
//! correlations' `∂x_k/∂x_j`), so it settles without a step; where it lands on Δχ² ≈ 1 the 95%
//! end is the local quadratic's, else the next re-fit is aimed at the crossing of the profile's
//! local shape and accepted as it stands when it lands within the crossing tolerance. Crossings
//! not found so are bracketed and refined by regula falsi on `√Δχ²` (`search`). Every later
//! solve starts where the solved points extrapolate to. Parameters run in parallel (rayon);
//! each parameter's sequence of solves is fixed, so results are identical for any thread count.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use rayon::prelude::*;

use super::problem::{FitData, FitParam, Forward, ParamSet, Space};
use super::solve::LocalRun;
use super::verdict::Assessment;
use super::Loss;
use super::{FitOptions, FitOutcome};
use crate::error::{Error, Result};

mod record;
mod search;
use crate::files::{FitStatus, ProfileMethod, StageTiming};
pub use record::apply;
pub use search::{first_steps, profile_parameter, FirstStep};

/// Δχ² of a 68.27% interval for one parameter.
pub const CHI2_68: f64 = 1.0;
/// Δχ² of a 95% interval for one parameter (the χ²₁ quantile).
pub const CHI2_95: f64 = 3.841_458_820_694_124;
/// `--intervals auto` profiles when the estimated cost is at most this many seconds.
pub const AUTO_BUDGET_S: f64 = 10.0;
/// Jacobian entries (residuals × columns) an LM iteration of a fit gets through per second on
/// the 2-core machine, model and AD included: measured 8e6/s on the demo (7020 residuals × 8
/// columns) and 4e6/s on a 360-sample fit (per-solve overhead), taken at the lower end.
const JACOBIAN_ENTRIES_PER_S: f64 = 5e6;
/// Estimated cost of a profile, for `--intervals auto`: solves per side and LM iterations per
/// (warm-started) solve. Measured: the demo (8 well-determined parameters) 3 solves per side,
/// 2 iterations each; `data/azimuthal_1ch_noisy.csv` with cauchy (two undetermined parameters
/// that crawl) 6.4 and 17.6. In between, leaning to the expensive side.
const SOLVES_PER_SIDE: f64 = 5.0;
const ITERS_PER_SOLVE: f64 = 8.0;

/// `--intervals`: profile likelihood, linearised only, or profile when cheap.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Intervals {
    Profile,
    Linear,
    #[default]
    Auto,
}

impl std::str::FromStr for Intervals {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "profile" => Ok(Intervals::Profile),
            "linear" => Ok(Intervals::Linear),
            "auto" => Ok(Intervals::Auto),
            other => Err(Error::Other(format!(
                "--intervals `{other}`: use profile, linear or auto"
            ))),
        }
    }
}

impl std::fmt::Display for Intervals {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Intervals::Profile => "profile",
            Intervals::Linear => "linear",
            Intervals::Auto => "auto",
        })
    }
}

/// Estimated wall time of profiling `n_free` parameters over `n_residuals` residuals with
/// `n_cols` Jacobian columns: LM iterations × Jacobian entries / [`JACOBIAN_ENTRIES_PER_S`].
/// Counted, not timed: the choice (and so fit.json) must not depend on the machine's load.
pub fn estimate_seconds(n_free: usize, n_residuals: usize, n_cols: usize) -> f64 {
    let iterations = n_free as f64 * 2.0 * SOLVES_PER_SIDE * ITERS_PER_SOLVE;
    iterations * n_residuals as f64 * n_cols as f64 / JACOBIAN_ENTRIES_PER_S
}

/// Whether to profile, and why (fit.json `options.intervals_reason`).
pub fn decide(
    choice: Intervals,
    n_free: usize,
    n_residuals: usize,
    n_cols: usize,
) -> (bool, String) {
    match choice {
        Intervals::Profile => (true, "--intervals profile".into()),
        Intervals::Linear => (false, "--intervals linear".into()),
        Intervals::Auto => {
            let est = estimate_seconds(n_free, n_residuals, n_cols);
            let how = format!(
                "estimated {est:.2} s on 2 idle cores: {n_free} parameters × 2 sides × ~{SOLVES_PER_SIDE} LM solves × ~{ITERS_PER_SOLVE} iterations over {n_residuals} residuals × {n_cols} columns"
            );
            if est <= AUTO_BUDGET_S {
                (true, format!("auto: {how} ≤ {AUTO_BUDGET_S} s"))
            } else {
                (
                    false,
                    format!(
                        "auto: {how} > {AUTO_BUDGET_S} s; pass --intervals profile to compute them"
                    ),
                )
            }
        }
    }
}

/// The fit's optimum, where every profile starts.
pub struct Optimum<'a, F: Forward> {
    pub forward: &'a F,
    pub data: &'a FitData,
    pub space: Space,
    pub loss: Loss,
    pub loss_scale: f64,
    /// Every parameter at the optimum (natural units).
    pub params: ParamSet<F>,
    pub free: Vec<F::Param>,
    /// Solver coordinates of the optimum (free parameters, then explicit log-scales).
    pub u: Vec<f64>,
    pub cost: f64,
    /// `s²`: `Δχ² = 2Δcost/s²`.
    pub chi2_unit: f64,
    /// Residual degrees of freedom (prices a χ² unit as a relative cost change).
    pub dof: usize,
    pub max_iters: u64,
    pub cancel: Option<Arc<AtomicBool>>,
}

/// Where one side of an interval ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum End {
    /// The profile crosses the threshold here (natural units).
    Closed(f64),
    /// It stays below up to `at`, with Δχ² = `dchi2` there; `bound` when `at` is the fit bound
    /// (else the search limit).
    Open { at: f64, dchi2: f64, bound: bool },
}

impl End {
    fn value(&self) -> Option<f64> {
        match *self {
            End::Closed(v) => Some(v),
            End::Open { .. } => None,
        }
    }
}

/// One parameter's profile.
#[derive(Debug, Clone)]
pub struct Profile<P> {
    pub name: P,
    /// `(value, Δχ²)` in natural units, ascending in value, the optimum included.
    pub points: Vec<(f64, f64)>,
    /// `[lower, upper]` at Δχ² = 1 and at 3.84.
    pub end_68: [End; 2],
    pub end_95: [End; 2],
    /// LM iterations spent.
    pub iterations: u64,
    /// Re-minimisations run.
    pub solves: usize,
    /// How each side (`[below, above]`) found its ends.
    pub methods: [ProfileMethod; 2],
}

/// Profile every free parameter in parallel (`first[j]`: how parameter `j`'s profile starts).
/// `None` when cancelled: the linearised intervals stand.
pub fn profile_all<F: Forward>(
    opt: &Optimum<'_, F>,
    first: &[FirstStep],
) -> Result<Option<Vec<Profile<F::Param>>>> {
    let none = FirstStep::default();
    let out: Vec<Result<Option<Profile<F::Param>>>> = (0..opt.free.len())
        .into_par_iter()
        .map(|j| profile_parameter(opt, j, first.get(j).unwrap_or(&none)))
        .collect();
    let mut profiles = Vec::with_capacity(out.len());
    for r in out {
        match r? {
            Some(p) => profiles.push(p),
            None => return Ok(None),
        }
    }
    Ok(Some(profiles))
}

/// What the interval stage decided and found, for `assemble::FitDraft::finish` to write into
/// fit.json (the stage itself edits nothing).
pub struct IntervalStage {
    /// `linear` or `profile` (fit.json `options.intervals`), and why (`intervals_reason`).
    pub method: &'static str,
    pub reason: String,
    /// Each free parameter's profile, by its fit.json name and reporting factor.
    pub profiles: Vec<Profile<Label>>,
    /// Ctrl-C stopped the profiles: the linearised standard errors stand.
    pub interrupted: bool,
    /// The profiles' wall time (timing.json stage `profile`), when they ran.
    pub wall_s: Option<f64>,
}

impl IntervalStage {
    fn linear(reason: impl Into<String>) -> IntervalStage {
        IntervalStage {
            method: "linear",
            reason: reason.into(),
            profiles: Vec::new(),
            interrupted: false,
            wall_s: None,
        }
    }
}

/// A profiled parameter as fit.json names it: its name and the factor from natural to reporting
/// units.
pub struct Label {
    pub json_name: String,
    pub factor: f64,
}

impl<P: FitParam> Profile<P> {
    /// The profile with its parameter as fit.json names it.
    pub fn labelled(self) -> Profile<Label> {
        Profile {
            name: Label {
                json_name: self.name.json_name(),
                factor: self.name.report_factor(),
            },
            points: self.points,
            end_68: self.end_68,
            end_95: self.end_95,
            iterations: self.iterations,
            solves: self.solves,
            methods: self.methods,
        }
    }
}

/// The fit's interval stage: decide (`--intervals`) from the draft's outcome and assessment
/// (`assemble::FitDraft`), then profile every free parameter of `opt` (`best`: the polish run,
/// whose cost is the reference). Ctrl-C stops it: the linearised intervals stand and the status
/// is `interrupted`.
pub fn intervals<F: Forward, Q>(
    draft: &FitOutcome<Q>,
    assessment: &Assessment,
    mut opt: Optimum<'_, F>,
    best: &LocalRun,
    opts: &FitOptions,
) -> Result<IntervalStage> {
    let t0 = std::time::Instant::now();
    let nf = opt.free.len();
    let json = &draft.json;
    let dof = json.residuals.dof;
    if nf == 0 || dof == 0 || !(best.cost.is_finite() && best.cost > 0.0) {
        return Ok(IntervalStage::linear("nothing to profile (no free parameter, no residual degrees of freedom, or a zero cost)"));
    }
    if matches!(json.status, FitStatus::Failed | FitStatus::Interrupted) {
        return Ok(IntervalStage::linear(format!(
            "the fit ended {}",
            json.status
        )));
    }
    // Noise-free data: the cost is rounding, so Δχ² (and every interval) would be rounding noise.
    let relative = draft.worst_row_misfit;
    if relative.is_finite() && relative <= super::EXACT_MISFIT {
        return Ok(IntervalStage::linear(format!("the fit is exact to {relative:.1e} relative (noise-free data): no statistical interval to profile")));
    }
    // A profile interval is where Δχ² of a model that describes the data crosses a quantile; on
    // a poor fit the misfit, not the noise, shapes χ², so its intervals mean no more than the
    // linearised errors (already scaled by √(reduced χ²)) and cost most of the run (re-fits of a
    // mismatched model settle slowly). `--intervals profile` still computes them.
    if opts.intervals == Intervals::Auto && assessment.is_poor_fit() {
        return Ok(IntervalStage::linear("auto: the fit is poor_fit, so the model does not describe the data and profile intervals (which assume it does) are no more meaningful than the linearised standard errors; pass --intervals profile to compute them anyway"));
    }
    let n_cols = opt.u.len();
    let n_residuals = dof + nf + json.scale.len();
    let (go, reason) = decide(opts.intervals, nf, n_residuals, n_cols);
    if !go {
        return Ok(IntervalStage::linear(reason));
    }
    opt.chi2_unit = 2.0 * best.cost / dof as f64;
    opt.dof = dof;
    // The linearised path is where the other parameters go while the model describes the data;
    // a poor fit's profile (run only when asked for) is far from it, and its re-fits start from
    // the optimum instead (on traced data the path starts cost Marschner's forced profile 89
    // re-fits and d'Eon's 80 where the optimum's cost 91 and 55).
    let mut first = first_steps(json, &opt.free);
    if assessment.is_poor_fit() {
        first.iter_mut().for_each(|f| f.slopes.clear());
    }
    let stage = match profile_all(&opt, &first)? {
        Some(profiles) => {
            let iterations: u64 = profiles.iter().map(|p| p.iterations).sum();
            let solves: usize = profiles.iter().map(|p| p.solves).sum();
            let quadratic = profiles
                .iter()
                .flat_map(|p| p.methods)
                .filter(|m| *m != ProfileMethod::Refits)
                .count();
            let sides = 2 * profiles.len();
            IntervalStage {
                method: "profile",
                reason: format!(
                    "{reason}; ran {solves} solves, {iterations} LM iterations; {quadratic} of {sides} sides settled by the local quadratic (fit.json `profile_method`; wall time: timing.json stage `profile`)"
                ),
                profiles: profiles.into_iter().map(Profile::labelled).collect(),
                interrupted: false,
                wall_s: None,
            }
        }
        None => IntervalStage {
            interrupted: true,
            ..IntervalStage::linear(
                "profiling interrupted (Ctrl-C): the linearised standard errors stand",
            )
        },
    };
    Ok(IntervalStage {
        wall_s: Some(t0.elapsed().as_secs_f64()),
        ..stage
    })
}

/// Write the interval stage into `out`: the method and its reason, each profile's intervals,
/// an interruption's warning and status, the stage's time.
pub fn write_into<Q>(out: &mut FitOutcome<Q>, stage: IntervalStage, started: std::time::Instant) {
    out.json.options.intervals = stage.method.into();
    out.json.options.intervals_reason = stage.reason;
    record::apply(&mut out.json, &stage.profiles);
    if stage.interrupted {
        out.json.warnings.push("profiling was interrupted: the parameter intervals are the linearised standard errors only".into());
        out.json.status = FitStatus::Interrupted;
    }
    if let Some(wall_s) = stage.wall_s {
        out.timing.stages.push(StageTiming {
            stage: "profile".into(),
            wall_s,
        });
        out.timing.wall_time_s = started.elapsed().as_secs_f64();
    }
}
