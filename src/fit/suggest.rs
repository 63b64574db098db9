//! What to try after a poor or undetermined fit (fit.json `suggestions`), each backed by a number
//! from this fit: a few huge residuals → a robust loss; residuals shaped like the exact root
//! map's difference from the cubic one (the glints, the transmitted lobes) → `--mode exact`; residuals that follow ln cos θ_i → the other `--measurement`; parameters the
//! data do not determine → `--fix`. A suggestion is made only when its evidence is there.

use rayon::prelude::*;

use super::evidence::{Evidence, LARGE_RESIDUAL};
use super::gof;
use super::problem::{FitParam, Forward, ScaleMode, Space, CHUNK};
use crate::files::{GoodnessOfFit, ParamStatus, ParameterEntry, Suggestion};
use crate::fit::Loss;
use crate::geometry::Measurement;
use crate::slices::Slice;

/// A robust loss is suggested when the large residuals are at most this fraction of the data…
const MAX_OUTLIER_FRACTION: f64 = 0.25;
/// …and carry at least this share of Σr² (a few samples dominate an l2 fit).
const MIN_OUTLIER_SHARE: f64 = 0.5;
/// Isolated spikes along scans that point to outliers: at least this many…
const MIN_SPIKES: usize = 2;
/// `--mode exact` is suggested when a linearised refit with the exact root map lowers the sum of
/// squares by more than 25 noise variances (Δχ² > 25: five standard errors for one model
/// choice; residuals that are noise give Δχ² ≤ 0 on average)…
const MIN_EXACT_GAIN: f64 = 25.0;
/// …and by at least 5% of it (a change worth the slower mode).
const MIN_EXACT_SHARE: f64 = 0.05;
/// The θ_i trend of ln(data/fit) must be this many standard errors from zero, with a slope
/// against ln cos θ_i within ±0.5 of ±1 (what fitting radiance as S, or S as radiance, gives).
const MIN_TREND_T: f64 = 5.0;

/// What to try for a poor fit with statistics `g`: a robust loss, the exact mode, another
/// measurement quantity.
pub fn poor_fit_suggestions<F: Forward>(
    x: &Evidence<'_, '_, '_, F>,
    g: &GoodnessOfFit,
    slices: &[Slice],
) -> Vec<Suggestion> {
    let mut out = Vec::new();
    out.extend(robust_loss(x, g, slices));
    out.extend(exact_mode(x, g));
    out.extend(measurement(x));
    out
}

/// Samples that are isolated spikes along their scan, whatever the fit: ln y above (or below)
/// both neighbours by more than [`LARGE_RESIDUAL`] robust spreads of the second difference.
/// Model-free, so an l2 fit dragged by its outliers cannot hide them. (spikes, samples looked at)
fn spikes<F: Forward>(x: &Evidence<'_, '_, '_, F>, slices: &[Slice]) -> (usize, usize) {
    let nc = x.data.n_channels().max(1);
    // (sample, second difference, smaller one-sided jump when both have one sign, else 0)
    let mut d2: Vec<(usize, f64, f64)> = Vec::new();
    for s in slices {
        for c in 0..nc {
            let v: Vec<(usize, f64)> = s
                .samples
                .iter()
                .map(|&i| (i, x.data.values[i * nc + c]))
                .filter(|(_, y)| *y > 0.0 && y.is_finite())
                .map(|(i, y)| (i, y.ln()))
                .collect();
            for w in v.windows(3) {
                let (a, b) = (w[1].1 - w[0].1, w[1].1 - w[2].1);
                let jump = if a.signum() == b.signum() {
                    a.abs().min(b.abs())
                } else {
                    0.0
                };
                d2.push((w[1].0, 0.5 * (a + b), jump));
            }
        }
    }
    let spread: Vec<f64> = d2.iter().map(|t| t.1).collect();
    let Some(sd) = gof::robust_sd(&spread).filter(|s| *s > 0.0) else {
        return (0, 0);
    };
    let mut flagged: Vec<usize> = d2
        .iter()
        .filter(|(_, _, jump)| *jump > LARGE_RESIDUAL * sd)
        .map(|t| t.0)
        .collect();
    flagged.sort_unstable();
    flagged.dedup();
    let mut seen: Vec<usize> = d2.iter().map(|t| t.0).collect();
    seen.sort_unstable();
    seen.dedup();
    (flagged.len(), seen.len())
}

fn robust_loss<F: Forward>(
    x: &Evidence<'_, '_, '_, F>,
    g: &GoodnessOfFit,
    slices: &[Slice],
) -> Option<Suggestion> {
    if x.ev.loss != Loss::L2 {
        return None;
    }
    let noise = g.robust_noise?;
    let n = x.e.raw.len();
    let fraction = g.large_residuals as f64 / n.max(1) as f64;
    let share = g.large_residual_share.unwrap_or(0.0);
    let by_residuals =
        g.large_residuals > 0 && fraction <= MAX_OUTLIER_FRACTION && share >= MIN_OUTLIER_SHARE;
    let (spiky, looked) = spikes(x, slices);
    let spike_fraction = spiky as f64 / looked.max(1) as f64;
    let by_spikes = spiky >= MIN_SPIKES && spike_fraction <= MAX_OUTLIER_FRACTION;
    if !(by_residuals || by_spikes) {
        return None;
    }
    // With σ the residuals are in σ units and the default scale 1 fits; without σ the scale must
    // be stated in the residuals' own units: 3× their robust noise level.
    let action = if g.sigma_given {
        "--loss cauchy".to_string()
    } else {
        format!("--loss cauchy --loss-scale {:.2}", 3.0 * noise)
    };
    let mut evidence = Vec::new();
    if by_residuals {
        evidence.push(format!(
            "{} of {n} residuals ({:.1}%) lie beyond {LARGE_RESIDUAL} times the robust noise level {noise:.3e} and carry {:.0}% of the sum of squares",
            g.large_residuals,
            100.0 * fraction,
            100.0 * share
        ));
    }
    if by_spikes {
        evidence.push(format!(
            "{spiky} of {looked} samples ({:.1}%) are isolated spikes along their scan (ln value more than {LARGE_RESIDUAL} robust spreads above or below both neighbours)",
            100.0 * spike_fraction
        ));
    }
    Some(Suggestion {
        action,
        evidence: format!(
            "{}: a few bad samples dominate the l2 fit",
            evidence.join("; ")
        ),
    })
}

fn exact_mode<F: Forward>(x: &Evidence<'_, '_, '_, F>, g: &GoodnessOfFit) -> Option<Suggestion> {
    let nc = x.data.n_channels().max(1);
    // The exact root map at the fitted parameters and scales: how the residuals would change if
    // the data followed it (in the fit's normalised units).
    let mut s_exact = vec![0.0; x.e.model.len()];
    let has_exact = x
        .data
        .angles
        .par_chunks(CHUNK)
        .zip(s_exact.par_chunks_mut(CHUNK * nc))
        .map(|(a, out)| x.ev.forward.exact_values(x.params, a, out))
        .reduce(|| true, |a, b| a && b);
    if !has_exact {
        return None;
    }
    let w = x.ev.weights();
    let m = x.e.model.len();
    let d: Vec<f64> = (0..m)
        .map(|k| {
            let (cubic, ex) = (x.e.model[k], s_exact[k]);
            let d = match x.ev.space {
                Space::Log => w[k] * (ex.max(1e-300).ln() - cubic.max(1e-300).ln()),
                Space::Linear => w[k] * x.e.scale[k % nc] * (ex - cubic),
            };
            if d.is_finite() {
                d
            } else {
                0.0
            }
        })
        .collect();
    let noise = g.robust_noise.filter(|s| *s > 0.0)?;
    let clip = LARGE_RESIDUAL * noise;
    // Residuals clipped as the outlier test sees them; rows with a non-finite residual count
    // for neither sum.
    let (rc, d): (Vec<f64>, Vec<f64>) =
        x.e.raw
            .iter()
            .zip(d)
            .map(|(r, dk)| match r.is_finite() {
                true => (r.clamp(-clip, clip), dk),
                false => (0.0, 0.0),
            })
            .unzip();
    // A refit absorbs the part of that change the free parameters and scales can mimic: keep
    // the part orthogonal to the Jacobian's columns. The linearisation carries d and r along
    // (`[M | E] = Qᵀ[J | d r]`, chunked, J never stored), so the projection runs on its small
    // triangle with the same inner products.
    let free: Vec<f64> = x.ev.free.iter().map(|&p| p.get(x.params)).collect();
    let ones = vec![1.0; free.len()];
    let lin = x.ev.linearize_with(
        &free,
        &ones,
        ScaleMode::FixedNatural(&x.e.scale),
        &[&d, &rc],
        None,
    )?;
    if !lin.system.all_finite() {
        return None;
    }
    let d_perp = if lin.is_small() {
        let svd = lin.matrix().svd(true, false);
        let u = svd.u?;
        let smax = svd.singular_values.max();
        let mut d_perp = lin.extra.column(0).into_owned();
        for (j, &sv) in svd.singular_values.iter().enumerate() {
            if sv > 1e-10 * smax {
                let col = u.column(j);
                let c = col.dot(&d_perp);
                d_perp.axpy(-c, &col, 1.0);
            }
        }
        d_perp
    } else {
        // Many channels: by blocks, linear in channels (the dense M is channels²).
        crate::lm::blocks::orthogonal_part(&lin.system, &lin.extra.column(0).into_owned(), 1e-10)
    };
    let rd = lin.extra.column(1).dot(&d_perp);
    let dd = d_perp.norm_squared();
    let rr: f64 =
        x.e.raw
            .iter()
            .filter(|r| r.is_finite())
            .map(|r| r * r)
            .sum();
    // Linearised refit in exact mode: Σr² − Σ(r − d⊥)² = 2 r·d⊥ − |d⊥|², in noise units.
    let gain = (2.0 * rd - dd) / (noise * noise);
    let share = (2.0 * rd - dd) / rr;
    (gain > MIN_EXACT_GAIN && share > MIN_EXACT_SHARE).then(|| Suggestion {
        action: "--mode exact".into(),
        evidence: format!(
            "the residuals have the shape of the exact root map's difference from the cubic one at the fitted parameters: a linearised refit in exact mode lowers the sum of squares by {:.0}% ({gain:.0} noise variances)",
            100.0 * share
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

pub fn fix_undetermined(parameters: &[ParameterEntry]) -> Option<Suggestion> {
    let names: Vec<&str> = parameters
        .iter()
        .filter(|p| p.status == ParamStatus::Undetermined)
        .map(|p| p.name.as_str())
        .collect();
    if names.is_empty() {
        return None;
    }
    let example = parameters
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
