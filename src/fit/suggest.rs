//! What to try after a poor or undetermined fit (fit.json `suggestions`), each backed by a number
//! from this fit: a few huge residuals → a robust loss; misfit concentrated at the glints →
//! `--mode exact`; residuals that follow ln cos θ_i → the other `--measurement`; parameters the
//! data do not determine → `--fix`. A suggestion is made only when its evidence is there.

use super::problem::Forward;
use super::verdict::{Evidence, LARGE_RESIDUAL};
use crate::files::{GoodnessOfFit, ParamStatus, Suggestion, Verdict};
use crate::fit::Loss;
use crate::model::{Measurement, RootMode};

/// A robust loss is suggested when the large residuals are at most this fraction of the data…
const MAX_OUTLIER_FRACTION: f64 = 0.25;
/// …and carry at least this share of Σr² (a few samples dominate an l2 fit).
const MIN_OUTLIER_SHARE: f64 = 0.5;
/// `--mode exact` is suggested when the samples near the glint misfit this many times more (mean
/// squared residual, winsorised) than the others: the cubic root map is approximate only there.
const MIN_GLINT_RATIO: f64 = 3.0;
/// Fewest samples on each side of that comparison.
const MIN_GLINT_SAMPLES: usize = 5;
/// The θ_i trend of ln(data/fit) must be this many standard errors from zero, with a slope
/// against ln cos θ_i within ±0.5 of ±1 (what fitting radiance as S, or S as radiance, gives).
const MIN_TREND_T: f64 = 5.0;

/// Suggestions for a fit with `verdict` and statistics `g`.
pub fn suggestions<F: Forward>(
    x: &Evidence<'_, '_, '_, F>,
    g: &GoodnessOfFit,
    verdict: Verdict,
) -> Vec<Suggestion> {
    let mut out = Vec::new();
    if verdict == Verdict::PoorFit {
        out.extend(robust_loss(x, g));
        out.extend(exact_mode(x, g));
        out.extend(measurement(x));
    }
    if matches!(verdict, Verdict::PoorFit | Verdict::Undetermined) {
        out.extend(fix_undetermined(x));
    }
    out
}

fn robust_loss<F: Forward>(x: &Evidence<'_, '_, '_, F>, g: &GoodnessOfFit) -> Option<Suggestion> {
    let noise = g.robust_noise?;
    let share = g.large_residual_share?;
    let n = x.e.raw.len();
    let fraction = g.large_residuals as f64 / n.max(1) as f64;
    if x.ev.loss != Loss::L2
        || g.large_residuals == 0
        || fraction > MAX_OUTLIER_FRACTION
        || share < MIN_OUTLIER_SHARE
    {
        return None;
    }
    // With σ the residuals are in σ units and the default scale 1 fits; without σ the scale must
    // be stated in the residuals' own units: 3× their robust noise level.
    let action = if g.sigma_given {
        "--loss cauchy".to_string()
    } else {
        format!("--loss cauchy --loss-scale {:.2}", 3.0 * noise)
    };
    Some(Suggestion {
        action,
        evidence: format!(
            "{} of {n} residuals ({:.1}%) lie beyond {LARGE_RESIDUAL} times the robust noise level {noise:.3e} and carry {:.0}% of the sum of squares: a few bad samples dominate the l2 fit",
            g.large_residuals,
            100.0 * fraction,
            100.0 * share
        ),
    })
}

fn exact_mode<F: Forward>(x: &Evidence<'_, '_, '_, F>, g: &GoodnessOfFit) -> Option<Suggestion> {
    if x.config.mode != RootMode::Cubic || !x.config.effects.glints || !x.config.effects.lobes.trt {
        return None;
    }
    let nc = x.data.n_channels().max(1);
    let near = x.near_glint.as_ref()?;
    let clip = g.robust_noise.map_or(f64::INFINITY, |s| LARGE_RESIDUAL * s);
    let (mut ss, mut count) = ([0.0; 2], [0usize; 2]);
    for (k, r) in x.e.raw.iter().enumerate().filter(|(_, r)| r.is_finite()) {
        let side = usize::from(near[k / nc]);
        ss[side] += r.clamp(-clip, clip).powi(2);
        count[side] += 1;
    }
    if count[0] < MIN_GLINT_SAMPLES * nc || count[1] < MIN_GLINT_SAMPLES * nc || ss[0] <= 0.0 {
        return None;
    }
    let ratio = (ss[1] / count[1] as f64) / (ss[0] / count[0] as f64);
    (ratio >= MIN_GLINT_RATIO).then(|| Suggestion {
        action: "--mode exact".into(),
        evidence: format!(
            "the {} residuals within 2 w_c of the glint azimuth have {ratio:.1} times the mean square of the other {}: the misfit sits at the glints, where the cubic root map is an approximation",
            count[1], count[0]
        ),
    })
}

/// Least-squares slope of ln(data/fit) against ln cos θ_i, with its standard error.
fn theta_i_trend<F: Forward>(x: &Evidence<'_, '_, '_, F>) -> Option<(f64, f64)> {
    let nc = x.data.n_channels().max(1);
    let points: Vec<(f64, f64)> =
        x.e.model
            .iter()
            .enumerate()
            .filter_map(|(k, &m)| {
                let fit = x.e.scale[k % nc] * m;
                let y = x.data.values[k];
                let c = x.data.angles[k / nc].theta_i.cos();
                (y > 0.0 && fit > 0.0 && c > 0.0)
                    .then(|| (c.ln(), (y / fit).ln()))
                    .filter(|(a, b)| a.is_finite() && b.is_finite())
            })
            .collect();
    let n = points.len() as f64;
    if n < 3.0 {
        return None;
    }
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (u, v)| (a + u / n, b + v / n));
    let sxx: f64 = points.iter().map(|(u, _)| (u - mx).powi(2)).sum();
    // θ_i must vary: ln cos θ_i spanning less than 0.01 (e.g. 0–8°) says nothing.
    if sxx <= 1e-4 * n {
        return None;
    }
    let sxy: f64 = points.iter().map(|(u, v)| (u - mx) * (v - my)).sum();
    let b = sxy / sxx;
    let ss: f64 = points
        .iter()
        .map(|(u, v)| (v - my - b * (u - mx)).powi(2))
        .sum();
    let se = (ss / (n - 2.0) / sxx).sqrt();
    Some((b, se))
}

fn measurement<F: Forward>(x: &Evidence<'_, '_, '_, F>) -> Option<Suggestion> {
    let (b, se) = theta_i_trend(x)?;
    let (expected, action, what) = match x.ev.forward.measurement() {
        Measurement::S => (1.0, "--measurement radiance", "radiance fitted as S"),
        Measurement::Radiance => (-1.0, "--measurement s", "S fitted as radiance"),
    };
    let significant = se > 0.0 && (b / se).abs() > MIN_TREND_T;
    (significant && (b - expected).abs() < 0.5).then(|| Suggestion {
        action: action.into(),
        evidence: format!(
            "ln(data/fit) follows ln cos theta_i with slope {b:.3} ± {se:.3} ({what} gives {expected}): the data carry the cos theta_i factor the fit leaves out, or the other way round"
        ),
    })
}

fn fix_undetermined<F: Forward>(x: &Evidence<'_, '_, '_, F>) -> Option<Suggestion> {
    let names: Vec<&str> = x
        .parameters
        .iter()
        .filter(|p| p.status == ParamStatus::Undetermined)
        .map(|p| p.name.as_str())
        .collect();
    if names.is_empty() {
        return None;
    }
    let example = x
        .parameters
        .iter()
        .find(|p| p.status == ParamStatus::Undetermined)
        .map(|p| format!("--fix {}=VALUE", p.name))
        .unwrap_or_default();
    Some(Suggestion {
        action: format!(
            "{example} for each of {} (a published or separately measured value), or add measurements that vary what they act on",
            names.join(", ")
        ),
        evidence: format!(
            "{} parameter(s) are not determined by these data: {} (see the warnings for why)",
            names.len(),
            names.join(", ")
        ),
    })
}
