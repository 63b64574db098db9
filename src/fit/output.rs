//! The fit's outputs: `fit.json` (contracts.md), `params.json` (a plain `ParamFile`) and
//! `curves.csv`, all written atomically, plus the one-screen summary. Non-finite numbers never
//! reach a file: they become `null` with a warning.

use std::f64::consts::PI;
use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use super::bounds::{get, report_factor, typical_range, Bound};

/// A standard error above this fraction of the typical range earns a "poorly determined" warning.
pub const POORLY_DETERMINED: f64 = 0.2;
use super::problem::{Evaluator, FitData, Forward, ModelForward, ScaleMode};
use super::solve::RunStatus;
use super::{all_parameters, FitOutcome, StageTrace};
use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::model::{Effects, ModelConfig, ParamName, RootMode};
use crate::params::ParamFile;

/// A parameter whose unit column-scaled direction has at least this weight (squared component)
/// in the numerical null space of the Jacobian moves along a direction the data do not see:
/// 1e-6 is a component of 1e-3, far above the rounding of an SVD (~1e-15) yet catching partners
/// of an undetermined parameter that would otherwise get a meaningless tiny standard error.
const NULL_WEIGHT: f64 = 1e-6;

/// Per column of `j`, the weight of its unit vector in the numerical null space of the
/// column-scaled `j` (singular values below `lm::DEFAULT_RCOND`·σ_max), via QR then SVD of R.
fn null_space_weights(j: &nalgebra::DMatrix<f64>) -> Vec<f64> {
    let n = j.ncols();
    if n == 0 || j.nrows() < n || j.iter().any(|v| !v.is_finite()) {
        return vec![0.0; n];
    }
    let mut scaled = j.clone();
    for mut col in scaled.column_iter_mut() {
        let norm = col.norm();
        if norm > 0.0 {
            col /= norm;
        }
    }
    let r = scaled.qr().r();
    let svd = r.svd(false, true);
    let Some(v_t) = svd.v_t else {
        return vec![0.0; n];
    };
    let smax = svd.singular_values.max();
    let mut w = vec![0.0; n];
    for (k, &s) in svd.singular_values.iter().enumerate() {
        if s <= crate::lm::DEFAULT_RCOND * smax {
            for (j, wj) in w.iter_mut().enumerate() {
                *wj += v_t[(k, j)].powi(2);
            }
        }
    }
    w
}

/// `Some(x)` when finite.
fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

#[derive(Debug, Clone, Serialize)]
pub struct DataInfo {
    pub file: String,
    pub channels: Vec<String>,
    pub n_samples: usize,
    pub load_report: serde_json::Value,
}

#[derive(Debug, Clone, Serialize)]
pub struct ModelInfo {
    pub mode: RootMode,
    pub effects: Effects,
}

#[derive(Debug, Clone, Serialize)]
pub struct ParamEntry {
    pub name: String,
    pub value: Option<f64>,
    pub std_error: Option<f64>,
    /// `free`, `fixed`, `at_bound` or `undetermined`.
    pub status: String,
}

#[derive(Debug, Clone, Serialize)]
pub struct ScaleEntry {
    pub channel: String,
    pub value: Option<f64>,
    pub std_error: Option<f64>,
}

#[derive(Debug, Clone, Serialize)]
pub struct Correlation {
    pub names: Vec<String>,
    pub matrix: Vec<Vec<Option<f64>>>,
}

#[derive(Debug, Clone, Serialize)]
pub struct ChannelStats {
    pub channel: String,
    pub rms: Option<f64>,
    pub reduced_chi2: Option<f64>,
}

#[derive(Debug, Clone, Serialize)]
pub struct ResidualStats {
    pub space: String,
    pub loss: String,
    pub rms: Option<f64>,
    pub reduced_chi2: Option<f64>,
    pub dof: usize,
    pub per_channel: Vec<ChannelStats>,
}

/// fit.json, field names fixed by contracts.md.
#[derive(Debug, Clone, Serialize)]
pub struct FitJson {
    pub hairfit_version: String,
    pub status: String,
    pub data: DataInfo,
    pub model: ModelInfo,
    pub options: serde_json::Value,
    pub params: ParamFile,
    pub parameters: Vec<ParamEntry>,
    pub scale: Vec<ScaleEntry>,
    pub correlation: Correlation,
    pub warnings: Vec<String>,
    pub residuals: ResidualStats,
    pub trace: Vec<StageTrace>,
    pub wall_time_s: f64,
}

/// One row of curves.csv (one sample, one channel; angles in degrees; fits include the scale).
#[derive(Debug, Clone, Serialize)]
pub struct CurveRow {
    pub sample: usize,
    pub line: u64,
    pub channel: String,
    pub theta_i: f64,
    pub phi_i: f64,
    pub theta_r: f64,
    pub phi_r: f64,
    pub data: f64,
    pub sigma: Option<f64>,
    pub fit: f64,
    pub fit_r: f64,
    pub fit_tt: f64,
    pub fit_trt: f64,
    pub residual: f64,
    pub weight: f64,
}

/// What [`assemble`] needs from the fit driver.
pub struct Assembly<'a, 'e, 'f> {
    pub data: &'a FitData,
    pub file: &'a str,
    pub load_report: serde_json::Value,
    pub config: ModelConfig,
    pub ev: &'e Evaluator<'f, ModelForward>,
    pub u: &'a [f64],
    pub status: RunStatus,
    pub options: serde_json::Value,
    pub warnings: Vec<String>,
    pub trace: Vec<StageTrace>,
    pub started: Instant,
}

/// Wrap an azimuth to (−π, π].
fn wrap(x: f64) -> f64 {
    let y = (x + PI).rem_euclid(2.0 * PI) - PI;
    if y <= -PI {
        y + 2.0 * PI
    } else {
        y
    }
}

/// Samples within 2 w_c of a glint azimuth ±φ_c(θ_d) (exact caustic, circular fiber, index η),
/// and the span of |φ| they cover.
fn samples_near_glint(data: &FitData, eta: f64, w_c: f64) -> (usize, f64) {
    let near: Vec<f64> = data
        .angles
        .iter()
        .filter(|a| {
            let td = 0.5 * (a.theta_r - a.theta_i);
            let (s, c) = td.sin_cos();
            let ep = (eta * eta - s * s).sqrt() / c;
            if ep.is_nan() || ep >= 2.0 {
                return false;
            }
            let hc = ((4.0 - ep * ep) / 3.0).sqrt();
            let phic = wrap(4.0 * (hc / ep).asin() - 2.0 * hc.asin() + 2.0 * PI).abs();
            let phi = wrap(a.phi_r - a.phi_i).abs();
            (phi - phic).abs() < 2.0 * w_c
        })
        .map(|a| wrap(a.phi_r - a.phi_i).abs())
        .collect();
    let span = near.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - near.iter().copied().fold(f64::INFINITY, f64::min);
    (near.len(), if near.is_empty() { 0.0 } else { span })
}

/// Why the data cannot determine `p` (geometry first, else the correlated partners).
fn why_undetermined(
    p: ParamName,
    data: &FitData,
    params: &crate::model::Params<f64>,
    partners: &[String],
) -> String {
    let tail = if partners.is_empty() {
        String::new()
    } else {
        format!("; strongly correlated with {}", partners.join(", "))
    };
    match p {
        ParamName::KG | ParamName::WC => {
            let (n, span) = samples_near_glint(data, params.eta, params.w_c);
            if n == 0 {
                format!("no sample near the glint (|phi - phi_c| < 2 w_c){tail}")
            } else if span < params.w_c {
                format!(
                    "the {n} sample(s) near the glint span only {:.1} deg of |phi|: its width and height trade off{tail}",
                    span.to_degrees()
                )
            } else {
                format!("{n} sample(s) near the glint (|phi - phi_c| < 2 w_c){tail}")
            }
        }
        ParamName::Eccentricity => {
            let c2: Vec<f64> = data
                .angles
                .iter()
                .map(|a| (a.phi_i + a.phi_r).cos())
                .collect();
            let spread = c2.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - c2.iter().copied().fold(f64::INFINITY, f64::min);
            format!("the samples span cos(2 phi_h) by only {spread:.3}: eccentricity acts through phi_h{tail}")
        }
        ParamName::SigmaA(_) => {
            let n = data
                .angles
                .iter()
                .filter(|a| wrap(a.phi_r - a.phi_i).abs() > 0.75 * PI)
                .count();
            format!(
                "absorption shows in TT/TRT; {n} sample(s) have |phi| > 135 deg (TT region){tail}"
            )
        }
        ParamName::AlphaR | ParamName::BetaR => {
            let th: Vec<f64> = data
                .angles
                .iter()
                .map(|a| 0.5 * (a.theta_i + a.theta_r))
                .collect();
            let spread = th.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - th.iter().copied().fold(f64::INFINITY, f64::min);
            format!(
                "the samples span theta_h by {:.1} deg only: the longitudinal lobe shape needs a scan across it{tail}",
                spread.to_degrees()
            )
        }
        _ => format!("the data do not constrain it{tail}"),
    }
}

/// Build the outcome (fit.json content, parameters, curves) at solver parameters `u`.
pub fn assemble(a: Assembly<'_, '_, '_>) -> Result<FitOutcome> {
    let Assembly {
        data,
        file,
        load_report,
        config,
        ev,
        u,
        status,
        options,
        mut warnings,
        trace,
        started,
    } = a;
    let nc = data.n_channels();
    let nf = ev.free.len();
    let x = ev.natural(&u[..nf]);
    let mut params = ev.params_at(&x);
    // Transforms keep x inside; clamp anyway so rounding can never leave the domain.
    for &p in &ev.free {
        let v = get(&params, p);
        super::bounds::set(&mut params, p, Bound::of(p).clamp(v));
    }
    let e = ev.eval_internal(u, false);
    let scale = e.scale.clone();

    // Standard errors: Jacobian in natural reporting units (degrees for angles) + natural scales.
    let col: Vec<f64> = ev.free.iter().map(|&p| 1.0 / report_factor(p)).collect();
    let ej = ev.evaluate(&x, &col, ScaleMode::FixedNatural(&scale), true);
    let m = ej.residual.len();
    let ncol = ej.n_cols;
    let jm = nalgebra::DMatrix::from_row_slice(m, ncol, ej.jacobian.as_deref().unwrap_or(&[]));
    let ss: f64 = ej.residual.iter().map(|r| r * r).sum();
    let dof = m.saturating_sub(ncol);
    let cov = crate::lm::covariance(&jm, ss, dof);
    if cov.is_none() {
        warnings.push(format!(
            "no standard errors: {} residuals for {} parameters (dof = {dof}) or a non-finite Jacobian",
            m, ncol
        ));
    }
    let null_w = null_space_weights(&jm);
    let col_zero: Vec<bool> = (0..ncol)
        .map(|j| jm.column(j).iter().all(|v| *v == 0.0))
        .collect();
    let std_of = |j: usize| -> Option<f64> {
        let c = cov.as_ref()?;
        if c.undetermined[j] || col_zero[j] || null_w[j] >= NULL_WEIGHT {
            return None;
        }
        finite(c.matrix[(j, j)].max(0.0).sqrt())
    };
    // Statistically undetermined: the standard error exceeds the whole typical range (the data
    // say less than the prior box does), even when JᵀJ is numerically invertible.
    let range_width = |p: ParamName| {
        let (a, b) = typical_range(p);
        (b - a) * report_factor(p)
    };
    let corr = cov.as_ref().map(|c| crate::lm::correlation(&c.matrix));

    let mut parameters = Vec::new();
    for p in all_parameters(nc) {
        let f = report_factor(p);
        let value = get(&params, p) * f;
        let entry = match ev.free.iter().position(|q| *q == p) {
            Some(j) => {
                let se = std_of(j);
                let too_wide = se.is_some_and(|e| e > range_width(p));
                let undetermined = col_zero[j]
                    || too_wide
                    || null_w[j] >= NULL_WEIGHT
                    || cov.as_ref().is_some_and(|c| c.undetermined[j]);
                let partners: Vec<String> = match &corr {
                    Some(r) => (0..nf)
                        .filter(|&k| k != j && r[(j, k)].abs() > 0.99)
                        .map(|k| ev.free[k].json_name())
                        .collect(),
                    None => Vec::new(),
                };
                let status = if undetermined {
                    warnings.push(format!(
                        "{}: not determined by the data ({}); value is the best fit but has no standard error",
                        p.json_name(),
                        if col_zero[j] {
                            "S does not depend on it at any sample".to_string()
                        } else if too_wide {
                            format!(
                                "standard error {:.3e} exceeds its whole typical range; {}",
                                se.unwrap_or(f64::NAN),
                                why_undetermined(p, data, &params, &partners)
                            )
                        } else {
                            why_undetermined(p, data, &params, &partners)
                        }
                    ));
                    "undetermined"
                } else if Bound::of(p).at_bound(get(&params, p)) {
                    warnings.push(format!(
                        "{}: at its bound {:.6} (the data push it there; its standard error is one-sided; {})",
                        p.json_name(),
                        value,
                        why_undetermined(p, data, &params, &partners)
                    ));
                    "at_bound"
                } else {
                    if let Some(e) = se.filter(|&e| e > POORLY_DETERMINED * range_width(p)) {
                        warnings.push(format!(
                            "{}: poorly determined (standard error {e:.3e} is {:.0}% of its typical range; {})",
                            p.json_name(),
                            100.0 * e / range_width(p),
                            why_undetermined(p, data, &params, &partners)
                        ));
                    }
                    "free"
                };
                ParamEntry {
                    name: p.json_name(),
                    value: finite(value),
                    std_error: if undetermined { None } else { se },
                    status: status.into(),
                }
            }
            None => ParamEntry {
                name: p.json_name(),
                value: finite(value),
                std_error: None,
                status: "fixed".into(),
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
    let scale_entries: Vec<ScaleEntry> = (0..nc)
        .map(|c| ScaleEntry {
            channel: data.channels[c].clone(),
            value: finite(scale[c]),
            std_error: std_of(nf + c),
        })
        .collect();
    for e in scale_entries.iter().filter(|e| e.std_error.is_none()) {
        warnings.push(format!(
            "scale[{}]: no standard error: it trades off with parameters the data do not determine",
            e.channel
        ));
    }
    let correlation = Correlation {
        names: ev.free.iter().map(|p| p.json_name()).collect(),
        matrix: (0..nf)
            .map(|i| {
                (0..nf)
                    .map(|j| corr.as_ref().and_then(|r| finite(r[(i, j)])))
                    .collect()
            })
            .collect(),
    };

    // Residual statistics in the fit space (normalised residuals).
    let raw_ss: f64 = e.raw.iter().map(|r| r * r).sum();
    let rt_ss: f64 = e.residual.iter().map(|r| r * r).sum();
    let per_channel = (0..nc)
        .map(|c| {
            let rr: Vec<f64> = e.raw.iter().skip(c).step_by(nc).copied().collect();
            let rt: f64 = e.residual.iter().skip(c).step_by(nc).map(|r| r * r).sum();
            let n = rr.len() as f64;
            // Each channel carries its share of the degrees of freedom.
            let dof_c = n * dof as f64 / m.max(1) as f64;
            ChannelStats {
                channel: data.channels[c].clone(),
                rms: finite((rr.iter().map(|r| r * r).sum::<f64>() / n).sqrt()),
                reduced_chi2: finite(rt / dof_c),
            }
        })
        .collect();
    let residuals = ResidualStats {
        space: ev.space.to_string(),
        loss: ev.loss.to_string(),
        rms: finite((raw_ss / m.max(1) as f64).sqrt()),
        reduced_chi2: finite(rt_ss / dof as f64),
        dof,
        per_channel,
    };

    // Curves.
    let fwd = ModelForward { config };
    // Per-lobe values in parallel, one Vec per sample, collected in sample order.
    let lobes_all: Vec<Option<Vec<[f64; 3]>>> = data
        .angles
        .par_iter()
        .map(|ang| {
            let mut lobes = vec![[0.0; 3]; nc];
            fwd.by_lobe(&params, ang, &mut lobes).then_some(lobes)
        })
        .collect();
    let mut curves = Vec::with_capacity(m);
    for (i, ang) in data.angles.iter().enumerate() {
        for c in 0..nc {
            let k = i * nc + c;
            let s = scale[c];
            let fit = s * e.model[k];
            let (fr, ft, ftrt) = match &lobes_all[i] {
                Some(l) => (s * l[c][0], s * l[c][1], s * l[c][2]),
                None => (f64::NAN, f64::NAN, f64::NAN),
            };
            curves.push(CurveRow {
                sample: i,
                line: data.line.get(i).copied().unwrap_or(i as u64 + 1),
                channel: data.channels[c].clone(),
                theta_i: ang.theta_i.to_degrees(),
                phi_i: ang.phi_i.to_degrees(),
                theta_r: ang.theta_r.to_degrees(),
                phi_r: ang.phi_r.to_degrees(),
                data: data.values[k],
                sigma: data.sigma.as_ref().map(|s| s[k]),
                fit,
                fit_r: fr,
                fit_tt: ft,
                fit_trt: ftrt,
                residual: e.raw[k],
                weight: e.robust_weight[k],
            });
        }
    }
    if curves.iter().any(|r| {
        ![r.fit, r.fit_r, r.fit_tt, r.fit_trt, r.residual, r.weight]
            .iter()
            .all(|v| v.is_finite())
    }) {
        warnings
            .push("curves.csv: some fitted values are not finite; written as empty cells".into());
    }

    let json = FitJson {
        hairfit_version: env!("CARGO_PKG_VERSION").into(),
        status: status.as_str().into(),
        data: DataInfo {
            file: file.into(),
            channels: data.channels.clone(),
            n_samples: data.len(),
            load_report,
        },
        model: ModelInfo {
            mode: config.mode,
            effects: config.effects,
        },
        options,
        params: ParamFile::from_params(&params),
        parameters,
        scale: scale_entries,
        correlation,
        warnings,
        residuals,
        trace,
        wall_time_s: started.elapsed().as_secs_f64(),
    };
    Ok(FitOutcome {
        json,
        params,
        curves,
    })
}

fn json_err(path: &Path, e: serde_json::Error) -> Error {
    Error::Other(format!("{}: cannot serialise: {e}", path.display()))
}

/// A CSV cell: empty for non-finite values.
fn cell(x: f64) -> String {
    if x.is_finite() {
        format!("{x:e}")
    } else {
        String::new()
    }
}

/// Write `fit.json`, `params.json` and `curves.csv` into `dir` (each atomically).
/// Draw the plotted report of the fit just written to `dir`; the fit's files stand whatever
/// happens here, so a drawing failure is a line in the summary, not an error.
pub fn write_report_line(dir: &Path) -> String {
    match crate::report::write_report(dir) {
        Ok(_) => format!("report: {}\n", dir.join("index.html").display()),
        Err(e) => format!("warning: the plotted report could not be drawn: {e}\n"),
    }
}

pub fn write_outputs(dir: &Path, out: &FitOutcome) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let fit_path = dir.join("fit.json");
    // Serialised straight from the struct to keep contracts.md's field order; serde_json writes
    // any non-finite f64 as null, and the Option fields already carry null + warning.
    write_atomically(&fit_path, |w| {
        serde_json::to_writer_pretty(&mut *w, &out.json).map_err(|e| json_err(&fit_path, e))?;
        w.write_all(b"\n").map_err(|e| Error::io(&fit_path, e))
    })?;
    let params_path = dir.join("params.json");
    write_atomically(&params_path, |w| {
        serde_json::to_writer_pretty(&mut *w, &out.json.params)
            .map_err(|e| json_err(&params_path, e))?;
        w.write_all(b"\n").map_err(|e| Error::io(&params_path, e))
    })?;
    let curves_path = dir.join("curves.csv");
    write_atomically(&curves_path, |w| {
        let io = |e| Error::io(&curves_path, e);
        writeln!(
            w,
            "sample,line,channel,theta_i,phi_i,theta_r,phi_r,data,sigma,fit,fit_r,fit_tt,fit_trt,residual,weight"
        )
        .map_err(io)?;
        for r in &out.curves {
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                r.sample,
                r.line,
                r.channel,
                r.theta_i,
                r.phi_i,
                r.theta_r,
                r.phi_r,
                cell(r.data),
                r.sigma.map(cell).unwrap_or_default(),
                cell(r.fit),
                cell(r.fit_r),
                cell(r.fit_tt),
                cell(r.fit_trt),
                cell(r.residual),
                cell(r.weight)
            )
            .map_err(io)?;
        }
        Ok(())
    })?;
    Ok(())
}

/// `v ± e` with a sensible number of digits.
fn pm(v: Option<f64>, e: Option<f64>) -> String {
    match (v, e) {
        (Some(v), Some(e)) => format!("{v:>12.6} ± {e:.2e}"),
        (Some(v), None) => format!("{v:>12.6}"),
        _ => "        null".into(),
    }
}

/// The one-screen summary printed by `hairfit fit` / `hairfit demo`.
pub fn summary(out: &FitOutcome, dir: Option<&Path>) -> String {
    let j = &out.json;
    let mut s = String::new();
    let l = j.model.effects.lobes;
    let lobes: Vec<&str> = [(l.r, "R"), (l.tt, "TT"), (l.trt, "TRT")]
        .iter()
        .filter(|(on, _)| *on)
        .map(|(_, n)| *n)
        .collect();
    s += &format!(
        "hairfit fit: {} — {} samples × {} channel(s) from {}\n",
        j.status,
        j.data.n_samples,
        j.data.channels.len(),
        j.data.file
    );
    s += &format!(
        "model: {} mode, lobes {}, glints {}, eccentricity {} ({})\n",
        j.model.mode,
        lobes.join("+"),
        if j.model.effects.glints { "on" } else { "off" },
        if j.model.effects.eccentricity {
            "on"
        } else {
            "off"
        },
        j.options["effects_choice"].as_str().unwrap_or("?")
    );
    if let Some(reasons) = j.options["effects_reasons"].as_array() {
        for r in reasons {
            s += &format!("  {}\n", r.as_str().unwrap_or(""));
        }
    }
    s += "parameters:\n";
    for p in &j.parameters {
        s += &format!(
            "  {:<16} {}  {}\n",
            p.name,
            pm(p.value, p.std_error),
            p.status
        );
    }
    for c in &j.scale {
        s += &format!(
            "  scale[{}]{:<8} {}\n",
            c.channel,
            "",
            pm(c.value, c.std_error)
        );
    }
    let r = &j.residuals;
    s += &format!(
        "residuals ({} space, {} loss): rms {} reduced chi2 {} dof {}\n",
        r.space,
        r.loss,
        r.rms.map_or("null".into(), |v| format!("{v:.4e}")),
        r.reduced_chi2.map_or("null".into(), |v| format!("{v:.4e}")),
        r.dof
    );
    for t in &j.trace {
        s += &format!(
            "  stage {:<18} iterations {:>5}  cost {:.6e}  {:.2} s\n",
            t.stage, t.iterations, t.cost, t.wall_s
        );
    }
    for w in &j.warnings {
        s += &format!("warning: {w}\n");
    }
    s += &format!("wall time {:.2} s", j.wall_time_s);
    if let Some(d) = dir {
        s += &format!(
            "; wrote {}/{{fit.json,params.json,curves.csv}}",
            d.display()
        );
    }
    s.push('\n');
    s
}
