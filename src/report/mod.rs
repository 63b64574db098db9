//! `hairfit report`: plotted fit reports. Reads `fits/NAME/{fit.json,curves.csv}` and writes,
//! into the same directory, SVG and PNG figures (per-slice curves with the model re-evaluated
//! densely, data against fit, residuals, a polar view, the correlation heatmap, convergence) and
//! one offline `index.html` that shows them with the summary numbers and the parameter table.
//!
//! The fit's result arrives typed ([`FitJson`], [`Curves`] from [`crate::files`]): straight
//! from the fit ([`write_report_of`]) or read back from its files ([`write_report_with`]). The
//! model configuration, measurement, scale and weights are the fit's; none is re-derived here.
//! Without curves (`--curves none`) the report shows parameters and verdict only; with a
//! summary (`--curves summary`) it draws the rows the summary kept ([`summary_rows`]).

pub mod figures;
mod html;
mod panels;
pub mod publish;

use std::path::Path;

use plotters::prelude::*;

use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::families::{FamilyModel, ModelFamily};
use crate::files::{CurveRow, Curves, CurvesMode, FitJson, ProfileMethod};
use crate::geometry::Angles;

use crate::plot::{render, YScale};
use crate::slices::decimate::stride_indices;
pub use crate::slices::summary::{summary_rows, summary_samples, SUMMARY_SAMPLES};
use crate::slices::{find_slices, samples_of, FoundSlices, Slice, SliceKind};
pub use crate::slices::{MAX_PANELS, MAX_SLICE_POINTS};
use figures::{
    channel_color, ConvergenceFigure, CorrelationFigure, CurvesFigure, PolarFigure, ProfileFigure,
    ProfilePanel, SlicePanel,
};
use panels::Ctx;

/// Points of the dense model curve per slice (the curve is never decimated).
pub const DENSE_POINTS: usize = 721;
/// Most points drawn in a scatter figure (data against fit, each residual panel).
pub const MAX_SCATTER_POINTS: usize = 6000;

/// Options of `hairfit report`.
#[derive(Debug, Clone, Copy, Default)]
pub struct ReportOptions {
    /// Linear instead of logarithmic value axes.
    pub linear: bool,
}

/// The model as the report evaluates it: `out[c] = [R, TT, TRT]` at `angles` (radians).
pub type LobeModel<'a> = dyn Fn(&Angles, &mut [[f64; 3]]) + Sync + 'a;

pub use crate::plot::FigureInfo;

/// What a report wrote and how much it drew.
#[derive(Debug, Clone, Default)]
pub struct ReportSummary {
    /// File names written into the fit directory (figures, then index.html).
    pub files: Vec<String>,
    pub figures: Vec<FigureInfo>,
    /// Slices found / drawn as panels.
    pub slices: usize,
    pub panels: usize,
    /// Measured points drawn over all figures (after decimation).
    pub drawn_points: usize,
    /// Slice series (one channel of one slice) whose points were decimated for drawing.
    pub decimated_series: usize,
    /// Things the reader should know (decimation, points not drawable on log axes, ...).
    pub notes: Vec<String>,
}

/// Refuse what is not a fit directory before touching it, saying what `report` takes (the
/// output set's own checks would name `--out` and `--force`, which `report` does not have).
fn check_fit_dir(dir: &Path, is_dir: bool) -> Result<()> {
    let shown = dir.display();
    if !is_dir {
        return Err(Error::Other(format!(
            "{shown}: is a file; hairfit report takes a fit's directory (the --out of hairfit fit, \
             holding fit.json), e.g. hairfit report fits/demo"
        )));
    }
    if dir.join("fit.json").is_file() {
        return Ok(());
    }
    let families: Vec<&str> = (ModelFamily::ALL.into_iter())
        .map(ModelFamily::as_str)
        .filter(|f| dir.join(f).join("fit.json").is_file())
        .collect();
    Err(Error::Other(if families.is_empty() {
        format!(
            "{shown}: holds no fit.json, so it is not a fit's directory; hairfit report takes \
             the --out of hairfit fit, e.g. hairfit report fits/demo"
        )
    } else {
        format!(
            "{shown}: is a hairfit compare directory; report one of its fits, e.g. hairfit \
             report {}",
            dir.join(families[0]).display()
        )
    }))
}

/// The label of fit.json's `residuals.reduced_chi2`: the fit's own cost (the loss applied to
/// the normalised residuals) over the degrees of freedom, the factor that scales the standard
/// errors. Under a robust loss it differs from the verdict's χ² test, which sums plain squared
/// normalised residuals and leaves out those beyond 5 σ; under l2 the two agree.
pub fn cost_chi2_label(loss: &str) -> String {
    if loss == "l2" {
        "reduced chi2 (l2 cost / dof)".into()
    } else {
        format!("reduced chi2 of the {loss} cost (cost / dof, not the verdict's chi2)")
    }
}

/// Write the report of the fit in `dir` with default options (reads its files).
pub fn write_report(dir: &Path) -> Result<ReportSummary> {
    write_report_with(dir, &ReportOptions::default())
}

/// `hairfit report DIR`: read the fit's fit.json and curves.csv from `dir` and report them.
/// The directory is republished as one set: its other files carried over, the figures redrawn.
pub fn write_report_with(dir: &Path, options: &ReportOptions) -> Result<ReportSummary> {
    // A missing directory is reported as such before any lock is taken beside it.
    let meta = std::fs::metadata(dir).map_err(|e| crate::Error::io(dir, e))?;
    check_fit_dir(dir, meta.is_dir())?;
    // Read first: a malformed fit.json is reported as such, before any lock is taken.
    let fit = FitJson::load(&dir.join("fit.json"))?;
    let set = crate::outdir::OutputSet::begin(dir, "hairfit report", false, &[])?;
    let curves_path = dir.join("curves.csv");
    let curves = match std::fs::metadata(&curves_path) {
        Ok(_) => Some(Curves::read_csv(&curves_path)?),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
        Err(e) => return Err(Error::io(&curves_path, e)),
    };
    set.keep_all_but(publish::is_report_file)?;
    let summary = write_report_of(set.staging(), &fit, curves.as_ref(), None, options)
        .map_err(|e| set.explain(e))?;
    set.publish()?;
    Ok(summary)
}

/// Report the fit `fit` with its `curves` (`None`: no curves.csv) into `dir`: the dense curves
/// evaluate the fit's model family, configuration and measurement with its fitted parameters.
pub fn write_report_of(
    dir: &Path,
    fit: &FitJson,
    curves: Option<&Curves>,
    slices: Option<&FoundSlices>,
    options: &ReportOptions,
) -> Result<ReportSummary> {
    let family_model = FamilyModel::new(&fit.params, &fit.setup()?);
    let measurement = fit.options.measurement;
    let model = move |a: &Angles, out: &mut [[f64; 3]]| {
        family_model.by_lobe(a, out);
        let f = measurement.factor(a);
        out.iter_mut().flatten().for_each(|v| *v *= f);
    };
    let mut pre_notes = Vec::new();
    let usable = match fit.params.validate() {
        Ok(()) => true,
        Err(e) => {
            pre_notes.push(format!(
                "fitted parameters are outside the model's domain ({e}); curves show the fit column at the samples only"
            ));
            false
        }
    };
    let n_model = fit.params.n_channels();
    let model_ref: Option<&LobeModel> = if usable { Some(&model) } else { None };
    let mut summary = render_curves_report(dir, fit, curves, slices, model_ref, n_model, options)?;
    summary.notes.splice(0..0, pre_notes);
    Ok(summary)
}

/// [`render_curves_report`] of curves given as rows.
pub fn render_report(
    dir: &Path,
    fit: &FitJson,
    rows: &[CurveRow],
    model: Option<&LobeModel>,
    n_model: usize,
    options: &ReportOptions,
) -> Result<ReportSummary> {
    let curves = Curves::from_rows(rows);
    render_curves_report(dir, fit, Some(&curves), None, model, n_model, options)
}

/// Render the report of `fit` and its `curves` into `dir`, evaluating `model` (with `n_model`
/// channels) for the dense curves; `None` draws the fit column at the samples instead.
/// Without curves only the parameter figures and the page are written. `slices`: the curves'
/// scan slices when the caller has them (found here otherwise).
pub fn render_curves_report(
    dir: &Path,
    fit: &FitJson,
    curves: Option<&Curves>,
    slices: Option<&FoundSlices>,
    model: Option<&LobeModel>,
    n_model: usize,
    options: &ReportOptions,
) -> Result<ReportSummary> {
    let mut summary = ReportSummary::default();
    // The figures of fit.json alone are drawn while the data's are (neither reads the other's).
    let mut parameters = ReportSummary::default();
    let (data, params) = rayon::join(
        || {
            let curves = curves.map(|c| (c, slices));
            data_part(dir, fit, curves, model, n_model, options, &mut summary)
        },
        || parameter_figures(dir, fit, &mut parameters),
    );
    data?;
    params?;
    summary.figures.append(&mut parameters.figures);
    for f in &summary.figures {
        summary.files.push(format!("{}.svg", f.stem));
        summary.files.push(format!("{}.png", f.stem));
    }
    let page = html::index_html(fit, &summary, options);
    let path = dir.join("index.html");
    write_atomically(&path, |w| {
        w.write_all(page.as_bytes())
            .map_err(|e| Error::io(&path, e))
    })?;
    summary.files.push("index.html".into());
    Ok(summary)
}

/// The report's part from curves.csv: its figures of the data, or the note saying why there
/// are none.
fn data_part(
    dir: &Path,
    fit: &FitJson,
    curves: Option<(&Curves, Option<&FoundSlices>)>,
    model: Option<&LobeModel>,
    n_model: usize,
    options: &ReportOptions,
    summary: &mut ReportSummary,
) -> Result<()> {
    match curves {
        Some((curves, slices)) => {
            if fit.options.curves == CurvesMode::Summary {
                let why = if fit.options.curves_reason.is_empty() {
                    "`--curves summary`".to_string()
                } else {
                    let why = &fit.options.curves_reason;
                    format!("`--curves auto` chose it: {}", why.trim_start_matches("auto: "))
                };
                summary.notes.push(format!(
                    "curves.csv is a summary ({why}): {} rows of {} samples, the slices drawn, an even spread and every down-weighted sample; figures of the data show those rows only",
                    curves.len(),
                    curves.n_samples()
                ));
            }
            data_figures(dir, fit, (curves, slices), model, n_model, options, summary)?;
        }
        None => summary.notes.push(match fit.options.curves {
            CurvesMode::None => "no curves.csv: the fit ran with `--curves none`, so only the parameters and the verdict are shown (rerun with `--curves summary` or `full` for figures of the data)".to_string(),
            _ => "no curves.csv in the fit's directory (removed?): only the parameters and the verdict are shown; rerun the fit for figures of the data".to_string(),
        }),
    }
    Ok(())
}

/// The figures of the data: slice curves, the polar view, data against fit, residuals.
fn data_figures(
    dir: &Path,
    fit: &FitJson,
    (curves, found): (&Curves, Option<&FoundSlices>),
    model: Option<&LobeModel>,
    n_model: usize,
    options: &ReportOptions,
    summary: &mut ReportSummary,
) -> Result<()> {
    let scale = if options.linear {
        YScale::Linear
    } else {
        YScale::Log
    };
    let channels = channel_list(fit, curves);
    // The report's channel index of each of the table's channels.
    let channel_of: Vec<usize> = curves
        .channels
        .iter()
        .map(|name| channels.iter().position(|c| c == name).unwrap_or(0))
        .collect();
    let colours: Vec<(String, RGBColor)> = channels
        .iter()
        .enumerate()
        .map(|(i, c)| (c.clone(), channel_color(c, i)))
        .collect();
    let samples = samples_of(curves);
    let searched;
    let (slices, scattered) = match found {
        Some((slices, scattered)) => (slices, scattered),
        None => {
            searched = find_slices(&samples);
            (&searched.0, &searched.1)
        }
    };
    summary.slices = slices.len();
    if scale == YScale::Log {
        let hidden = curves
            .values
            .iter()
            .filter(|r| YScale::Log.map(r.data).is_none())
            .count();
        if hidden > 0 {
            summary.notes.push(format!(
                "{hidden} measured values ≤ 0 (or not finite) cannot be drawn on log axes; use --linear to see them"
            ));
        }
    }
    let ctx = Ctx {
        fit,
        curves,
        samples: &samples,
        channel_of: &channel_of,
        colours: &colours,
        model,
        n_model: n_model.max(1),
    };

    // Curves per slice.
    if !slices.is_empty() {
        let shown = stride_indices(slices.len(), MAX_PANELS);
        let panels: Vec<SlicePanel> = shown
            .iter()
            .map(|&i| ctx.slice_panel(&slices[i], summary))
            .collect();
        summary.panels = panels.len();
        summary.drawn_points += panels.iter().map(panel_points).sum::<usize>();
        let subtitle = format!(
            "{} of {} slices ({} azimuthal, {} longitudinal); lines: model re-evaluated densely with the fitted parameters and scale{}",
            panels.len(),
            slices.len(),
            slices.iter().filter(|s| matches!(s.kind, SliceKind::Azimuthal { .. })).count(),
            slices.iter().filter(|s| matches!(s.kind, SliceKind::Longitudinal { .. })).count(),
            if scale == YScale::Log {
                figures::LOG_FLOOR_NOTE
            } else {
                ""
            },
        );
        let fig = CurvesFigure {
            panels,
            channels: colours.clone(),
            scale,
            subtitle,
        };
        summary.figures.push(render(dir, &fig)?);
        // Polar view of the best-sampled azimuthal slice, the one nearest normal incidence
        // and specular geometry among equals (the classic view of the lobes).
        if let Some(best) = slices
            .iter()
            .filter(|s| matches!(s.kind, SliceKind::Azimuthal { .. }))
            .min_by(|a, b| {
                let key = |s: &Slice| {
                    let tr = match s.kind {
                        SliceKind::Azimuthal { theta_r } => theta_r,
                        SliceKind::Longitudinal { .. } => 0.0,
                    };
                    (
                        std::cmp::Reverse(s.samples.len()),
                        s.theta_i.abs() + (s.theta_i + tr).abs(),
                    )
                };
                let (ka, kb) = (key(a), key(b));
                ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
            })
        {
            let panel = ctx.slice_panel(best, summary);
            summary.drawn_points += panel_points(&panel);
            let subtitle = match scale {
                YScale::Log => "radius: value on a log scale (rings labelled), angle: φ = φr − φi",
                YScale::Linear => "radius: value (rings labelled), angle: φ = φr − φi",
            };
            let fig = PolarFigure {
                panel,
                scale,
                subtitle: subtitle.into(),
            };
            summary.figures.push(render(dir, &fig)?);
        }
    }

    if summary.decimated_series > 0 {
        summary.notes.push(format!(
            "{} slice series had more than {MAX_SLICE_POINTS} points per channel and were decimated evenly for drawing (the curves are not)",
            summary.decimated_series
        ));
    }

    // Data against fit: every sample, the only view of scattered data.
    let versus = ctx.data_vs_fit(scale, slices.is_empty(), scattered.len());
    summary.drawn_points += versus.points.len();
    let residuals = ctx.residuals(summary);
    summary.drawn_points += residuals.points.len();
    // The two largest figures (every sample, or up to the scatter cap), drawn side by side.
    let (versus, residuals) = rayon::join(|| render(dir, &versus), || render(dir, &residuals));
    summary.figures.push(versus?);
    summary.figures.push(residuals?);

    Ok(())
}

/// The figures of fit.json alone: correlations, profiles, convergence.
fn parameter_figures(dir: &Path, fit: &FitJson, summary: &mut ReportSummary) -> Result<()> {
    if !fit.correlation.names.is_empty() {
        let fig = CorrelationFigure {
            names: fit.correlation.names.clone(),
            matrix: fit.correlation.matrix.clone(),
        };
        summary.figures.push(render(dir, &fig)?);
    }
    let profiles = profile_panels(fit);
    if !profiles.is_empty() {
        summary
            .figures
            .push(render(dir, &ProfileFigure { panels: profiles })?);
    }
    let stages: Vec<(String, u64, Vec<f64>)> = fit
        .trace
        .iter()
        .map(|t| {
            let h = if t.history.is_empty() {
                t.cost.into_iter().collect()
            } else {
                t.history.clone()
            };
            (t.stage.clone(), t.iterations, h)
        })
        .filter(|(_, _, h)| !h.is_empty())
        .collect();
    if !stages.is_empty() {
        summary
            .figures
            .push(render(dir, &ConvergenceFigure { stages })?);
    }
    Ok(())
}

/// The profiled parameters' panels (fit.json stores the points, so nothing is refitted).
fn profile_panels(fit: &FitJson) -> Vec<ProfilePanel> {
    fit.parameters
        .iter()
        .filter(|p| !p.profile.is_empty())
        .map(|p| {
            let unit = fit.family().unit_label(&p.name);
            ProfilePanel {
                title: if unit.is_empty() {
                    p.name.clone()
                } else {
                    format!("{} ({unit})", p.name)
                },
                value: p.value.unwrap_or(f64::NAN),
                std_error: p.std_error,
                points: p.profile.iter().map(|q| (q[0], q[1])).collect(),
                quadratic_ends: quadratic_ends(p),
            }
        })
        .filter(|p| p.value.is_finite())
        .collect()
}

/// The 95% ends a profile took from the local quadratic (`profile_method` `extrapolated`),
/// `[below, above]`.
fn quadratic_ends(p: &crate::files::fit_json::ParameterEntry) -> [Option<f64>; 2] {
    let methods = p.profile_method.unwrap_or([ProfileMethod::Refits; 2]);
    let ends = p
        .interval_95
        .map(|i| [i.lower, i.upper])
        .unwrap_or([None; 2]);
    std::array::from_fn(|side| {
        (methods[side] == ProfileMethod::Extrapolated)
            .then_some(ends[side])
            .flatten()
    })
}

/// Channels in fit.json's order, then any other channel named in curves.csv.
fn channel_list(fit: &FitJson, curves: &Curves) -> Vec<String> {
    let mut channels = fit.data.channels.clone();
    for c in &curves.channels {
        if !channels.contains(c) {
            channels.push(c.clone());
        }
    }
    if channels.is_empty() {
        channels.push("value".into());
    }
    channels
}

fn panel_points(p: &SlicePanel) -> usize {
    p.channels.iter().map(|c| c.points.len()).sum()
}
