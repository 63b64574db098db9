//! The fit's verdict (fit.json `verdict`, `reasons`, `goodness_of_fit`, `suggestions`): whether
//! the numbers are a fit at all (failure detection), whether the model describes the data
//! (goodness of fit from [`super::gof`]), and whether every free parameter is determined.
//!
//! Precedence: `interrupted` > `failed` > `poor_fit` > `undetermined` > `good`. The deciding
//! reasons come first; the others follow, so a poor fit still names its undetermined parameters.
//! What to try next is [`super::suggest`]'s.

use std::sync::Arc;

use super::evidence::Evidence;
use super::evidence::LARGE_RESIDUAL;
use super::gof::{
    self, centre_per_channel, direction_groups, poisson_upper_tail, GAUSSIAN_BEYOND_5SD,
};
use super::problem::{FitData, Forward};
use super::suggest::{fix_undetermined, poor_fit_suggestions};
use crate::files::{
    FitJson, FitStatus, GofThresholds, GoodnessOfFit, ParamStatus, ParameterEntry, Suggestion,
    Verdict,
};
use crate::fit::Loss;
use crate::slices::{find_slices_by, FoundSlices, Slice};

/// A test rejects the model when its p-value is below 1e-3: with the handful of tests applied
/// to one fit, a model that does describe its data is called poor about once in 300–1000 fits,
/// while the misfits that matter (the mismatch and outlier cases) give p < 1e-10.
pub const P_VALUE: f64 = 1e-3;

/// With σ the reduced χ² must also exceed 1.2: unexplained scatter of at least √0.2 ≈ 0.45 σ on
/// top of the noise. On 10⁵ samples p < 1e-3 alone flags a reduced χ² of 1.01, which the
/// log-space approximation σ_ln = σ/y and a slightly misstated σ can produce; the mismatches
/// worth reporting measured 2.4–17.
pub const MIN_REDUCED_CHI2: f64 = 1.2;

/// Without σ, neighbouring residuals must share at least 20% of their variance (lag-1 r > 0.2)
/// for the autocorrelation to call the fit poor: a smooth misfit comparable to the noise gives
/// r ≈ 0.5, while the fit's own parameters induce |r| ~ p/n ≪ 0.2.
pub const MIN_LAG1: f64 = 0.2;

/// Without σ, residual signs must form fewer than 80% of the runs expected for noise.
pub const MAX_RUNS_RATIO: f64 = 0.8;

/// Without σ, the misfit of replicate means must exceed twice the replicates' own scatter.
pub const MIN_LOF_F: f64 = 2.0;

/// With a robust loss and σ, residuals beyond 5 σ are what the loss discounts: they are left out
/// of the χ² test (Gaussian noise puts 6e-7 of samples there) and counted.
pub const ROBUST_EXCLUSION_SIGMA: f64 = 5.0;

/// More than this fraction of residuals beyond [`ROBUST_EXCLUSION_SIGMA`] are not outliers: the
/// model misses the bulk of the data.
pub const MAX_OUTLIER_FRACTION: f64 = 0.25;

/// At most this many rows are named in one reason (the count says how many more).
const NAMED_ROWS: usize = 3;

/// The verdict with its reasons, statistics and suggestions.
#[derive(Debug, Clone)]
pub struct Judgement {
    pub verdict: Verdict,
    pub reasons: Vec<String>,
    pub goodness_of_fit: GoodnessOfFit,
    pub suggestions: Vec<Suggestion>,
}

/// What a fit's final evaluation says, before its intervals are profiled: why the numbers are
/// no fit, why the model misses the data, the goodness-of-fit statistics and what to try when
/// it does. The verdict is decided from it once, by [`decide`], after the profiles.
#[derive(Debug, Clone)]
pub struct Assessment {
    /// The solver's status when the fit ended (profiling may still be interrupted).
    fit_status: FitStatus,
    /// Solver iterations over every stage.
    iterations: u64,
    failed: Vec<String>,
    poor: Vec<String>,
    /// The worst row's relative misfit, when at rounding level (noise-free data).
    exact: Option<f64>,
    goodness_of_fit: GoodnessOfFit,
    /// What to try for a poor fit (robust loss, exact mode, what was measured).
    poor_fit_suggestions: Vec<Suggestion>,
    /// The data's scan slices, which the report of full curves draws again.
    slices: Arc<FoundSlices>,
}

impl Assessment {
    /// The verdict before the profiles, up to undetermined parameters: `interrupted`, `failed`,
    /// `poor_fit`, or `None` for a fit that describes its data.
    fn ranking(&self) -> Option<Verdict> {
        if self.fit_status == FitStatus::Interrupted {
            Some(Verdict::Interrupted)
        } else if !self.failed.is_empty() {
            Some(Verdict::Failed)
        } else if !self.poor.is_empty() {
            Some(Verdict::PoorFit)
        } else {
            None
        }
    }

    /// The data's scan slices and the samples in none ([`scan_slices`]).
    pub fn scan_slices(&self) -> &Arc<FoundSlices> {
        &self.slices
    }

    /// True when the model misses the data (the verdict will be `poor_fit`).
    pub fn is_poor_fit(&self) -> bool {
        self.ranking() == Some(Verdict::PoorFit)
    }
}

/// Assess a fit at its optimum (see [`Assessment`]).
pub fn assess<F: Forward>(x: &Evidence<'_, '_, '_, F>) -> Assessment {
    let failed = failures(x);
    let found = Arc::new(scan_slices(x.data));
    let g = goodness_of_fit(x, &found.0);
    // Residuals at rounding level carry no noise for the tests to judge: the model is the data.
    let exact = x.worst_row_misfit.is_finite() && x.worst_row_misfit <= super::EXACT_MISFIT;
    let poor = if failed.is_empty() && !exact {
        poor_fit_reasons(&g, x.ev.loss, x.e.raw.len())
    } else {
        Vec::new()
    };
    let mut a = Assessment {
        fit_status: x.status,
        iterations: x.trace.iter().map(|t| t.iterations).sum(),
        failed,
        poor,
        exact: exact.then_some(x.worst_row_misfit),
        goodness_of_fit: g,
        poor_fit_suggestions: Vec::new(),
        slices: found,
    };
    if a.is_poor_fit() {
        a.poor_fit_suggestions = poor_fit_suggestions(x, &a.goodness_of_fit, &a.slices.0);
    }
    a
}

/// The verdict of a fit, decided once: from its assessment, its parameters after the profiles
/// (an open profile makes one `undetermined`), its status (profiling may have been
/// interrupted) and the caveats of the data's design ([`super::scan_design`]).
pub fn decide(a: &Assessment, json: &FitJson, data: &FitData) -> Judgement {
    let g = &a.goodness_of_fit;
    let undetermined: Vec<&ParameterEntry> = json
        .parameters
        .iter()
        .filter(|p| p.status == ParamStatus::Undetermined)
        .collect();
    let mut verdict = a.ranking().unwrap_or(if undetermined.is_empty() {
        Verdict::Good
    } else {
        Verdict::Undetermined
    });
    let mut reasons = Vec::new();
    if verdict == Verdict::Interrupted {
        reasons.push(format!(
            "stopped by a signal (Ctrl-C or SIGTERM) after {} solver iterations: the parameters are the best point so far, not a converged fit",
            a.iterations
        ));
    }
    reasons.extend(a.failed.iter().cloned());
    reasons.extend(a.poor.iter().cloned());
    match a.exact {
        Some(worst) if a.failed.is_empty() => reasons.push(format!(
            "the model reproduces the data to rounding: every row within {worst:.1e} of its value (relative; <= {:e}), so there is no noise for the goodness-of-fit tests to judge",
            super::EXACT_MISFIT
        )),
        _ if a.failed.is_empty() && a.poor.is_empty() => reasons.extend(good_fit_reasons(g)),
        _ => {}
    }
    if verdict == Verdict::PoorFit && g.sigma_given {
        if let Some(f) = g.se_scale_factor.filter(|f| *f > 1.0) {
            reasons.push(format!(
                "standard errors include the factor sqrt(reduced chi2) = {f:.3}: the sigma column alone would give errors {f:.3}x smaller (the PDG's scale factor for a poor fit)"
            ));
        }
    }
    if verdict != Verdict::Failed {
        for p in &undetermined {
            reasons.push(undetermined_reason(p, &json.warnings));
        }
    }
    for p in json
        .parameters
        .iter()
        .filter(|p| p.status == ParamStatus::AtBound)
    {
        reasons.push(format!(
            "{} is stuck at its bound {}: the data push it there and its standard error is one-sided",
            p.name,
            p.value.map_or("null".into(), |v| format!("{v:.6}"))
        ));
    }
    if a.fit_status == FitStatus::MaxIterations {
        reasons.push(
            "the polish stopped at its iteration limit before converging (raise --polish-iters)"
                .into(),
        );
    }
    let mut suggestions = a.poor_fit_suggestions.clone();
    if matches!(verdict, Verdict::PoorFit | Verdict::Undetermined) {
        suggestions.extend(fix_undetermined(&json.parameters));
    }
    if json.status == FitStatus::Interrupted && verdict != Verdict::Interrupted {
        verdict = Verdict::Interrupted;
        reasons.insert(
            0,
            "stopped by a signal (Ctrl-C or SIGTERM) while profiling: the intervals are the linearised standard errors only".into(),
        );
    }
    if !matches!(verdict, Verdict::Failed | Verdict::Interrupted) {
        let c = super::scan_design::caveats(&super::scan_design::Design::of(data), json);
        if c.undetermined && verdict == Verdict::Good {
            verdict = Verdict::Undetermined;
        }
        reasons.extend(c.reasons);
        suggestions.extend(c.suggestions);
    }
    Judgement {
        verdict,
        reasons,
        goodness_of_fit: g.clone(),
        suggestions,
    }
}

/// The named parameter's own warning (it says why), or a plain sentence.
fn undetermined_reason(p: &ParameterEntry, warnings: &[String]) -> String {
    let prefix = format!("{}:", p.name);
    match warnings.iter().find(|w| w.starts_with(&prefix)) {
        Some(w) => format!("{} is undetermined — {}", p.name, w[prefix.len()..].trim()),
        None => format!("{} is undetermined: the data do not fix its value", p.name),
    }
}

/// Why the numbers are not a fit (empty when they are).
fn failures<F: Forward>(x: &Evidence<'_, '_, '_, F>) -> Vec<String> {
    let mut why = Vec::new();
    if x.status == FitStatus::Failed {
        why.push(
            x.warnings
                .iter()
                .find(|w| w.contains("not finite at any point"))
                .cloned()
                .unwrap_or_else(|| "the solver failed at every start".into()),
        );
    }
    let cost = x.e.cost();
    if !cost.is_finite() {
        why.push(if cost.is_nan() {
            "the cost at the result is undefined (0·∞ or ∞−∞ in the residuals)".into()
        } else {
            "the cost at the result overflows: the residuals are too large for floating point"
                .into()
        });
    }
    let iterations: u64 = x.trace.iter().map(|t| t.iterations).sum();
    if x.ev.n_params() > 0 && iterations == 0 && x.status != FitStatus::Interrupted {
        why.push(
            "no progress from the start: the solver took 0 iterations in every stage, so the parameters are start values, not a fit"
                .into(),
        );
    }
    for p in x.parameters.iter().filter(|p| p.value.is_none()) {
        why.push(format!("{} is not finite", p.name));
    }
    for s in x.scale {
        match s.value {
            Some(v) if v > 0.0 => {}
            Some(v) => why.push(format!(
                "scale[{}] = {v}: a zero or negative scale cannot match the data",
                s.channel
            )),
            None => why.push(format!(
                "scale[{}] is not finite: the weighted sums that give it overflow",
                s.channel
            )),
        }
    }
    why.extend(weight_failures(x));
    why.extend(loss_scale_failure(x));
    let rms = x.e.raw.iter().map(|r| r * r).sum::<f64>();
    if cost == 0.0 && rms > 0.0 && rms.is_finite() {
        why.push(format!(
            "the cost is 0 although the residuals are not (sum of squares {rms:.3e}): the loss underflows, so no step can improve anything"
        ));
    }
    why
}

/// Rows whose residual weight (1/σ, or y/σ in log space) overflows or underflows when squared:
/// one such row makes every sum of the fit non-finite or blind to it.
fn weight_failures<F: Forward>(x: &Evidence<'_, '_, '_, F>) -> Option<String> {
    let nc = x.data.n_channels().max(1);
    let w = x.ev.weights();
    let user_zero = |k: usize| x.data.weight.as_ref().is_some_and(|wt| wt[k] <= 0.0);
    let bad: Vec<(usize, f64)> = w
        .iter()
        .enumerate()
        .filter(|&(k, &wk)| {
            let w2 = wk * wk;
            !w2.is_finite() || (wk == 0.0 && !user_zero(k)) || (wk != 0.0 && w2 < f64::MIN_POSITIVE)
        })
        .map(|(k, &wk)| (k, wk))
        .collect();
    if bad.is_empty() {
        return None;
    }
    let named: Vec<String> = bad
        .iter()
        .take(NAMED_ROWS)
        .map(|&(k, wk)| {
            let i = k / nc;
            let line = x.data.line.get(i).copied().unwrap_or(i as u64 + 1);
            let sigma = x
                .data
                .sigma
                .as_ref()
                .map_or(String::new(), |s| format!(", sigma {:e}", s[k]));
            let what = if wk == 0.0 || !(wk * wk).is_finite() {
                "overflows"
            } else {
                "underflows"
            };
            format!(
                "line {line} (value {:e}{sigma}: weight {wk:.3e} {what} when squared)",
                x.data.values[k]
            )
        })
        .collect();
    Some(format!(
        "{} value(s) have a residual weight outside floating-point range: {}{}; correct or remove their sigma/weight",
        bad.len(),
        named.join("; "),
        if bad.len() > NAMED_ROWS { "; …" } else { "" }
    ))
}

/// A robust-loss scale so large (or small) that (r/C)² underflows (or overflows) at typical
/// residuals: every loss is 0 (or infinite) and the solver cannot move.
fn loss_scale_failure<F: Forward>(x: &Evidence<'_, '_, '_, F>) -> Option<String> {
    if x.ev.loss == Loss::L2 {
        return None;
    }
    let c = x.ev.loss_scale;
    let typical = gof::robust_sd(&x.e.raw)? / 1.4826;
    let ratio2 = (typical / c).powi(2);
    let broken = !(c * c).is_finite()
        || c * c < f64::MIN_POSITIVE
        || !ratio2.is_finite()
        || (typical > 0.0 && ratio2 < f64::MIN_POSITIVE);
    broken.then(|| {
        format!(
            "--loss-scale {c:e} is outside floating-point range for residuals of typical size {typical:.3e}: (r/C)^2 = {ratio2:.3e} {}; use a scale near the noise level",
            if ratio2 < 1.0 { "underflows" } else { "overflows" }
        )
    })
}

/// The data's scan slices (fixed incidence and one outgoing angle, swept in order) and the
/// samples in none, found as the report finds them.
pub fn scan_slices(data: &FitData) -> FoundSlices {
    find_slices_by(data.len(), |i| data.angles_deg(i))
}

/// Goodness-of-fit statistics of the final residuals.
pub fn goodness_of_fit<F: Forward>(x: &Evidence<'_, '_, '_, F>, slices: &[Slice]) -> GoodnessOfFit {
    let raw = &x.e.raw;
    let nc = x.data.n_channels().max(1);
    let n_fitted = x.n_fitted();
    let sigma_given = x.data.sigma.is_some();
    // Outliers are judged about each channel's median residual: the scale is re-estimated in
    // the noise model's space after the shape fit, and under l2 outliers drag that mean, which
    // moves every inlier by the same offset (a robust spread about zero would then hide them).
    let centred = centre_per_channel(raw, nc);
    let robust_noise = gof::robust_sd(&centred).filter(|s| s.is_finite());
    let (mut large, mut large_ss, mut total_ss) = (0usize, 0.0, 0.0);
    for r in centred.iter().filter(|r| r.is_finite()) {
        total_ss += r * r;
        if robust_noise.is_some_and(|s| r.abs() > LARGE_RESIDUAL * s) {
            large += 1;
            large_ss += r * r;
        }
    }
    // χ² over the residuals the loss keeps (all of them under l2).
    let (mut chi2, mut chi2_dof, mut chi2_p_value, mut chi2_excluded) = (None, 0, None, 0);
    if sigma_given {
        let robust = x.ev.loss != Loss::L2;
        let kept: Vec<f64> = raw
            .iter()
            .copied()
            .filter(|r| !robust || r.abs() <= ROBUST_EXCLUSION_SIGMA)
            .collect();
        chi2_excluded = raw.len() - kept.len();
        let c: f64 = kept.iter().map(|r| r * r).sum();
        chi2_dof = kept.len().saturating_sub(n_fitted);
        chi2 = crate::files::finite(c);
        chi2_p_value = gof::chi2_p_value(c, chi2_dof as f64);
    }
    let loss_ss: f64 = x.e.residual.iter().map(|r| r * r).sum();
    let se_scale_factor =
        crate::files::finite((loss_ss / x.dof.max(1) as f64).sqrt()).filter(|_| x.dof > 0);

    // Structure along scan slices: each slice × channel in order of its swept angle.
    let clip = robust_noise.map_or(f64::INFINITY, |s| LARGE_RESIDUAL * s);
    let sequences: Vec<Vec<f64>> = slices
        .iter()
        .flat_map(|s| {
            (0..nc).map(move |c| {
                s.samples
                    .iter()
                    .map(|&i| raw[i * nc + c])
                    .collect::<Vec<f64>>()
            })
        })
        .collect();
    // Winsorised for the autocorrelation: one outlier is not a correlated misfit.
    let clipped: Vec<Vec<f64>> = sequences
        .iter()
        .map(|s| s.iter().map(|r| r.clamp(-clip, clip)).collect())
        .collect();
    let runs = gof::runs_test(sequences.iter().map(Vec::as_slice));
    let lag1 = gof::lag1_autocorrelation(clipped.iter().map(Vec::as_slice));

    // Replicates: the same direction (φ wrapped) and channel measured more than once.
    let (sample_group, sample_counts) = direction_groups(&x.data.angles);
    let replicate_groups = nc * sample_counts.iter().filter(|&&c| c > 1).count();
    let group: Vec<usize> = (0..raw.len())
        .map(|k| sample_group[k / nc] * nc + k % nc)
        .collect();
    let lack_of_fit = if replicate_groups > 0 {
        gof::lack_of_fit(raw, &group, n_fitted)
    } else {
        None
    };
    GoodnessOfFit {
        sigma_given,
        chi2,
        chi2_dof,
        chi2_p_value,
        chi2_excluded,
        se_scale_factor,
        robust_noise,
        large_residuals: large,
        large_residual_share: (total_ss > 0.0).then(|| large_ss / total_ss),
        slices: slices.len(),
        runs,
        lag1,
        replicate_groups,
        lack_of_fit,
        thresholds: GofThresholds {
            p_value: P_VALUE,
            reduced_chi2: MIN_REDUCED_CHI2,
            lag1: MIN_LAG1,
            runs_ratio: MAX_RUNS_RATIO,
            lack_of_fit_f: MIN_LOF_F,
            robust_exclusion_sigma: ROBUST_EXCLUSION_SIGMA,
        },
    }
}

/// Why the model does not describe the data (empty when nothing says so). With σ the χ² test
/// decides; without it, structure along scans and lack of fit against replicates.
pub fn poor_fit_reasons(g: &GoodnessOfFit, loss: Loss, n: usize) -> Vec<String> {
    let mut why = Vec::new();
    if g.sigma_given {
        if let (Some(chi2), Some(p)) = (g.chi2, g.chi2_p_value) {
            let red = chi2 / g.chi2_dof.max(1) as f64;
            if p < P_VALUE && red > MIN_REDUCED_CHI2 {
                why.push(format!(
                    "chi2 = {} for {} degrees of freedom (reduced chi2 of the normalised residuals {}, p = {p:.2e}): the model misses the data by more than their sigma column allows (poor when p < {P_VALUE:e} and reduced chi2 > {MIN_REDUCED_CHI2})",
                    num(chi2),
                    g.chi2_dof,
                    num(red)
                ));
            }
        }
        let n = g.chi2_dof + g.chi2_excluded;
        if g.chi2_excluded as f64 > MAX_OUTLIER_FRACTION * n as f64 {
            why.push(format!(
                "{} residuals beyond {ROBUST_EXCLUSION_SIGMA} sigma ({:.0}% of the data) are too many to be outliers the loss may ignore",
                g.chi2_excluded,
                100.0 * g.chi2_excluded as f64 / n.max(1) as f64
            ));
        }
        return why;
    }
    // Gaussian noise puts a fraction 5.7e-7 of residuals beyond 5 sd; under l2 a handful that
    // carry most of the sum of squares decide the fit.
    if let (Some(noise), Some(share)) = (g.robust_noise, g.large_residual_share) {
        let expected = n as f64 * GAUSSIAN_BEYOND_5SD;
        let p = poisson_upper_tail(g.large_residuals, expected);
        if loss == Loss::L2 && p < P_VALUE && share > 0.5 {
            why.push(format!(
                "{} of {n} residuals lie beyond {LARGE_RESIDUAL} times the robust noise level {noise:.3e} (Gaussian noise would put {expected:.1e} there, p = {p:.1e}) and carry {:.0}% of the sum of squares: a few samples decide the l2 fit",
                g.large_residuals,
                100.0 * share
            ));
        }
    }
    if let Some(r) = g
        .runs
        .filter(|r| r.p_value < P_VALUE && (r.runs as f64) < MAX_RUNS_RATIO * r.expected)
    {
        why.push(format!(
            "residual signs along {} scan slices form {} runs where {:.0} are expected for noise (z = {:.1}, p = {:.2e}): the model misses the data systematically along the scans",
            g.slices, r.runs, r.expected, r.z, r.p_value
        ));
    }
    if let Some(a) = g.lag1.filter(|a| a.p_value < P_VALUE && a.r1 > MIN_LAG1) {
        why.push(format!(
            "neighbouring residuals along the scans are correlated: lag-1 r = {:.3} over {} pairs (p = {:.2e}; noise gives |r| < {MIN_LAG1})",
            a.r1, a.pairs, a.p_value
        ));
    }
    if let Some(l) = g
        .lack_of_fit
        .filter(|l| l.p_value < P_VALUE && l.f > MIN_LOF_F)
    {
        why.push(format!(
            "replicates at {} directions scatter by {:.3e}, but the fit misses their means by F = {} times that variance (lack-of-fit test, p = {:.2e})",
            g.replicate_groups, l.pure_error_sd, num(l.f), l.p_value
        ));
    }
    why
}

/// Sentences for a fit whose residuals look like noise, carrying the statistics.
fn good_fit_reasons(g: &GoodnessOfFit) -> Vec<String> {
    if g.sigma_given {
        return match (g.chi2, g.chi2_p_value) {
            (Some(chi2), Some(p)) => vec![format!(
                "chi2 = {} for {} degrees of freedom (reduced chi2 of the normalised residuals {}, p = {p:.3}): consistent with the sigma column{}",
                num(chi2),
                g.chi2_dof,
                num(chi2 / g.chi2_dof.max(1) as f64),
                if g.chi2_excluded > 0 {
                    format!(" ({} residuals beyond {ROBUST_EXCLUSION_SIGMA} sigma discounted by the robust loss)", g.chi2_excluded)
                } else {
                    String::new()
                }
            )],
            _ => vec!["no chi2 test: no residual degrees of freedom".into()],
        };
    }
    let mut tests = Vec::new();
    if let Some(r) = g.runs {
        tests.push(format!(
            "{} runs of residual signs where {:.0} are expected (z = {:.1})",
            r.runs, r.expected, r.z
        ));
    }
    if let Some(a) = g.lag1 {
        tests.push(format!("lag-1 autocorrelation {:.3}", a.r1));
    }
    if let Some(l) = g.lack_of_fit {
        tests.push(format!(
            "lack of fit against {} replicated directions F = {} (p = {:.3})",
            g.replicate_groups,
            num(l.f),
            l.p_value
        ));
    }
    if tests.is_empty() {
        vec!["no goodness-of-fit test applies (no sigma column, no scan slice of 3 or more points, no repeated direction): the fit is judged on convergence alone".into()]
    } else {
        vec![format!(
            "no sigma column; the residuals look like noise along {} scan slices: {}",
            g.slices,
            tests.join(", ")
        )]
    }
}

/// Four significant digits, in exponent form outside [1e-3, 1e5).
fn num(x: f64) -> String {
    if x != 0.0 && !(1e-3..1e5).contains(&x.abs()) {
        format!("{x:.3e}")
    } else {
        let digits = (3 - x.abs().log10().floor().max(-1.0) as i32).max(0) as usize;
        format!("{x:.digits$}")
    }
}
