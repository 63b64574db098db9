//! The figures' content built from the fit's result: slice panels with the dense model curve
//! (scaled by fit.json's scale, checked against curves.csv's fit column), data against fit,
//! and residuals. Decimation happens here; drawing is in [`super::figures`].

use plotters::prelude::RGBColor;
use rayon::prelude::*;

use super::figures::{ChannelSeries, DataVsFitFigure, Point, ResidualsFigure, SlicePanel};
use super::{LobeModel, ReportSummary, DENSE_POINTS, MAX_SCATTER_POINTS, MAX_SLICE_POINTS};
use crate::files::{Curves, FitJson};
use crate::geometry::Angles;
use crate::plot::{fmt_num, YScale};
use crate::slices::decimate::{envelope_indices, stride_indices};
use crate::slices::{theta_h_deg, wrap_deg, Sample, Slice};

/// Samples per slice at which the dense curve is checked against the fit column.
const CHECK_SAMPLES: usize = 64;
/// Relative disagreement between the dense curve and the fit column that gets reported: the
/// two come from the same model, parameters and scale, so anything beyond rounding means the
/// files do not belong together.
const CHECK_TOLERANCE: f64 = 1e-6;

/// Everything the figure builders share.
pub(super) struct Ctx<'a> {
    pub fit: &'a FitJson,
    pub curves: &'a Curves,
    pub samples: &'a [Sample],
    /// The report's channel index of each of the table's channels.
    pub channel_of: &'a [usize],
    pub colours: &'a [(String, RGBColor)],
    pub model: Option<&'a LobeModel<'a>>,
    pub n_model: usize,
}

impl Ctx<'_> {
    /// The report's channel index of row `r`.
    fn channel(&self, r: usize) -> usize {
        self.channel_of[self.curves.row_channel[r] as usize]
    }

    /// The model's R, TT, TRT for `channel` at angles in degrees (`None` without a model).
    fn lobes_at(&self, deg: &[f64; 4], channel: usize) -> Option<[f64; 3]> {
        Some(self.all_lobes_at(deg)?[channel.min(self.n_model - 1)])
    }

    /// The model's R, TT, TRT for every channel at angles in degrees.
    fn all_lobes_at(&self, deg: &[f64; 4]) -> Option<Vec<[f64; 3]>> {
        let model = self.model?;
        let mut out = vec![[0.0; 3]; self.n_model];
        model(
            &Angles::from_degrees(deg[0], deg[1], deg[2], deg[3]),
            &mut out,
        );
        Some(out)
    }

    /// One slice: decimated points per channel and the dense model curve, calibrated to the
    /// fit column (the factor holds the fitted scale and any cos θ_i of the measurement).
    pub(super) fn slice_panel(&self, slice: &Slice, summary: &mut ReportSummary) -> SlicePanel {
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
        // The dense curve for every channel at once, the grid in parallel: one evaluation per
        // point, not one per point and channel (a Chiang curve point costs a width integral).
        let dense: Vec<Option<Vec<[f64; 3]>>> = grid
            .par_iter()
            .map(|&x| self.all_lobes_at(&slice.angles_at(x)))
            .collect();
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
                        .filter(move |&&r| self.channel(r) == c)
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
                    Point {
                        x,
                        y: self.curves.values[r].data,
                        sigma: self.curves.sigma(r),
                        outlier: self.curves.down_weighted(r),
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
            match self.scale_checked(&members, c, slice, summary) {
                Some(k) => {
                    let mut lobes = [Vec::new(), Vec::new(), Vec::new()];
                    let mut total = Vec::with_capacity(grid.len());
                    for point in &dense {
                        let l = point
                            .as_ref()
                            .map_or([f64::NAN; 3], |all| all[c.min(self.n_model - 1)]);
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
                        .map(|k| (members[k].0, self.curves.values[members[k].1].fit))
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

    /// The fitted scale of `channel` (fit.json), which takes the model to the fit column;
    /// checked at a sample of the slice's rows, a disagreement beyond rounding (files that do
    /// not belong together) is reported as a note. `None` without a model or a finite scale.
    fn scale_checked(
        &self,
        members: &[(f64, usize)],
        channel: usize,
        slice: &Slice,
        summary: &mut ReportSummary,
    ) -> Option<f64> {
        self.model?;
        let name = &self.colours[channel].0;
        let k = self.fit.scale_of(name)?;
        let worst = stride_indices(members.len(), CHECK_SAMPLES)
            .into_iter()
            .filter_map(|i| {
                let r = members[i].1;
                let l = self.lobes_at(&self.curves.angles_deg(r), channel)?;
                let d = (k * (l[0] + l[1] + l[2]) / self.curves.values[r].fit - 1.0).abs();
                d.is_finite().then_some(d)
            })
            .fold(0.0, f64::max);
        if worst > CHECK_TOLERANCE {
            summary.notes.push(format!(
                "slice {} channel {name}: the model re-evaluated with fit.json's parameters times fit.json's scale {k:.6e} differs from curves.csv's fit column by up to {worst:.2e} (relative); the files may not come from the same fit",
                slice.title(),
            ));
        }
        Some(k)
    }

    /// Measured against fitted value for every row (decimated evenly, outliers separately).
    pub(super) fn data_vs_fit(
        &self,
        scale: YScale,
        only_view: bool,
        scattered: usize,
    ) -> DataVsFitFigure {
        let (out, keep): (Vec<usize>, Vec<usize>) =
            (0..self.curves.len()).partition(|&r| self.curves.down_weighted(r));
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
                let v = &self.curves.values[r];
                (v.fit, v.data, self.channel(r), self.curves.down_weighted(r))
            })
            .collect::<Vec<_>>();
        let what = if only_view {
            "no slices found: samples are scattered".to_string()
        } else {
            format!("{scattered} samples outside any slice")
        };
        DataVsFitFigure {
            subtitle: format!(
                "{} of {} rows drawn; {what}",
                points.len(),
                self.curves.len()
            ),
            points,
            channels: self.colours.to_vec(),
            scale,
        }
    }

    /// Residuals against φ and θ_h (envelope-decimated so outliers survive) and the histogram
    /// of all finite residuals.
    pub(super) fn residuals(&self, summary: &mut ReportSummary) -> ResidualsFigure {
        let res: Vec<f64> = self.curves.values.iter().map(|v| v.residual).collect();
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
        let n_outliers = (0..self.curves.len())
            .filter(|&r| self.curves.down_weighted(r))
            .count();
        let idx = envelope_indices(&res, MAX_SCATTER_POINTS);
        let points = idx
            .into_iter()
            .map(|r| {
                let deg = self.curves.angles_deg(r);
                (
                    wrap_deg(deg[3] - deg[1]),
                    theta_h_deg(&deg),
                    self.curves.values[r].residual,
                    self.channel(r),
                    self.curves.down_weighted(r),
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
