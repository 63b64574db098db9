//! `hairfit compare DATA --models A,B,… --out DIR`: any list of model families fitted to the
//! same data with the same load and fit options, written as normal fit directories
//! (DIR/<family>), and ranked in one report ([`Comparison`], DIR/compare.json): χ², AIC/BIC,
//! the ranking by AIC with ΔAIC and ΔBIC against the best (ties within [`AIC_TIE`]), the
//! verdicts when the fits carry one, the parameters, every family's RMS residual per region
//! (the lobe regions R, TT, TRT and bins of |φ| and θh: [`regions`]) and the findings in words
//! (what each family loses against the best, and where), with every family's residuals
//! overlaid per slice (DIR/compare.svg/png, DIR/index.html). Nothing here names a family.
//!
//! Scales are not comparable across models (the normalisations of S differ), so only residuals
//! and information criteria are compared, never the fitted scales.

mod comparison;
mod figure;
mod findings;
mod fixes;
mod html;
pub mod regions;

use std::path::Path;
use std::sync::atomic::Ordering;

pub use comparison::{
    Comparison, ModelSummary, PerFamily, Ranked, Region, AIC_TIE, BIN_RATIO, MIN_RMS_GAP,
    SCALE_NOTE,
};
pub use fixes::check_fixes;

use crate::error::{Error, Result};
use crate::families::{FamilyParams, ModelFamily};
use crate::files::{CurveRow, FitJson, Verdict};
use crate::fit::{FitData, FitOptions, FitOutcome};

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

/// The summary of one fit.
fn summarise(
    family: ModelFamily,
    outcome: &FitOutcome<FamilyParams>,
    sigma_known: bool,
) -> ModelSummary {
    let j = &outcome.json;
    let k = j.options.free_parameters.len() + j.data.channels.len();
    let (chi2, aic, bic) = criteria(&outcome.curves.to_rows(), k, sigma_known);
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
        verdict: Some(j.verdict),
        params: j.params.clone(),
        parameters: j.parameters.clone(),
        scale: j.scale.clone(),
    }
}

/// One written fit of a comparison: its family and outcome.
pub struct WrittenFit<'a> {
    pub family: ModelFamily,
    pub outcome: &'a FitOutcome<FamilyParams>,
}

/// Compare written fits of the same data (curves of the same samples in the same order), in
/// the order given (compare.json's `models`).
pub fn compare(data_file: &str, data: &FitData, fits: &[WrittenFit<'_>]) -> Result<Comparison> {
    if fits.is_empty() {
        return Err(Error::Other("compare: no fits to compare".into()));
    }
    let sigma_known = data.sigma.is_some();
    let curves: Vec<Vec<CurveRow>> = fits.iter().map(|f| f.outcome.curves.to_rows()).collect();
    let first = &curves[0];
    for (fit, c) in fits.iter().zip(&curves).skip(1) {
        if c.len() != first.len()
            || c.iter()
                .zip(first)
                .any(|(a, b)| a.sample != b.sample || a.channel != b.channel)
        {
            return Err(Error::Other(format!(
                "compare: the {} and {} fits' curves do not cover the same samples in the same order",
                fits[0].family, fit.family
            )));
        }
    }
    let models: Vec<ModelSummary> = fits
        .iter()
        .map(|f| summarise(f.family, f.outcome, sigma_known))
        .collect();
    let families: Vec<ModelFamily> = fits.iter().map(|f| f.family).collect();
    let regions = regions::regions(&families, &curves);
    let ranking = findings::rank(&models);
    let findings = findings::findings(&models, &ranking, &regions);
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
        ranking,
        regions,
        findings,
        scale_note: SCALE_NOTE.into(),
    })
}

/// What `hairfit compare` wrote.
pub struct CompareOutcome {
    pub comparison: Comparison,
    /// The report line of each fit (its index.html, or why it could not be drawn).
    pub report_lines: Vec<String>,
}

impl CompareOutcome {
    /// The error of a comparison in which no fit succeeded (every one `failed`): published
    /// for inspection, but not a result.
    pub fn no_fit_succeeded(&self, out: &Path) -> Option<Error> {
        if !self.comparison.ranking.is_empty() {
            return None;
        }
        let each: Vec<String> = self
            .comparison
            .models
            .iter()
            .map(|m| format!("{} {}", m.family, m.verdict_str()))
            .collect();
        Some(Error::Other(format!(
            "no fit succeeded ({}), so nothing is ranked: each fit's reasons are in {}/<family>/fit.json",
            each.join(", "),
            out.display()
        )))
    }

    /// Under `--strict`, why the comparison is not a usable answer: the best-ranked fit is not
    /// `good`, or a listed fit failed.
    pub fn strict_refusal(&self) -> Option<String> {
        let c = &self.comparison;
        let failed: Vec<&str> = c
            .models
            .iter()
            .filter(|m| c.rank_of(m.family).is_none())
            .map(|m| m.family.as_str())
            .collect();
        let best = c.best().and_then(|b| c.model(b))?;
        if best.verdict != Some(Verdict::Good) {
            return Some(format!(
                "--strict: the best-ranked fit, {}, is {}",
                best.family,
                best.verdict_str()
            ));
        }
        (!failed.is_empty()).then(|| {
            format!(
                "--strict: {} failed, so the comparison is incomplete",
                failed.join(", ")
            )
        })
    }
}

/// How `hairfit compare` ended.
pub enum CompareEnd {
    /// Every fit ran to its end and DIR is published.
    Published(Box<CompareOutcome>),
    /// A signal stopped it: nothing new is published (DIR is as it was).
    Interrupted(String),
}

/// `hairfit compare DATA --out DIR`: load once, fit each family with its options (`fits`:
/// one [`FitOptions`] per family, its `family` set, in the order compare.json lists them),
/// and publish DIR as one output set (see [`crate::outdir`]): DIR/<family> (each a normal fit
/// directory with its report), compare.json, compare.svg/png and index.html. DIR is locked and
/// staged as `hairfit fit` does its --out (the lock file sits beside DIR), so a finished run
/// leaves no lock or staging directory inside it; `force` replaces a directory that holds
/// files other than a hairfit result.
pub fn compare_command(
    data_path: &Path,
    load_options: &crate::data::LoadOptions,
    fits: &[FitOptions],
    out: &Path,
    force: bool,
) -> Result<CompareEnd> {
    let families: Vec<ModelFamily> = fits.iter().map(|o| o.family).collect();
    let set = crate::outdir::OutputSet::begin(out, "hairfit compare", force, &[data_path])?;
    let (ds, report) = crate::data::load(data_path, load_options)?;
    // Every --fix against the data's channels, for every family, before any fit runs.
    // (Every family's options carry the same --fix.)
    if let Some(first) = fits.first() {
        check_fixes(&families, &first.fix, Some(ds.n_channels()))?;
    }
    let data = crate::fit::fit_data(&ds);
    let file = data_path.display().to_string();
    let mut outcomes = Vec::new();
    let mut report_lines = Vec::new();
    let stopped = || {
        fits.iter()
            .any(|o| o.cancel.as_ref().is_some_and(|c| c.load(Ordering::SeqCst)))
    };
    let interrupted = |what: String| {
        Ok(CompareEnd::Interrupted(format!(
            "compare was interrupted {what}: nothing is published, {} is as it was",
            out.display()
        )))
    };
    // Each fit's files and report are written on a thread of their own while the next family
    // fits, which can then use whatever core the writing leaves idle.
    let fitted = std::thread::scope(|scope| -> Result<Option<String>> {
        let mut writing = None;
        let mut collect = |writing: Option<(&str, Writing<'_, _>)>| {
            if let Some((name, pending)) = writing {
                let written: crate::report::publish::PublishedFit = match pending {
                    Writing::Thread(handle) => handle.join().map_err(|_| {
                        Error::Other(format!(
                            "writing {name}'s files and report failed (a panic)"
                        ))
                    })??,
                    Writing::Done(result) => result?,
                };
                report_lines.push(written.report_line(&out.join(name)));
                outcomes.push(written.outcome);
            }
            Ok::<_, Error>(())
        };
        // Every return joins the writer still running first: a thread left unjoined that
        // panicked would make the scope panic instead of returning an error.
        let run = (|| -> Result<Option<String>> {
            for opts in fits {
                let name = opts.family.as_str();
                let outcome = crate::fit::registry::fit_family(&data, &file, report.clone(), opts)?;
                // A ranking of interrupted fits would be a ranking of best-so-far points.
                if outcome.json.verdict == Verdict::Interrupted || stopped() {
                    return Ok(Some(name.to_string()));
                }
                let dir = set.sub_dir(name)?;
                collect(writing.take())?;
                let set = &set;
                // A thread that cannot start (a memory cap) is no error: this thread writes.
                let slot = std::sync::Arc::new(std::sync::Mutex::new(Some((dir, outcome))));
                let theirs = slot.clone();
                let write = move || {
                    let taken = theirs.lock().ok().and_then(|mut s| s.take());
                    let (dir, outcome) = taken.expect("the writer takes the outcome once");
                    crate::report::publish::write_fit(set, &dir, outcome)
                };
                let pending = match std::thread::Builder::new().spawn_scoped(scope, write) {
                    Ok(handle) => Writing::Thread(handle),
                    Err(_) => {
                        let taken = slot.lock().ok().and_then(|mut s| s.take());
                        let (dir, outcome) = taken.expect("no thread took the outcome");
                        Writing::Done(crate::report::publish::write_fit(set, &dir, outcome))
                    }
                };
                writing = Some((name, pending));
            }
            Ok(None)
        })();
        let last = collect(writing.take());
        let fitted = run?;
        last?;
        Ok(fitted)
    })?;
    if let Some(name) = fitted {
        return interrupted(format!("while fitting {name}"));
    }
    let written: Vec<WrittenFit<'_>> = families
        .iter()
        .zip(&outcomes)
        .map(|(&family, outcome)| WrittenFit { family, outcome })
        .collect();
    let comparison = compare(&file, &data, &written)?;
    let staging = set.staging();
    comparison
        .save(&staging.join("compare.json"))
        .map_err(|e| set.explain(e))?;
    let curves: Vec<(ModelFamily, Vec<CurveRow>)> = written
        .iter()
        .map(|w| (w.family, w.outcome.curves.to_rows()))
        .collect();
    let info =
        crate::plot::render(staging, &figure::overlay(&curves)).map_err(|e| set.explain(e))?;
    html::write_index(staging, &comparison, &info).map_err(|e| set.explain(e))?;
    // The last moment a signal can still keep the set from being published; one after this
    // changes nothing that is published (the command then exits as the comparison says).
    if stopped() {
        return interrupted("while its outputs were written".into());
    }
    set.publish()?;
    Ok(CompareEnd::Published(Box::new(CompareOutcome {
        comparison,
        report_lines,
    })))
}

/// The fit.json of a fit directory written by compare.
pub fn load_fit(dir: &Path) -> Result<FitJson> {
    FitJson::load(&dir.join("fit.json"))
}

/// The text `hairfit compare` prints: one line per family in rank order, then the findings.
pub fn summary_text(c: &Comparison, out: &Path) -> String {
    let mut s = format!(
        "hairfit compare: {} samples × {} channel(s) from {}; ranked by AIC\n",
        c.n_samples,
        c.channels.len(),
        c.data
    );
    let width = c
        .models
        .iter()
        .map(|m| m.family.as_str().len())
        .max()
        .unwrap_or(0);
    for r in &c.ranking {
        let Some(m) = c.model(r.family) else { continue };
        s += &format!(
            "  {:>2}{} {:<width$} verdict {:<12} status {:<14} chi2 {:>12.5e}  k {:>2}  AIC {:>12.2}  ΔAIC {:>10.2}  BIC {:>12.2}  ΔBIC {:>10.2}\n",
            r.rank,
            if r.tied_with_best && Some(r.family) != c.best() { "=" } else { " " },
            m.family.as_str(),
            m.verdict_str(),
            m.status,
            m.chi2,
            m.n_params,
            r.aic,
            r.delta_aic,
            r.bic,
            r.delta_bic
        );
    }
    // The fits with no place in the ranking, with their verdicts and no numbers to compare.
    for m in c.models.iter().filter(|m| c.rank_of(m.family).is_none()) {
        s += &format!(
            "   - {:<width$} verdict {:<12} status {:<14} not ranked\n",
            m.family.as_str(),
            m.verdict_str(),
            m.status
        );
    }
    for f in &c.findings {
        s += &format!("{f}\n");
    }
    s += &format!("compare: {}\n", out.join("index.html").display());
    s
}

/// A fit's files and report being written: on a thread of their own, or already written here
/// (no thread could start, as under a memory cap).
enum Writing<'scope, T> {
    Thread(std::thread::ScopedJoinHandle<'scope, T>),
    Done(T),
}
