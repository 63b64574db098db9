//! Profile-likelihood intervals (MINOS-style): for each free parameter, pin it at values on each
//! side of the optimum, re-minimise the others with the fit's own LM runner, and find where the
//! cost has risen by Δχ² = 1 (68%) and Δχ² = 3.84 (95%). Unlike the linearised standard error,
//! the profile follows the cost's real shape: curved valleys, trade-offs and bounds.
//!
//! Δχ² is in the units the covariance uses: `Δχ² = 2Δcost/s²` with `s² = 2·cost/dof` at the
//! optimum (the residual variance; with a `sigma` column and a good fit it is ≈ 1), so for a
//! linear problem the 68% interval is exactly `value ± SE`.
//!
//! Each crossing is bracketed by steps that grow like a parabola's extrapolation would need, then
//! refined by a few regula-falsi steps on `√Δχ²` (linear in the value for a quadratic profile).
//! Where the first step (the linearised SE) lands on Δχ² ≈ 1, the profile is the local
//! quadratic there, so the next solve is aimed at the quadratic's 95% point and accepted as it
//! stands when it lands within the crossing tolerance: two solves a side instead of three.
//! Every solve is warm-started from the nearest solved point. Parameters run in parallel (rayon);
//! each parameter's sequence of solves is fixed, so results are identical for any thread count.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use rayon::prelude::*;

use super::bounds::Bound;
use super::problem::{Evaluator, FitData, FitParam, Forward, ParamSet, Space};
use super::solve::{is_cancelled, run_lm, LocalRun};
use super::verdict::Assessment;
use super::Loss;
use super::{FitOptions, FitOutcome};
use crate::error::{Error, Result};

mod record;
use crate::files::{FitStatus, ProfileMethod, StageTiming};
pub use record::apply;

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
/// On a side without a fit bound the search stops this many typical ranges from the optimum.
const SEARCH_RANGES: f64 = 3.0;
/// Bracketing steps per side at most.
const MAX_BRACKET: usize = 10;
const MAX_REFINE: usize = 4; // Regula-falsi steps per crossing at most.
/// A crossing is accepted when `√Δχ²` is this close to its target (Δχ² within ~2% at 68%).
const SQRT_TOL: f64 = 0.01;
/// A side's 95% end is the local quadratic's, without a re-fit there, when the re-fit at the
/// linearised SE found `√Δχ²` this close to 1 (Δχ² within 0.2%): a cubic or quartic term that
/// small at 1 SE moves Δχ² at the 95% point (1.96 SE) by at most ~4× as much, under 1% — inside
/// the [`SQRT_TOL`] a re-fitted crossing is accepted at.
const EXTRAPOLATE_TOL: f64 = 1e-3;
/// A profile solve stops when a step gains less than this many χ² units (the polish's own
/// tolerance is 10⁻¹²·dof, far finer than a crossing needs).
const SOLVE_CHI2_TOL: f64 = 1e-3;
/// LM iterations per profile solve at most (warm-started solves need 3–15).
const SOLVE_MAX_ITERS: u64 = 100;
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

/// A solved point at signed distance `h` from the optimum.
struct Pt {
    h: f64,
    d: f64,
    u: Vec<f64>,
}

/// One parameter pinned: an evaluator without it, and its solves.
struct Pinned<'a, 'o, F: Forward> {
    opt: &'o Optimum<'a, F>,
    ev: Evaluator<'a, F>,
    p: F::Param,
    x0: f64,
    iterations: u64,
    solves: usize,
}

impl<F: Forward> Pinned<'_, '_, F> {
    /// Δχ² at `x0 + h` with the other parameters re-minimised from `u_start`.
    fn solve(&mut self, h: f64, u_start: &[f64]) -> Pt {
        self.p.set(&mut self.ev.base, self.x0 + h);
        let max_iters = self.opt.max_iters.min(SOLVE_MAX_ITERS);
        let (u, cost, iterations) = self.run(u_start, max_iters);
        self.iterations += iterations;
        self.solves += 1;
        let d = 2.0 * (cost - self.opt.cost) / self.opt.chi2_unit;
        Pt {
            h,
            d: if d.is_finite() { d } else { f64::INFINITY },
            u,
        }
    }

    /// The fit's LM runner ([`run_lm`]), stopping once the cost change or the Gauss–Newton
    /// predicted χ² gain (a warm start that close takes no step) is below [`SOLVE_CHI2_TOL`],
    /// without a final linearisation: `(u, cost, iterations)`, never worse than the start (the
    /// solver's best point and its cost: no extra passes for the start's and the end's cost).
    fn run(&self, u0: &[f64], max_iters: u64) -> (Vec<f64>, f64, u64) {
        let ftol = (SOLVE_CHI2_TOL / self.opt.dof.max(1) as f64).clamp(super::solve::FTOL, 1e-4);
        let solver = crate::lm::LevenbergMarquardt::new()
            .with_tolerances(ftol, crate::lm::DEFAULT_XTOL, 0.0)
            .and_then(|lm| lm.with_statistical_tolerance(self.opt.dof.max(1), SOLVE_CHI2_TOL))
            .unwrap_or_default()
            .with_lazy_final_linearization();
        let run = run_lm(&self.ev, u0, solver, max_iters, &self.opt.cancel, None);
        (run.u, run.cost, run.iterations)
    }

    /// Bracket both thresholds on one side (`dir` = ±1) out to `hmax`; the points, ascending in
    /// |h| and starting at the optimum. `None` when cancelled.
    /// `first_start`: where the first solve starts (the other side's first point mirrored
    /// through the optimum), else the optimum.
    fn bracket(
        &mut self,
        dir: f64,
        step: f64,
        hmax: f64,
        u0: &[f64],
        first_start: Option<Vec<f64>>,
    ) -> Option<Vec<Pt>> {
        let mut pts = vec![Pt {
            h: 0.0,
            d: 0.0,
            u: u0.to_vec(),
        }];
        let mut first_start = first_start;
        let mut h = step.min(hmax);
        for _ in 0..MAX_BRACKET {
            if h <= 0.0 {
                break;
            }
            if is_cancelled(&self.opt.cancel) {
                return None;
            }
            // The other parameters move nearly linearly with the pinned one near the optimum:
            // start where the last two points extrapolate to (the LM then settles in about one
            // iteration instead of two), the first solve from `first_start`.
            let start = match pts.len() {
                1 => first_start.take().unwrap_or_else(|| u0.to_vec()),
                n => extrapolate(&pts[n - 2], &pts[n - 1], dir * h),
            };
            let pt = self.solve(dir * h, &start);
            let d = pt.d;
            pts.push(pt);
            if d >= CHI2_95 || near(d, CHI2_95) || h >= hmax || quadratic_end(&pts, hmax).is_some()
            {
                break;
            }
            // Where the first step (the linearised SE) found Δχ² ≈ 1, the profile is the local
            // quadratic there: aim at its 95% crossing, h·√(3.84/d), which the crossing search
            // then accepts as it stands when the quadratic still holds (one solve, not a
            // bracket and a refinement). Otherwise a parabola through the optimum reaches
            // 1.3·3.84 at h·√(5/d); grow by 1.5–4×.
            let grow = if pts.len() == 2 && near(d, CHI2_68) {
                (CHI2_95 / d).sqrt()
            } else {
                (1.3 * CHI2_95 / d.max(0.05)).sqrt().clamp(1.5, 4.0)
            };
            h = (h * grow).min(hmax);
        }
        Some(pts)
    }

    /// Where the side's profile crosses `target` (refining between bracketing points, which are
    /// added to `pts`), or where it ends open.
    fn crossing(&mut self, pts: &mut Vec<Pt>, target: f64, bounded: bool) -> Option<End> {
        let Some(k) = pts.iter().position(|p| p.d >= target || near(p.d, target)) else {
            let last = pts.last()?;
            return Some(End::Open {
                at: self.x0 + last.h,
                dchi2: last.d,
                bound: bounded,
            });
        };
        if near(pts[k].d, target) {
            return Some(End::Closed(self.x0 + pts[k].h));
        }
        let g = |d: f64| d.max(0.0).sqrt() - target.sqrt();
        let (mut a, mut b) = (k - 1, k);
        for _ in 0..MAX_REFINE {
            let (pa, pb) = (&pts[a], &pts[b]);
            let (ga, gb) = (g(pa.d), g(pb.d));
            if gb.abs() < SQRT_TOL {
                return Some(End::Closed(self.x0 + pb.h));
            }
            if ga.abs() < SQRT_TOL && a > 0 {
                return Some(End::Closed(self.x0 + pa.h));
            }
            let mut h = pa.h + (pb.h - pa.h) * (-ga) / (gb - ga);
            let (lo, hi) = (pa.h.min(pb.h), pa.h.max(pb.h));
            if !(h > lo && h < hi && h.is_finite()) {
                h = 0.5 * (pa.h + pb.h);
            }
            if is_cancelled(&self.opt.cancel) {
                return None;
            }
            let near = if (h - pa.h).abs() < (h - pb.h).abs() {
                pa.u.clone()
            } else {
                pb.u.clone()
            };
            let pt = self.solve(h, &near);
            let below = pt.d < target;
            pts.insert(b, pt);
            // The new point sits at index b; the old b moved to b + 1.
            if below {
                a = b;
                b += 1;
            }
        }
        let (pa, pb) = (&pts[a], &pts[b]);
        let (ga, gb) = (g(pa.d), g(pb.d));
        let t = if gb != ga { -ga / (gb - ga) } else { 0.5 };
        Some(End::Closed(
            self.x0 + pa.h + (pb.h - pa.h) * t.clamp(0.0, 1.0),
        ))
    }
}

/// The point on the line through `a` and `b` (solved points, in the solver's coordinates) at
/// pinned offset `h`.
fn extrapolate(a: &Pt, b: &Pt, h: f64) -> Vec<f64> {
    let t = if b.h != a.h {
        (h - b.h) / (b.h - a.h)
    } else {
        0.0
    };
    a.u.iter()
        .zip(&b.u)
        .map(|(ua, ub)| ub + (ub - ua) * t)
        .collect()
}

/// The side's 95% offset from the local quadratic, when its only solve (at the linearised SE)
/// found Δχ² within [`EXTRAPOLATE_TOL`] of 1 and the offset is inside the side's room `hmax`.
fn quadratic_end(pts: &[Pt], hmax: f64) -> Option<f64> {
    let [_, first] = pts else {
        return None;
    };
    let h95 = first.h.abs() * (CHI2_95 / first.d).sqrt();
    ((first.d.sqrt() - 1.0).abs() < EXTRAPOLATE_TOL && h95 <= hmax)
        .then_some(first.h.signum() * h95)
}

/// Whether a solved Δχ² is close enough to `target` to be its crossing: `√Δχ²` within
/// [`SQRT_TOL`] of `√target`.
fn near(d: f64, target: f64) -> bool {
    (d.max(0.0).sqrt() - target.sqrt()).abs() < SQRT_TOL
}

/// Profile free parameter `j` of `opt`, stepping first by `step` (natural units, e.g. the
/// linearised SE). `None` when cancelled.
pub fn profile_parameter<F: Forward>(
    opt: &Optimum<'_, F>,
    j: usize,
    step: Option<f64>,
) -> Result<Option<Profile<F::Param>>> {
    let p = opt.free[j];
    let free: Vec<F::Param> = opt.free.iter().copied().filter(|&q| q != p).collect();
    let (ev, _) = Evaluator::new(
        opt.forward,
        opt.data,
        opt.space,
        opt.loss,
        opt.loss_scale,
        opt.params.clone(),
        free,
    )?;
    let x0 = p.get(&opt.params);
    let mut u0 = opt.u.clone();
    u0.remove(j);
    let (a, b) = p.typical_range();
    let width = (b - a).abs().max(1e-12);
    let step = step
        .filter(|s| s.is_finite() && *s > 0.0)
        .unwrap_or(0.05 * width)
        .clamp(1e-6 * width, width);
    let mut pin = Pinned {
        opt,
        ev,
        p,
        x0,
        iterations: 0,
        solves: 0,
    };
    let far = SEARCH_RANGES * width;
    let (lo_room, lo_bounded, hi_room, hi_bounded) = match p.bound() {
        Bound::Free => (far, false, far, false),
        Bound::Lower(lo) => ((x0 - lo).max(0.0), true, far, false),
        Bound::Both(lo, hi) => ((x0 - lo).max(0.0), true, (hi - x0).max(0.0), true),
    };
    let mut ends = [[End::Closed(x0); 2]; 2];
    let mut methods = [ProfileMethod::Refits; 2];
    let mut points = Vec::new();
    let mut mirrored = None;
    for (side, (dir, room, bounded)) in [(-1.0, lo_room, lo_bounded), (1.0, hi_room, hi_bounded)]
        .into_iter()
        .enumerate()
    {
        let Some(mut pts) = pin.bracket(dir, step, room, &u0, mirrored.take()) else {
            return Ok(None);
        };
        // The upper side's first solve (at +step) starts from the lower side's (at −step)
        // mirrored through the optimum.
        if let Some(first) = pts.get(1).filter(|p| p.h == -step) {
            mirrored = Some(u0.iter().zip(&first.u).map(|(o, f)| 2.0 * o - f).collect());
        }
        if let Some(h95) = quadratic_end(&pts, room) {
            ends[0][side] = End::Closed(x0 + pts[1].h);
            ends[1][side] = End::Closed(x0 + h95);
            methods[side] = ProfileMethod::Extrapolated;
        } else {
            for (t, target) in [CHI2_68, CHI2_95].into_iter().enumerate() {
                let Some(end) = pin.crossing(&mut pts, target, bounded) else {
                    return Ok(None);
                };
                ends[t][side] = end;
            }
            // Two solves, no refinement inserted: the SE's solve at Δχ² ≈ 1 and the
            // quadratic's 95% point at ≈ 3.84 were taken as they stand.
            if pts.len() == 3 && near(pts[1].d, CHI2_68) && near(pts[2].d, CHI2_95) {
                methods[side] = ProfileMethod::Quadratic;
            }
        }
        points.extend(pts.iter().skip(side).map(|pt| (x0 + pt.h, pt.d)));
    }
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(Some(Profile {
        name: p,
        points,
        end_68: ends[0],
        end_95: ends[1],
        iterations: pin.iterations,
        solves: pin.solves,
        methods,
    }))
}

/// Profile every free parameter in parallel (`steps[j]`: first step of parameter `j`). `None`
/// when cancelled: the linearised intervals stand.
pub fn profile_all<F: Forward>(
    opt: &Optimum<'_, F>,
    steps: &[Option<f64>],
) -> Result<Option<Vec<Profile<F::Param>>>> {
    let out: Vec<Result<Option<Profile<F::Param>>>> = (0..opt.free.len())
        .into_par_iter()
        .map(|j| profile_parameter(opt, j, steps.get(j).copied().flatten()))
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
    let steps: Vec<Option<f64>> = opt
        .free
        .iter()
        .map(|&p| {
            json.parameters
                .iter()
                .find(|e| e.name == p.json_name())
                .and_then(|e| e.std_error)
                .map(|se| se / p.report_factor())
        })
        .collect();
    let stage = match profile_all(&opt, &steps)? {
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
