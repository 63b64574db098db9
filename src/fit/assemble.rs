//! The fit's typed result at the solver's final point ([`assemble`]): parameter values and
//! statuses with standard errors in natural units, the scale, correlations, residual
//! statistics, the curves at every sample, the warnings that explain them, and the verdict
//! ([`super::verdict`]) that says what the result is good for.

use std::time::Instant;

use rayon::prelude::*;

use super::diagnostics::{NULL_WEIGHT, POORLY_DETERMINED};
use super::problem::{Evaluation, Evaluator, FitData, FitParam, Forward, ParamSet, ScaleMode};
use super::verdict::Assessment;
use super::FitOutcome;
use crate::error::Result;
use crate::families::{FamilyParams, ModelRecords};
use crate::files::{
    finite, ChannelCorrelation, ChannelResiduals, Correlation, CurveValues, Curves, DataInfo,
    DownWeighted, FitJson, FitStatus, LoadReport, OptionsRecord, ParamStatus, ParameterEntry,
    ResidualSummary, ScaleEntry, StageTiming, Timing, TraceStage, DOWN_WEIGHT,
};
use crate::files::{CurvesMode, Verdict};
use crate::geometry::Angles;

/// Why the data cannot determine a parameter: words for its warning, from the parameter, the
/// fitted set and its strongly correlated partners (family-specific geometry).
pub type WhyUndetermined<'a, P> =
    &'a (dyn Fn(P, &<P as FitParam>::Set, &[String]) -> String + Sync);

/// What [`assemble`] needs from the fit driver.
pub struct Assembly<'a, 'e, 'f, F: Forward> {
    pub data: &'a FitData,
    pub file: &'a str,
    pub load_report: LoadReport,
    /// fit.json `model` (the Marschner configuration; for another family the lobes it
    /// draws), `chiang` and `terms`.
    pub records: ModelRecords,
    /// Every parameter of the family in output order (fit.json `parameters`).
    pub all: Vec<F::Param>,
    pub why: WhyUndetermined<'a, F::Param>,
    /// The parameter file of a fitted set (fit.json `params`, params.json).
    pub params_file: fn(&ParamSet<F>) -> FamilyParams,
    pub ev: &'e Evaluator<'f, F>,
    pub u: &'a [f64],
    pub status: FitStatus,
    pub options: OptionsRecord,
    pub warnings: Vec<String>,
    pub trace: Vec<TraceStage>,
    pub stage_times: Vec<StageTiming>,
    pub started: Instant,
}

/// The covariance of the free parameters and scales, in reporting units, with what makes a
/// column's standard error meaningless.
struct Uncertainty {
    cov: Option<crate::lm::ParameterCovariance>,
    null_w: Vec<f64>,
    col_zero: Vec<bool>,
    dof: usize,
    m: usize,
}

impl Uncertainty {
    /// Column `j`'s standard error, unless it is undetermined.
    fn std_of(&self, j: usize) -> Option<f64> {
        let c = self.cov.as_ref()?;
        if c.undetermined(j) || self.col_zero[j] || self.null_w[j] >= NULL_WEIGHT {
            return None;
        }
        finite(c.variance(j).max(0.0).sqrt())
    }
}

/// Jacobian in natural reporting units (degrees for angles) with the natural scales fixed.
fn uncertainty<F: Forward>(
    ev: &Evaluator<'_, F>,
    x: &[f64],
    scale: &[f64],
    warnings: &mut Vec<String>,
) -> Uncertainty {
    let col: Vec<f64> = ev.free.iter().map(|&p| 1.0 / p.report_factor()).collect();
    // Accumulated in chunks (MᵀM = JᵀJ, ‖t‖ = ‖r̃‖): the same covariance without storing J,
    // by channel blocks when there are many channels.
    let lin = ev
        .linearize(x, &col, ScaleMode::FixedNatural(scale), None)
        .expect("no cancel flag: the pass runs to the end");
    let m = lin.rows;
    let ncol = lin.system.ncols;
    let dof = m.saturating_sub(ncol);
    let (cov, null_w) = lin.covariance(dof);
    if cov.is_none() {
        warnings.push(format!(
            "no standard errors: {m} residuals for {ncol} parameters (dof = {dof}) or a non-finite Jacobian"
        ));
    }
    Uncertainty {
        null_w,
        col_zero: lin.zero_columns(),
        cov,
        dof,
        m,
    }
}

/// fit.json `correlation`: the whole matrix of the free parameters while it is small; with more
/// than [`Correlation::FULL_MAX`] of them (many channels) the shared parameters' matrix and each
/// per-channel parameter's correlations with them, so the record grows linearly in channels.
fn correlation_record<F: Forward>(
    ev: &Evaluator<'_, F>,
    unc: &Uncertainty,
    nc: usize,
) -> Correlation {
    let nf = ev.free.len();
    let corr = |i: usize, j: usize| unc.cov.as_ref().and_then(|c| finite(c.correlation(i, j)));
    let full = nf <= Correlation::FULL_MAX;
    let (shared, own): (Vec<usize>, Vec<usize>) =
        (0..nf).partition(|&j| full || ev.free[j].channel().is_none_or(|c| c >= nc));
    Correlation {
        names: shared.iter().map(|&j| ev.free[j].json_name()).collect(),
        matrix: shared
            .iter()
            .map(|&i| shared.iter().map(|&j| corr(i, j)).collect())
            .collect(),
        per_channel: own
            .iter()
            .map(|&i| ChannelCorrelation {
                name: ev.free[i].json_name(),
                with_shared: shared.iter().map(|&j| corr(i, j)).collect(),
            })
            .collect(),
    }
}

/// Every parameter's entry in output order, with the warnings that explain its status.
fn parameter_entries<F: Forward>(
    ev: &Evaluator<'_, F>,
    all: &[F::Param],
    why_undetermined: WhyUndetermined<'_, F::Param>,
    params: &ParamSet<F>,
    unc: &Uncertainty,
    warnings: &mut Vec<String>,
) -> Vec<ParameterEntry> {
    let nf = ev.free.len();
    // Statistically undetermined: the standard error exceeds the whole typical range (the data
    // say less than the prior box does), even when JᵀJ is numerically invertible.
    let range_width = |p: F::Param| {
        let (a, b) = p.typical_range();
        (b - a) * p.report_factor()
    };
    let why = |p: F::Param, partners: &[String]| why_undetermined(p, params, partners);
    let mut parameters = Vec::new();
    for &p in all {
        let value = p.get(params) * p.report_factor();
        let entry = match ev.free.iter().position(|q| *q == p) {
            Some(j) => {
                let se = unc.std_of(j);
                let too_wide = se.is_some_and(|e| e > range_width(p));
                let undetermined = unc.col_zero[j]
                    || too_wide
                    || unc.null_w[j] >= NULL_WEIGHT
                    || unc.cov.as_ref().is_some_and(|c| c.undetermined(j));
                let partners: Vec<String> = match &unc.cov {
                    Some(c) => c
                        .neighbours(j)
                        .into_iter()
                        .filter(|&k| k < nf && k != j && c.correlation(j, k).abs() > 0.99)
                        .map(|k| ev.free[k].json_name())
                        .collect(),
                    None => Vec::new(),
                };
                let status = if undetermined {
                    warnings.push(format!(
                        "{}: not determined by the data ({}); value is the best fit but has no standard error",
                        p.json_name(),
                        if unc.col_zero[j] {
                            "S does not depend on it at any sample".to_string()
                        } else if too_wide {
                            format!(
                                "standard error {:.3e} exceeds its whole typical range; {}",
                                se.unwrap_or(f64::NAN),
                                why(p, &partners)
                            )
                        } else {
                            why(p, &partners)
                        }
                    ));
                    ParamStatus::Undetermined
                } else if p.bound().at_bound(p.get(params)) {
                    warnings.push(format!(
                        "{}: at its bound {:.6} (the data push it there; its standard error is one-sided; {})",
                        p.json_name(),
                        value,
                        why(p, &partners)
                    ));
                    ParamStatus::AtBound
                } else {
                    if let Some(e) = se.filter(|&e| e > POORLY_DETERMINED * range_width(p)) {
                        warnings.push(format!(
                            "{}: poorly determined (standard error {e:.3e} is {:.0}% of its typical range; {})",
                            p.json_name(),
                            100.0 * e / range_width(p),
                            why(p, &partners)
                        ));
                    }
                    ParamStatus::Free
                };
                ParameterEntry {
                    name: p.json_name(),
                    value: finite(value),
                    std_error: if undetermined { None } else { se },
                    status,
                    interval_68: None,
                    interval_95: None,
                    profile: Vec::new(),
                    profile_method: None,
                }
            }
            None => ParameterEntry {
                name: p.json_name(),
                value: finite(value),
                std_error: None,
                status: ParamStatus::Fixed,
                interval_68: None,
                interval_95: None,
                profile: Vec::new(),
                profile_method: None,
            },
        };
        if entry.value.is_none() {
            warnings.push(format!(
                "{}: value is not finite; written as null",
                p.json_name()
            ));
        }
        parameters.push(entry);
    }
    parameters
}

/// Residual statistics in the fit space (normalised residuals), overall and per channel.
fn residual_summary<F: Forward>(
    ev: &Evaluator<'_, F>,
    data: &FitData,
    e: &Evaluation,
    unc: &Uncertainty,
) -> ResidualSummary {
    let nc = data.n_channels();
    let (m, dof) = (unc.m, unc.dof);
    let raw_ss: f64 = e.raw.iter().map(|r| r * r).sum();
    let rt_ss: f64 = e.residual.iter().map(|r| r * r).sum();
    let per_channel = (0..nc)
        .map(|c| {
            let rr: Vec<f64> = e.raw.iter().skip(c).step_by(nc).copied().collect();
            let rt: f64 = e.residual.iter().skip(c).step_by(nc).map(|r| r * r).sum();
            let n = rr.len() as f64;
            // Each channel carries its share of the degrees of freedom.
            let dof_c = n * dof as f64 / m.max(1) as f64;
            ChannelResiduals {
                channel: data.channels[c].clone(),
                rms: finite((rr.iter().map(|r| r * r).sum::<f64>() / n).sqrt()),
                reduced_chi2: finite(rt / dof_c),
            }
        })
        .collect();
    ResidualSummary {
        space: ev.space.to_string(),
        loss: ev.loss.to_string(),
        rms: finite((raw_ss / m.max(1) as f64).sqrt()),
        reduced_chi2: finite(rt_ss / dof as f64),
        dof,
        per_channel,
        down_weighted: down_weighted(ev, data, e),
    }
}

/// Robust losses: the values the loss really discounted (weight below [`DOWN_WEIGHT`]).
fn down_weighted<F: Forward>(
    ev: &Evaluator<'_, F>,
    data: &FitData,
    e: &Evaluation,
) -> Option<DownWeighted> {
    if ev.loss == super::Loss::L2 {
        return None;
    }
    let nc = data.n_channels();
    let hit: Vec<usize> = (0..e.robust_weight.len())
        .filter(|&k| e.robust_weight[k] < DOWN_WEIGHT)
        .collect();
    let mut lines: Vec<u64> = hit
        .iter()
        .map(|&k| {
            data.line
                .get(k / nc)
                .copied()
                .unwrap_or((k / nc) as u64 + 1)
        })
        .collect();
    lines.dedup();
    lines.truncate(DownWeighted::MAX_LINES);
    Some(DownWeighted {
        threshold: DOWN_WEIGHT,
        count: hit.len(),
        lines,
    })
}

/// Samples per chunk of [`curves_of`]'s per-lobe pass: whole lane groups, and enough chunks
/// for both cores on small fits.
const CURVE_CHUNK: usize = 256;

/// One row per channel of each sample in `samples` (indices into `data`, in order): the data,
/// the fit and its lobes (with the evaluator's measurement factor and the fitted scale), the
/// residual and the robust weight, computed in parallel straight into the table's columns (no
/// row values, no channel name per row).
fn curves_of<F: Forward>(
    ev: &Evaluator<'_, F>,
    data: &FitData,
    params: &ParamSet<F>,
    e: &Evaluation,
    samples: &[usize],
) -> Curves {
    let nc = data.n_channels();
    let fwd = ev.forward;
    let mut values = vec![CurveValues::MISSING; samples.len() * nc];
    // Per-lobe values a chunk of samples at a time (a family may run them on its lanes).
    values
        .par_chunks_mut(CURVE_CHUNK * nc.max(1))
        .zip(samples.par_chunks(CURVE_CHUNK))
        .for_each(|(rows, chunk)| {
            let angles: Vec<Angles> = chunk.iter().map(|&i| data.angles[i]).collect();
            let mut lobes = vec![[0.0; 3]; chunk.len() * nc];
            let ok = fwd.by_lobe_batch(params, &angles, &mut lobes);
            for (j, v) in rows.iter_mut().enumerate() {
                let (i, c) = (chunk[j / nc.max(1)], j % nc.max(1));
                let k = i * nc + c;
                let s = e.scale[c];
                let l = if ok { lobes[j] } else { [f64::NAN; 3] };
                *v = CurveValues {
                    data: data.values[k],
                    sigma: data.sigma.as_ref().map_or(f64::NAN, |s| s[k]),
                    fit: s * e.model[k],
                    fit_r: s * l[0],
                    fit_tt: s * l[1],
                    fit_trt: s * l[2],
                    residual: e.raw[k],
                    weight: e.robust_weight[k],
                };
            }
        });
    let n = samples.len();
    Curves {
        channels: data.channels.clone(),
        sample_id: samples.iter().map(|&i| i as u64).collect(),
        sample_line: samples
            .iter()
            .map(|&i| data.line.get(i).copied().unwrap_or(i as u64 + 1))
            .collect(),
        sample_angles: samples.iter().map(|&i| data.angles_deg(i)).collect(),
        row_sample: (0..n * nc).map(|k| (k / nc.max(1)) as u32).collect(),
        row_channel: (0..n * nc).map(|k| (k % nc.max(1)) as u32).collect(),
        values,
    }
}

/// The log-space scale and a linear noise model's differ by more than this factor's share (and
/// three standard errors) only when the shape misses the data: for a model that describes them,
/// the geometric-mean bias of log residuals is 0.5–1.5 σ_rel², 3.4% at 15% relative noise.
const NOISE_MODELS_AGREE: f64 = 0.05;

/// A warning per channel whose log-space scale (the one reported) and linear noise-model scale
/// disagree: the fit's cost decides, and the summary says the other would differ.
fn noise_models_disagree(
    scale: &[ScaleEntry],
    linear: &[f64],
    loss: super::Loss,
    warnings: &mut Vec<String>,
) {
    for (s, &l) in scale.iter().zip(linear) {
        let Some(v) = s.value else { continue };
        let ratio = l / v;
        let se = s.std_error.unwrap_or(0.0);
        if ratio.is_finite() && (ratio - 1.0).abs() > NOISE_MODELS_AGREE && (l - v).abs() > 3.0 * se
        {
            warnings.push(format!(
                "scale[{}]: the log-space {loss} cost the fit minimised puts it at {v:.4e}; a linear noise model (residuals y − s·S weighted by 1/sigma) would put it at {l:.4e}, {ratio:.3}× that: the model's shape misses the data and the two noise models weigh its misses differently. Every number reported (scale, chi2, errors, verdict) is the log-space cost's; fit with --space linear for the other",
                s.channel
            ));
        }
    }
}

/// ‖fit − data‖ / ‖data‖ over every row. Both sums overflow on values near 1e300: then the
/// ratio is NaN and the data are not known to be exact.
fn relative_misfit(data: &FitData, e: &Evaluation) -> f64 {
    let nc = data.n_channels().max(1);
    let (misfit, size) = data
        .values
        .iter()
        .enumerate()
        .fold((0.0, 0.0), |(m, s), (k, &d)| {
            (m + (e.scale[k % nc] * e.model[k] - d).powi(2), s + d * d)
        });
    (misfit / size).sqrt()
}

/// max over rows of |fit − data| / max(|data|, 1e-9 · the channel's largest |data|): relative
/// where the data are within nine decades of their peak, absolute below (a model's tail there
/// is rounding of its peak). NaN when a value or fit is not finite.
fn worst_row_misfit(data: &FitData, e: &Evaluation) -> f64 {
    let nc = data.n_channels().max(1);
    let mut peak = vec![0.0f64; nc];
    for (k, &d) in data.values.iter().enumerate() {
        peak[k % nc] = peak[k % nc].max(d.abs());
    }
    data.values
        .iter()
        .enumerate()
        .map(|(k, &d)| {
            let c = k % nc;
            (e.scale[c] * e.model[k] - d).abs() / d.abs().max(1e-9 * peak[c])
        })
        .fold(0.0, |m, r| {
            if r.is_nan() || m.is_nan() {
                f64::NAN
            } else {
                m.max(r)
            }
        })
}

/// The samples whose rows curves.csv gets under `mode`: all, the summary's, or none.
fn written_samples(mode: CurvesMode, data: &FitData, e: &Evaluation) -> Vec<usize> {
    let nc = data.n_channels().max(1);
    match mode {
        CurvesMode::Full => (0..data.len()).collect(),
        CurvesMode::Summary => crate::slices::summary_samples(
            data.len(),
            |i| data.angles_deg(i),
            |i| {
                e.robust_weight[i * nc..(i + 1) * nc]
                    .iter()
                    .any(|&w| w < DOWN_WEIGHT)
            },
        ),
        CurvesMode::None => Vec::new(),
    }
}

/// Build the outcome (fit.json content, parameters, curves, timing) at solver parameters `u`.
pub fn assemble<F: Forward>(a: Assembly<'_, '_, '_, F>) -> Result<FitDraft<ParamSet<F>>> {
    let Assembly {
        data,
        file,
        load_report,
        records,
        all,
        why,
        params_file,
        ev,
        u,
        status,
        options,
        mut warnings,
        trace,
        mut stage_times,
        started,
    } = a;
    // A file a command loaded: its loader's settings and warnings are the fit's.
    let mut options = options;
    if let Some(settings) = &load_report.settings {
        options.load = Some(settings.clone());
        warnings.splice(0..0, load_report.warnings.iter().cloned());
    }
    let load_s = load_report.seconds;
    // Each statistics step's wall time joins the solver stages' in timing.json.
    let mut clock = Instant::now();
    let mut lap = |stage: &str| {
        stage_times.push(StageTiming {
            stage: stage.into(),
            wall_s: clock.elapsed().as_secs_f64(),
        });
        clock = Instant::now();
    };
    let nc = data.n_channels();
    let nf = ev.free.len();
    let x = ev.natural(&u[..nf]);
    let mut params = ev.params_at(&x);
    // Transforms keep x inside; clamp anyway so rounding can never leave the domain.
    for &p in &ev.free {
        let v = p.get(&params);
        p.set(&mut params, p.bound().clamp(v));
    }
    // Everything reported (scale, χ², errors, verdict) is the cost the fit minimised at `u`.
    let e = ev.eval_internal(u, false);
    let linear_scale = ev.linear_noise_scale(&e, data.sigma.is_some());
    let unc = uncertainty(ev, &x, &e.scale, &mut warnings);
    let parameters = parameter_entries(ev, &all, why, &params, &unc, &mut warnings);
    let scale: Vec<ScaleEntry> = (0..nc)
        .map(|c| ScaleEntry {
            channel: data.channels[c].clone(),
            value: finite(e.scale[c]),
            std_error: unc.std_of(nf + c),
            linear_noise_value: linear_scale.as_ref().and_then(|l| finite(l[c])),
        })
        .collect();
    if let Some(l) = &linear_scale {
        noise_models_disagree(&scale, l, ev.loss, &mut warnings);
    }
    for s in scale.iter().filter(|s| s.std_error.is_none()) {
        warnings.push(format!(
            "scale[{}]: no standard error: it trades off with parameters the data do not determine",
            s.channel
        ));
    }
    let correlation = correlation_record(ev, &unc, nc);
    let residuals = residual_summary(ev, data, &e, &unc);
    lap("standard_errors");
    // Everything fixed: no solver unknowns, the scales come in closed form (variable
    // projection). The solver has nothing to run on and says `failed`; the fit is complete.
    let status = if ev.n_params() == 0 && status == FitStatus::Failed && e.cost().is_finite() {
        FitStatus::Converged
    } else {
        status
    };
    let worst_row = worst_row_misfit(data, &e);
    // The assessment and the curves read the optimum alone, not each other: computed side by
    // side (the assessment's serial parts no longer leave a core idle), each stage timed alone.
    let ((assessment, verdict_s), (curves, curves_s)) = rayon::join(
        || {
            let t = Instant::now();
            let assessment = super::verdict::assess(&super::evidence::Evidence {
                data,
                ev,
                e: &e,
                worst_row_misfit: worst_row,
                params: &params,
                status,
                parameters: &parameters,
                scale: &scale,
                trace: &trace,
                warnings: &warnings,
                dof: unc.dof,
            });
            (assessment, t.elapsed())
        },
        || {
            let t = Instant::now();
            let samples = written_samples(options.curves, data, &e);
            (curves_of(ev, data, &params, &e, &samples), t.elapsed())
        },
    );
    if curves.values.iter().any(|r| {
        ![r.fit, r.fit_r, r.fit_tt, r.fit_trt, r.residual, r.weight]
            .iter()
            .all(|v| v.is_finite())
    }) {
        warnings
            .push("curves.csv: some fitted values are not finite; written as empty cells".into());
    }
    for (stage, took) in [("verdict", verdict_s), ("curves", curves_s)] {
        stage_times.push(StageTiming {
            stage: stage.into(),
            wall_s: took.as_secs_f64(),
        });
    }

    let json = FitJson {
        hairfit_version: env!("CARGO_PKG_VERSION").into(),
        status,
        data: DataInfo {
            file: file.into(),
            channels: data.channels.clone(),
            n_samples: data.len(),
            load_report,
        },
        model: records.config,
        options,
        params: params_file(&params),
        parameters,
        scale,
        correlation,
        warnings,
        residuals,
        trace,
        // Decided once, after the profiles: FitDraft::finish.
        verdict: Verdict::default(),
        reasons: Vec::new(),
        goodness_of_fit: Default::default(),
        suggestions: Vec::new(),
        family_record: records.family_record,
        terms: records.terms,
    };
    Ok(FitDraft {
        outcome: FitOutcome {
            json,
            params,
            curves,
            relative_misfit: relative_misfit(data, &e),
            worst_row_misfit: worst_row,
            curve_slices: None,
            timing: Timing {
                wall_time_s: started.elapsed().as_secs_f64(),
                stages: stage_times,
                load_s,
                ..Timing::default()
            },
        },
        assessment,
    })
}

/// A fit measured at its optimum whose verdict is not decided yet: the interval stage reads it
/// ([`super::profile::intervals`]), then [`FitDraft::finish`] writes the stage's findings, decides
/// the verdict once and hands the outcome over, not to be edited again.
pub struct FitDraft<P> {
    pub outcome: FitOutcome<P>,
    pub assessment: Assessment,
}

impl<P> FitDraft<P> {
    /// The finished outcome: the interval stage's intervals written, then the verdict, its
    /// reasons and suggestions decided from the assessment and the profiled parameters
    /// ([`super::verdict::decide`]).
    pub fn finish(
        self,
        data: &FitData,
        intervals: super::profile::IntervalStage,
        started: std::time::Instant,
    ) -> FitOutcome<P> {
        let FitDraft {
            mut outcome,
            assessment,
        } = self;
        super::profile::write_into(&mut outcome, intervals, started);
        // Full curves hold every sample in the data's order: the verdict's slices are theirs.
        if outcome.json.options.curves == CurvesMode::Full {
            outcome.curve_slices = Some(assessment.scan_slices().clone());
        }
        let judgement = super::verdict::decide(&assessment, &outcome.json, data);
        outcome.json.verdict = judgement.verdict;
        outcome.json.reasons = judgement.reasons;
        outcome.json.goodness_of_fit = judgement.goodness_of_fit;
        outcome.json.suggestions = judgement.suggestions;
        outcome
    }
}
