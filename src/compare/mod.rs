//! `hairfit compare DATA --out DIR`: both model families fitted to the same data with the same
//! load and fit options, written as two normal fit directories (DIR/marschner, DIR/chiang), and
//! compared side by side ([`Comparison`], DIR/compare.json): χ², AIC/BIC, the verdicts when the
//! fits carry one, the parameters, and where each model's residuals are worse (bins of |φ| and
//! θ_h), with the residuals of both overlaid per slice (DIR/compare.svg/png, DIR/index.html).
//!
//! Scales are not comparable across models (the normalisations of S differ), so only residuals
//! and information criteria are compared, never the fitted scales.

mod figure;
mod html;

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::family::{FamilyParams, ModelFamily};
use crate::files::{CurveRow, FitJson, ParameterEntry, ScaleEntry};
use crate::fit::{FitData, FitOptions, FitOutcome};
use crate::model::angles::wrap_deg;

/// What compare.json says about scales.
pub const SCALE_NOTE: &str = "scales are not comparable across models: the two families \
normalise S differently, so each fit's per-channel scale absorbs a different factor; compare \
residuals, chi2 and AIC/BIC instead";

/// A difference in AIC below this is no preference (Burnham & Anderson: ΔAIC < 2 means
/// substantial support for both).
pub const AIC_TIE: f64 = 2.0;

/// A bin is called out when one model's RMS residual there is at least this many times the
/// other's (and the difference exceeds [`MIN_RMS_GAP`]).
pub const BIN_RATIO: f64 = 1.5;
/// Smallest RMS difference (normalised residual units) worth calling out.
pub const MIN_RMS_GAP: f64 = 0.05;

/// One family's fit as compare.json reports it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelSummary {
    pub family: ModelFamily,
    /// The fit directory, relative to compare.json.
    pub dir: String,
    pub status: String,
    /// Σ r² of the normalised residuals in the fit space.
    pub chi2: f64,
    pub n_residuals: usize,
    /// Free shape parameters plus one scale per channel.
    pub n_params: usize,
    pub aic: f64,
    pub bic: f64,
    pub reduced_chi2: Option<f64>,
    pub rms: Option<f64>,
    /// fit.json's `verdict`, when the fit wrote one.
    pub verdict: Option<serde_json::Value>,
    pub params: FamilyParams,
    pub parameters: Vec<ParameterEntry>,
    /// Not comparable across models (see `scale_note`).
    pub scale: Vec<ScaleEntry>,
}

/// One bin of the data (|φ| or θ_h) and each model's RMS normalised residual in it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Region {
    /// `abs_phi` or `theta_h`.
    pub axis: String,
    /// Bin centre and half-width, degrees.
    pub centre_deg: f64,
    pub half_width_deg: f64,
    /// Residuals (samples × channels) in the bin.
    pub n: usize,
    pub rms_marschner: f64,
    pub rms_chiang: f64,
}

impl Region {
    /// The family with the larger residual here, when the gap is worth calling out.
    pub fn worse(&self) -> Option<ModelFamily> {
        let (m, c) = (self.rms_marschner, self.rms_chiang);
        if (m - c).abs() < MIN_RMS_GAP {
            None
        } else if m > BIN_RATIO * c {
            Some(ModelFamily::Marschner)
        } else if c > BIN_RATIO * m {
            Some(ModelFamily::Chiang)
        } else {
            None
        }
    }

    fn place(&self) -> String {
        match self.axis.as_str() {
            "abs_phi" => format!("|φ| ≈ {:.0}°", self.centre_deg),
            _ => format!("θh ≈ {:.0}°", self.centre_deg),
        }
    }
}

/// The whole of compare.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    pub hairfit_version: String,
    pub data: String,
    pub n_samples: usize,
    pub channels: Vec<String>,
    /// `chi2 + 2k` (σ known: χ² is a log-likelihood) or `n ln(chi2/n) + 2k` (σ unknown).
    pub criterion: String,
    pub models: Vec<ModelSummary>,
    /// `marschner`, `chiang`, or `neither` (|ΔAIC| < 2).
    pub better: String,
    /// AIC(chiang) − AIC(marschner): positive means Marschner fits better.
    pub delta_aic: f64,
    pub delta_bic: f64,
    pub regions: Vec<Region>,
    /// Sentences: which fits better and where.
    pub findings: Vec<String>,
    pub scale_note: String,
}

impl Comparison {
    /// Write compare.json atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        crate::files::write_json(path, self)
    }

    /// Read compare.json.
    pub fn load(path: &Path) -> Result<Comparison> {
        crate::files::read_json(path, "compare.json is written by `hairfit compare`")
    }
}

/// χ², AIC and BIC of one fit from its curves (normalised residuals).
fn criteria(rows: &[CurveRow], k: usize, sigma_known: bool) -> (f64, f64, f64) {
    let chi2: f64 = rows
        .iter()
        .filter(|r| r.residual.is_finite())
        .map(|r| r.residual * r.residual)
        .sum();
    let n = rows.len().max(1) as f64;
    let k = k as f64;
    // Without σ the noise level is estimated too: the profile likelihood n ln(RSS/n).
    let fit_term = if sigma_known {
        chi2
    } else {
        n * (chi2.max(1e-300) / n).ln()
    };
    (chi2, fit_term + 2.0 * k, fit_term + k * n.ln())
}

/// The summary of one written fit (`dir` holds its fit.json, read back for a `verdict`).
fn summarise(
    family: ModelFamily,
    outcome: &FitOutcome<FamilyParams>,
    dir: &Path,
    sigma_known: bool,
) -> ModelSummary {
    let j = &outcome.json;
    let k = j.options.free_parameters.len() + j.data.channels.len();
    let (chi2, aic, bic) = criteria(&outcome.curves.to_rows(), k, sigma_known);
    let verdict = std::fs::read_to_string(dir.join("fit.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v.get("verdict").cloned());
    ModelSummary {
        family,
        dir: family.as_str().into(),
        status: j.status.to_string(),
        chi2,
        n_residuals: outcome.curves.len(),
        n_params: k,
        aic,
        bic,
        reduced_chi2: j.residuals.reduced_chi2,
        rms: j.residuals.rms,
        verdict,
        params: j.params.clone(),
        parameters: j.parameters.clone(),
        scale: j.scale.clone(),
    }
}

/// RMS residual per bin of `value(row)` (bins of `width` degrees from `lo`), both fits.
fn bins(
    axis: &str,
    m: &[CurveRow],
    c: &[CurveRow],
    value: impl Fn(&CurveRow) -> f64,
    (lo, hi, width): (f64, f64, f64),
) -> Vec<Region> {
    let nb = ((hi - lo) / width).ceil() as usize;
    let mut acc = vec![(0usize, 0.0f64, 0.0f64); nb];
    for (a, b) in m.iter().zip(c) {
        let x = value(a);
        if !(a.residual.is_finite() && b.residual.is_finite() && x.is_finite()) {
            continue;
        }
        let k = (((x - lo) / width).floor().max(0.0) as usize).min(nb - 1);
        acc[k].0 += 1;
        acc[k].1 += a.residual * a.residual;
        acc[k].2 += b.residual * b.residual;
    }
    acc.iter()
        .enumerate()
        .filter(|(_, a)| a.0 >= 3)
        .map(|(k, a)| Region {
            axis: axis.into(),
            centre_deg: lo + (k as f64 + 0.5) * width,
            half_width_deg: 0.5 * width,
            n: a.0,
            rms_marschner: (a.1 / a.0 as f64).sqrt(),
            rms_chiang: (a.2 / a.0 as f64).sqrt(),
        })
        .collect()
}

fn name(f: ModelFamily) -> &'static str {
    f.title()
}

/// The two families compared.
const COMPARED: [ModelFamily; 2] = [ModelFamily::Marschner, ModelFamily::Chiang];

/// Which fits better overall (AIC) and where each is worse, in words.
fn findings(models: &[ModelSummary], regions: &[Region], delta_aic: f64) -> (String, Vec<String>) {
    let (m, c) = (&models[0], &models[1]);
    let mut out = Vec::new();
    let better = if delta_aic.abs() < AIC_TIE {
        out.push(format!(
            "Neither model fits better: AIC differs by {delta_aic:.2} (< {AIC_TIE}); chi2 {:.4e} (Marschner) vs {:.4e} (Chiang)",
            m.chi2, c.chi2
        ));
        "neither"
    } else {
        let (win, lose) = if delta_aic > 0.0 { (m, c) } else { (c, m) };
        out.push(format!(
            "{} fits better: AIC {:.1} vs {:.1} (ΔAIC {:.1}), chi2 {:.4e} vs {:.4e} with {} vs {} parameters",
            name(win.family),
            win.aic,
            lose.aic,
            delta_aic.abs(),
            win.chi2,
            lose.chi2,
            win.n_params,
            lose.n_params
        ));
        win.family.as_str()
    };
    for family in COMPARED {
        let mut worst: Vec<&Region> = regions
            .iter()
            .filter(|r| r.worse() == Some(family))
            .collect();
        let gap = |r: &Region| (r.rms_marschner - r.rms_chiang).abs();
        worst.sort_by(|a, b| gap(b).total_cmp(&gap(a)));
        for r in worst.iter().take(3) {
            let (own, other) = match family {
                ModelFamily::Marschner => (r.rms_marschner, r.rms_chiang),
                _ => (r.rms_chiang, r.rms_marschner),
            };
            out.push(format!(
                "{} misses the data at {} (RMS normalised residual {:.3} vs {:.3}, {} residuals)",
                name(family),
                r.place(),
                own,
                other,
                r.n
            ));
        }
    }
    out.push(format!("Scales: {SCALE_NOTE}."));
    (better.into(), out)
}

/// Compare two written fits of the same data (curves in the same sample order).
pub fn compare(
    data_file: &str,
    data: &FitData,
    fits: [(&FitOutcome<FamilyParams>, &Path); 2],
) -> Result<Comparison> {
    let sigma_known = data.sigma.is_some();
    let [(m_out, m_dir), (c_out, c_dir)] = fits;
    let (m, c) = (&m_out.curves.to_rows(), &c_out.curves.to_rows());
    if m.len() != c.len()
        || m.iter()
            .zip(c)
            .any(|(a, b)| a.sample != b.sample || a.channel != b.channel)
    {
        return Err(Error::Other(
            "compare: the two fits' curves do not cover the same samples in the same order".into(),
        ));
    }
    let models = vec![
        summarise(ModelFamily::Marschner, m_out, m_dir, sigma_known),
        summarise(ModelFamily::Chiang, c_out, c_dir, sigma_known),
    ];
    let delta_aic = models[1].aic - models[0].aic;
    let delta_bic = models[1].bic - models[0].bic;
    let mut regions = bins(
        "abs_phi",
        m,
        c,
        |r| wrap_deg(r.phi_r - r.phi_i).abs(),
        (0.0, 180.0, 10.0),
    );
    regions.extend(bins(
        "theta_h",
        m,
        c,
        |r| 0.5 * (r.theta_i + r.theta_r),
        (-90.0, 90.0, 10.0),
    ));
    let (better, findings) = findings(&models, &regions, delta_aic);
    Ok(Comparison {
        hairfit_version: env!("CARGO_PKG_VERSION").into(),
        data: data_file.into(),
        n_samples: data.len(),
        channels: data.channels.clone(),
        criterion: if sigma_known {
            "chi2 + 2k (AIC), chi2 + k ln n (BIC): the data give sigma".into()
        } else {
            "n ln(chi2/n) + 2k (AIC), n ln(chi2/n) + k ln n (BIC): sigma unknown, estimated".into()
        },
        models,
        better,
        delta_aic,
        delta_bic,
        regions,
        findings,
        scale_note: SCALE_NOTE.into(),
    })
}

/// Names of a family's parameters that act on every channel (not `sigma_a[c]`).
fn shared_names<P: crate::fit::problem::FitParam>(all: Vec<P>) -> Vec<String> {
    all.into_iter()
        .filter(|p| p.channel().is_none())
        .map(|p| p.json_name())
        .collect()
}

/// `--fix` of `hairfit compare`: both fits get the same options, so each name must be a
/// parameter of both families (η and σ_a: `sigma_a` or `sigma_a[c]`); one that only one family
/// has (`k_g`, `beta_m`, …) or neither is refused, naming which family lacks it, before
/// anything is fitted. The values are then checked as each family's fit would check them.
/// `nc`: the data's channel count, or `None` before the data are loaded (each `sigma_a[k]`
/// then names a channel; the data's count is checked once they are).
pub fn check_fixes(fix: &[String], nc: Option<usize>) -> Result<()> {
    use crate::fit::fixes::{channel_index, channels_named};
    let marschner = shared_names(crate::fit::all_parameters(1));
    let chiang = shared_names(crate::chiang::all_parameters(1));
    let both: Vec<&str> = marschner
        .iter()
        .filter(|n| chiang.contains(n))
        .map(String::as_str)
        .collect();
    let own = |names: &[String]| {
        names
            .iter()
            .filter(|n| !both.contains(&n.as_str()))
            .cloned()
            .collect::<Vec<_>>()
            .join(", ")
    };
    let fixable = format!(
        "sigma_a (every channel), sigma_a[c] (one channel), {}",
        both.join(", ")
    );
    for item in fix {
        let Some((name, _)) = item.split_once('=') else {
            continue; // the families' own parser says how to write it
        };
        let name = name.trim();
        let per_channel = name == "sigma_a" || channel_index(name).is_some();
        let has = |names: &[String]| per_channel || names.iter().any(|n| n == name);
        let lacking = match (has(&marschner), has(&chiang)) {
            (true, true) => continue,
            (true, false) => Some((ModelFamily::Marschner, ModelFamily::Chiang)),
            (false, true) => Some((ModelFamily::Chiang, ModelFamily::Marschner)),
            (false, false) => None,
        };
        return Err(Error::Other(match lacking {
            Some((owner, other)) => format!(
                "--fix `{item}`: compare fits both model families with the same options, but \
                 `{name}` is a {} parameter the {} model does not have; compare fixes only \
                 what both have: {fixable}. To fix {name}, fit the {} model alone: hairfit fit \
                 DATA --model {owner} --fix {item}",
                self::name(owner),
                self::name(other),
                self::name(owner),
            ),
            None => format!(
                "--fix `{item}`: neither model family has a parameter `{name}`; compare fixes \
                 only what both have: {fixable} (Marschner alone has {}; Chiang alone has {})",
                own(&marschner),
                own(&chiang)
            ),
        }));
    }
    let nc = match nc {
        Some(nc) => nc,
        None => channels_named(fix)?,
    };
    for family in COMPARED {
        crate::fit::family::family_fit(family).check_fixes(fix, nc)?;
    }
    Ok(())
}

/// What `hairfit compare` wrote.
pub struct CompareOutcome {
    pub comparison: Comparison,
    /// The report line of each fit (its index.html, or why it could not be drawn).
    pub report_lines: Vec<String>,
}

/// `hairfit compare DATA --out DIR`: load once, fit both families with `opts` (its `family`
/// is ignored), and publish DIR as one output set (see [`crate::outdir`]): DIR/marschner and
/// DIR/chiang (each a normal fit directory with its report), compare.json, compare.svg/png
/// and index.html. DIR is locked and staged as `hairfit fit` does its --out (the lock file
/// sits beside DIR), so a finished run leaves no lock or staging directory inside it; `force`
/// replaces a directory that holds files other than a hairfit result.
pub fn compare_command(
    data_path: &Path,
    load_options: &crate::data::LoadOptions,
    opts: &FitOptions,
    out: &Path,
    force: bool,
) -> Result<CompareOutcome> {
    let set = crate::outdir::OutputSet::begin(out, "hairfit compare", force, &[data_path])?;
    let (ds, report) = crate::data::load(data_path, load_options)?;
    // Every --fix against the data's channels, for both families, before either fit runs.
    check_fixes(&opts.fix, Some(ds.n_channels()))?;
    let data = crate::fit::fit_data(&ds);
    let file = data_path.display().to_string();
    let mut outcomes = Vec::new();
    let mut report_lines = Vec::new();
    let mut staged = Vec::new();
    for family in COMPARED {
        let opts = FitOptions {
            family,
            ..opts.clone()
        };
        let mut outcome = crate::fit::fit_family(&data, &file, report.clone(), &opts)?;
        outcome.json.options.load = Some(format!("{load_options:?}"));
        let dir = set.sub_dir(family.as_str())?;
        let written = crate::report::publish::write_fit(&set, &dir, outcome)?;
        report_lines.push(written.report_line(&out.join(family.as_str())));
        outcomes.push(written.outcome);
        staged.push(dir);
    }
    let staging = set.staging();
    let comparison = compare(
        &file,
        &data,
        [(&outcomes[0], &staged[0]), (&outcomes[1], &staged[1])],
    )?;
    comparison.save(&staging.join("compare.json"))?;
    let fig = figure::overlay(&outcomes[0].curves.to_rows(), &outcomes[1].curves.to_rows());
    let info = crate::plot::render(staging, &fig)?;
    html::write_index(
        staging,
        &comparison,
        &info,
        &outcomes[0].json,
        &outcomes[1].json,
    )?;
    set.publish()?;
    Ok(CompareOutcome {
        comparison,
        report_lines,
    })
}

/// The fit.json of a fit directory written by compare.
pub fn load_fit(dir: &Path) -> Result<FitJson> {
    FitJson::load(&dir.join("fit.json"))
}

/// The text `hairfit compare` prints.
pub fn summary_text(c: &Comparison, out: &Path) -> String {
    let mut s = format!(
        "hairfit compare: {} samples × {} channel(s) from {}\n",
        c.n_samples,
        c.channels.len(),
        c.data
    );
    for m in &c.models {
        s += &format!(
            "  {:<10} status {:<14} chi2 {:>12.5e}  k {:>2}  AIC {:>12.2}  BIC {:>12.2}\n",
            m.family.as_str(),
            m.status,
            m.chi2,
            m.n_params,
            m.aic,
            m.bic
        );
    }
    for f in &c.findings {
        s += &format!("{f}\n");
    }
    s += &format!("compare: {}\n", out.join("index.html").display());
    s
}
