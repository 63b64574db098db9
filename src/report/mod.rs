//! `hairfit report`: plotted fit reports. Reads `fits/NAME/{fit.json,curves.csv}` and writes,
//! into the same directory, SVG and PNG figures (per-slice curves with the model re-evaluated
//! densely, data against fit, residuals, a polar view, the correlation heatmap, convergence) and
//! one offline `index.html` that shows them with the summary numbers and the parameter table.
//!
//! Also owns the typed form of the fit's output files ([`FitResult`], [`CurveRow`]).

pub mod decimate;
pub mod figures;
pub mod fit_file;
mod html;
pub mod slices;

use std::path::Path;

use plotters::prelude::*;

use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::model::{scattering_by_lobe, Angles, Measurement, ModelConfig};

pub use fit_file::{
    read_curves_csv, read_fit_json, write_curves_csv, write_fit_json, ChannelResiduals,
    Correlation, CurveRow, DataInfo, FitResult, FitStatus, ParamStatus, ParameterEntry,
    ResidualSummary, ScaleEntry, TraceStage, CURVES_HEADER,
};

use crate::plot::{fmt_num, render, YScale};
use decimate::{envelope_indices, stride_indices};
use figures::{
    channel_color, ChannelSeries, ConvergenceFigure, CorrelationFigure, CurvesFigure,
    DataVsFitFigure, Point, PolarFigure, ResidualsFigure, SlicePanel,
};
use slices::{collect_samples, find_slices, theta_h_deg, wrap_deg, Sample, Slice, SliceKind};

/// Points of the dense model curve per slice (the curve is never decimated).
pub const DENSE_POINTS: usize = 721;
/// Most slice panels drawn; more slices are sampled evenly.
pub const MAX_PANELS: usize = 12;
/// Most measured points drawn per channel in one slice panel.
pub const MAX_SLICE_POINTS: usize = 600;
/// Most points drawn in a scatter figure (data against fit, each residual panel).
pub const MAX_SCATTER_POINTS: usize = 6000;
/// Samples per slice used to calibrate the dense curve against the fit column.
const CALIBRATION_SAMPLES: usize = 64;
/// Relative disagreement between the dense curve and the fit column that gets reported: the
/// two come from the same model and parameters, so anything beyond rounding means a mismatch.
const CALIBRATION_TOLERANCE: f64 = 1e-6;

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

/// Write the report of the fit in `dir` with default options (called at the end of a fit).
pub fn write_report(dir: &Path) -> Result<ReportSummary> {
    write_report_with(dir, &ReportOptions::default())
}

/// Write the report of the fit in `dir`: reads fit.json and curves.csv, evaluates the model with
/// the fitted parameters for the dense curves, as the data measure it (`options.measurement`).
pub fn write_report_with(dir: &Path, options: &ReportOptions) -> Result<ReportSummary> {
    let fit = read_fit_json(&dir.join("fit.json"))?;
    let rows = read_curves_csv(&dir.join("curves.csv"))?;
    let params = fit.params.to_params();
    let config: ModelConfig = fit.model;
    let mut pre_notes = Vec::new();
    let measurement = measurement_of(&fit, &mut pre_notes);
    let model = move |a: &Angles, out: &mut [[f64; 3]]| {
        scattering_by_lobe(&params, &config, a, out);
        let f = measurement.factor(a);
        out.iter_mut().flatten().for_each(|v| *v *= f);
    };
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
    let mut summary = render_report(dir, &fit, &rows, model_ref, n_model, options)?;
    summary.notes.splice(0..0, pre_notes);
    Ok(summary)
}

/// What the fit's values were (fit.json `options.measurement`); fits written before the option
/// existed fitted S itself.
fn measurement_of(fit: &FitResult, notes: &mut Vec<String>) -> Measurement {
    match fit.options.get("measurement") {
        None => Measurement::S,
        Some(v) => serde_json::from_value(v.clone()).unwrap_or_else(|_| {
            notes.push(format!(
                "fit.json options.measurement is {v}, not \"s\" or \"radiance\"; curves assume s"
            ));
            Measurement::S
        }),
    }
}

/// Render the report of `fit` and its `rows` into `dir`, evaluating `model` (with `n_model`
/// channels) for the dense curves; `None` draws the fit column at the samples instead.
pub fn render_report(
    dir: &Path,
    fit: &FitResult,
    rows: &[CurveRow],
    model: Option<&LobeModel>,
    n_model: usize,
    options: &ReportOptions,
) -> Result<ReportSummary> {
    let scale = if options.linear {
        YScale::Linear
    } else {
        YScale::Log
    };
    let mut summary = ReportSummary::default();
    let channels = channel_list(fit, rows);
    let channel_of_row: Vec<usize> = rows
        .iter()
        .map(|r| channels.iter().position(|c| *c == r.channel).unwrap_or(0))
        .collect();
    let colours: Vec<(String, RGBColor)> = channels
        .iter()
        .enumerate()
        .map(|(i, c)| (c.clone(), channel_color(c, i)))
        .collect();
    let samples = collect_samples(rows);
    let (slices, scattered) = find_slices(&samples);
    summary.slices = slices.len();
    if scale == YScale::Log {
        let hidden = rows
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
        rows,
        samples: &samples,
        channel_of_row: &channel_of_row,
        colours: &colours,
        model,
        n_model: n_model.max(1),
    };

    // Curves per slice.
    if !slices.is_empty() {
        let shown = stride_indices(slices.len(), MAX_PANELS);
        let panels: Vec<SlicePanel> = shown
            .iter()
            .map(|&i| ctx.slice_panel(&slices[i], &mut summary))
            .collect();
        summary.panels = panels.len();
        summary.drawn_points += panels.iter().map(panel_points).sum::<usize>();
        let subtitle = format!(
            "{} of {} slices ({} azimuthal, {} longitudinal); lines: model re-evaluated densely with the fitted parameters and scale",
            panels.len(),
            slices.len(),
            slices.iter().filter(|s| matches!(s.kind, SliceKind::Azimuthal { .. })).count(),
            slices.iter().filter(|s| matches!(s.kind, SliceKind::Longitudinal { .. })).count(),
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
            let panel = ctx.slice_panel(best, &mut summary);
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
    let fig = ctx.data_vs_fit(scale, slices.is_empty(), scattered.len());
    summary.drawn_points += fig.points.len();
    summary.figures.push(render(dir, &fig)?);

    let fig = ctx.residuals(&mut summary);
    summary.drawn_points += fig.points.len();
    summary.figures.push(render(dir, &fig)?);

    if !fit.correlation.names.is_empty() {
        let fig = CorrelationFigure {
            names: fit.correlation.names.clone(),
            matrix: fit.correlation.matrix.clone(),
        };
        summary.figures.push(render(dir, &fig)?);
    }
    let stages: Vec<(String, Vec<f64>)> = fit
        .trace
        .iter()
        .map(|t| {
            let h = if t.history.is_empty() {
                t.cost.into_iter().collect()
            } else {
                t.history.clone()
            };
            (t.stage.clone(), h)
        })
        .filter(|(_, h)| !h.is_empty())
        .collect();
    if !stages.is_empty() {
        summary
            .figures
            .push(render(dir, &ConvergenceFigure { stages })?);
    }

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

/// Channels in fit.json's order, then any other channel named in curves.csv.
fn channel_list(fit: &FitResult, rows: &[CurveRow]) -> Vec<String> {
    let mut channels = fit.data.channels.clone();
    for r in rows {
        if !channels.contains(&r.channel) {
            channels.push(r.channel.clone());
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

/// Everything the figure builders share.
struct Ctx<'a> {
    fit: &'a FitResult,
    rows: &'a [CurveRow],
    samples: &'a [Sample],
    channel_of_row: &'a [usize],
    colours: &'a [(String, RGBColor)],
    model: Option<&'a LobeModel<'a>>,
    n_model: usize,
}

impl Ctx<'_> {
    /// The model's R, TT, TRT for `channel` at angles in degrees (`None` without a model).
    fn lobes_at(&self, deg: &[f64; 4], channel: usize) -> Option<[f64; 3]> {
        let model = self.model?;
        let mut out = vec![[0.0; 3]; self.n_model];
        model(
            &Angles::from_degrees(deg[0], deg[1], deg[2], deg[3]),
            &mut out,
        );
        Some(out[channel.min(self.n_model - 1)])
    }

    /// One slice: decimated points per channel and the dense model curve, calibrated to the
    /// fit column (the factor holds the fitted scale and any cos θ_i of the measurement).
    fn slice_panel(&self, slice: &Slice, summary: &mut ReportSummary) -> SlicePanel {
        let xs: Vec<f64> = slice
            .samples
            .iter()
            .map(|&s| slice.x_of(&self.samples[s].angles))
            .collect();
        let (x0, x1) = (xs[0], xs[xs.len() - 1]);
        let grid: Vec<f64> = (0..DENSE_POINTS)
            .map(|k| x0 + (x1 - x0) * k as f64 / (DENSE_POINTS - 1) as f64)
            .collect();
        let lobes_on = {
            let l = self.fit.model.effects.lobes;
            [l.r, l.tt, l.trt]
        };
        let mut channels = Vec::new();
        for (c, (name, colour)) in self.colours.iter().enumerate() {
            // (x, row) of this channel in the slice, in x order.
            let members: Vec<(f64, usize)> = slice
                .samples
                .iter()
                .zip(&xs)
                .flat_map(|(&s, &x)| {
                    self.samples[s]
                        .rows
                        .iter()
                        .filter(move |&&r| self.channel_of_row[r] == c)
                        .map(move |&r| (x, r))
                })
                .collect();
            if members.is_empty() {
                continue;
            }
            if members.len() > MAX_SLICE_POINTS {
                summary.decimated_series += 1;
            }
            let points: Vec<Point> = stride_indices(members.len(), MAX_SLICE_POINTS)
                .into_iter()
                .map(|k| {
                    let (x, r) = members[k];
                    let row = &self.rows[r];
                    Point {
                        x,
                        y: row.data,
                        sigma: row.sigma,
                        outlier: row.weight < 1.0,
                    }
                })
                .collect();
            let mut series = ChannelSeries {
                name: name.clone(),
                color: *colour,
                points,
                total: Vec::new(),
                lobes: [Vec::new(), Vec::new(), Vec::new()],
                fit_at_points: Vec::new(),
            };
            match self.calibration(&members, c, slice, summary) {
                Some(k) => {
                    let mut lobes = [Vec::new(), Vec::new(), Vec::new()];
                    let mut total = Vec::with_capacity(grid.len());
                    for &x in &grid {
                        let l = self
                            .lobes_at(&slice.angles_at(x), c)
                            .unwrap_or([f64::NAN; 3]);
                        total.push(k * (l[0] + l[1] + l[2]));
                        for p in 0..3 {
                            lobes[p].push(k * l[p]);
                        }
                    }
                    for p in 0..3 {
                        if !lobes_on[p] {
                            lobes[p].clear();
                        }
                    }
                    series.total = total;
                    series.lobes = lobes;
                }
                None => {
                    series.fit_at_points = stride_indices(members.len(), DENSE_POINTS)
                        .into_iter()
                        .map(|k| (members[k].0, self.rows[members[k].1].fit))
                        .collect();
                }
            }
            channels.push(series);
        }
        SlicePanel {
            title: slice.title(),
            x_label: slice.x_label().into(),
            grid,
            channels,
        }
    }

    /// The factor from the model to the fit column in a slice: the median ratio over a sample
    /// of its rows. A spread beyond rounding, or a factor that is not fit.json's scale of the
    /// channel (a constant the model did not reproduce, e.g. cos θ_i of a radiance fit), is
    /// reported as a note.
    fn calibration(
        &self,
        members: &[(f64, usize)],
        channel: usize,
        slice: &Slice,
        summary: &mut ReportSummary,
    ) -> Option<f64> {
        self.model?;
        let mut ratios: Vec<f64> = stride_indices(members.len(), CALIBRATION_SAMPLES)
            .into_iter()
            .filter_map(|k| {
                let row = &self.rows[members[k].1];
                let deg = [row.theta_i, row.phi_i, row.theta_r, row.phi_r];
                let l = self.lobes_at(&deg, channel)?;
                let s = l[0] + l[1] + l[2];
                let q = row.fit / s;
                (s > 0.0 && q.is_finite() && q > 0.0).then_some(q)
            })
            .collect();
        if ratios.is_empty() {
            return None;
        }
        ratios.sort_by(f64::total_cmp);
        let k = ratios[ratios.len() / 2];
        let spread = ratios
            .iter()
            .map(|q| (q / k - 1.0).abs())
            .fold(0.0, f64::max);
        if spread > CALIBRATION_TOLERANCE {
            summary.notes.push(format!(
                "slice {} channel {}: the re-evaluated model differs from curves.csv's fit column by up to {:.2e} (relative); the fit may have used other settings than fit.json records",
                slice.title(),
                self.colours[channel].0,
                spread
            ));
        }
        let fitted = self
            .fit
            .scale
            .iter()
            .find(|s| s.channel == self.colours[channel].0)
            .and_then(|s| s.value)
            .filter(|s| s.is_finite() && *s > 0.0);
        if let Some(s) = fitted.filter(|s| (k / s - 1.0).abs() > CALIBRATION_TOLERANCE) {
            summary.notes.push(format!(
                "slice {} channel {}: the re-evaluated model differs from curves.csv's fit column by a factor {k:.6e} where fit.json's scale is {s:.6e} ({:.2e} relative); the fit may have used other settings than fit.json records",
                slice.title(),
                self.colours[channel].0,
                k / s - 1.0
            ));
        }
        Some(k)
    }

    /// Measured against fitted value for every row (decimated evenly, outliers separately).
    fn data_vs_fit(&self, scale: YScale, only_view: bool, scattered: usize) -> DataVsFitFigure {
        let (out, keep): (Vec<usize>, Vec<usize>) =
            (0..self.rows.len()).partition(|&r| self.rows[r].weight < 1.0);
        let mut chosen: Vec<usize> = stride_indices(out.len(), MAX_SCATTER_POINTS / 4)
            .into_iter()
            .map(|k| out[k])
            .collect();
        let room = MAX_SCATTER_POINTS - chosen.len();
        chosen.extend(
            stride_indices(keep.len(), room)
                .into_iter()
                .map(|k| keep[k]),
        );
        let points = chosen
            .into_iter()
            .map(|r| {
                let row = &self.rows[r];
                (row.fit, row.data, self.channel_of_row[r], row.weight < 1.0)
            })
            .collect::<Vec<_>>();
        let what = if only_view {
            "no slices found: samples are scattered".to_string()
        } else {
            format!("{scattered} samples outside any slice")
        };
        DataVsFitFigure {
            subtitle: format!("{} of {} rows drawn; {what}", points.len(), self.rows.len()),
            points,
            channels: self.colours.to_vec(),
            scale,
        }
    }

    /// Residuals against φ and θ_h (envelope-decimated so outliers survive) and the histogram
    /// of all finite residuals.
    fn residuals(&self, summary: &mut ReportSummary) -> ResidualsFigure {
        let res: Vec<f64> = self.rows.iter().map(|r| r.residual).collect();
        let mut abs: Vec<f64> = res
            .iter()
            .filter(|v| v.is_finite())
            .map(|v| v.abs())
            .collect();
        let n_total = abs.len();
        if n_total < res.len() {
            summary.notes.push(format!(
                "{} residuals are not finite and are not drawn",
                res.len() - n_total
            ));
        }
        // The scatter axes span 99.9 % of residuals (at least ±3.5, the normal 1-in-2000 level)
        // so one wild point does not squash the rest; those beyond are drawn at the edge. The
        // histogram spans 99 % so its bins resolve the core of the distribution.
        let quantile = |abs: &mut Vec<f64>, q: f64, floor: f64| {
            if abs.is_empty() {
                return floor;
            }
            let k = ((abs.len() - 1) as f64 * q).round() as usize;
            let (_, v, _) = abs.select_nth_unstable_by(k, f64::total_cmp);
            (*v * 1.1).max(floor)
        };
        let limit = quantile(&mut abs, 0.999, 3.5);
        let hist_limit = quantile(&mut abs, 0.99, 3.5);
        let beyond = abs.iter().filter(|&&v| v > limit).count();
        if beyond > 0 {
            summary.notes.push(format!(
                "{beyond} residuals beyond ±{} are drawn at the edge of the residual axes",
                fmt_num(limit)
            ));
        }
        const BINS: usize = 41;
        let width = 2.0 * hist_limit / BINS as f64;
        let mut counts = vec![0u64; BINS];
        for &v in res.iter().filter(|v| v.is_finite()) {
            // Residuals beyond the histogram's range count in its edge bins.
            let b = ((v + hist_limit) / width)
                .floor()
                .clamp(0.0, (BINS - 1) as f64) as usize;
            counts[b] += 1;
        }
        let histogram = counts
            .into_iter()
            .enumerate()
            .map(|(b, c)| {
                let lo = -hist_limit + b as f64 * width;
                (lo, lo + width, c)
            })
            .collect();
        let n_outliers = self.rows.iter().filter(|r| r.weight < 1.0).count();
        let idx = envelope_indices(&res, MAX_SCATTER_POINTS);
        let points = idx
            .into_iter()
            .map(|r| {
                let row = &self.rows[r];
                let deg = [row.theta_i, row.phi_i, row.theta_r, row.phi_r];
                (
                    wrap_deg(row.phi_r - row.phi_i),
                    theta_h_deg(&deg),
                    row.residual,
                    self.channel_of_row[r],
                    row.weight < 1.0,
                )
            })
            .collect::<Vec<_>>();
        let r = &self.fit.residuals;
        ResidualsFigure {
            subtitle: format!(
                "space: {}, loss: {}; {} of {} residuals drawn (envelope decimation keeps the extremes); × down-weighted by the loss",
                r.space,
                r.loss,
                points.len(),
                n_total
            ),
            points,
            histogram,
            n_total,
            n_outliers,
            channels: self.colours.to_vec(),
            limit,
        }
    }
}
