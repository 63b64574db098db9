//! The residuals figure: normalised residuals against φ and against θh (decimated, extremes
//! kept, clamped to the axis limit) and the histogram of all finite residuals with the standard
//! normal density for reference.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::LEGEND_HEADER_H;
use crate::error::Result;
use crate::plot::{
    cartesian, de, draw_key, header, line_glyph, range_of, Axes, Chart, Figure, Frame, FONT,
    LABEL_PX,
};
use crate::slices::short;

/// Normalised residuals against φ and θ_h, and their histogram.
pub struct ResidualsFigure {
    /// (φ deg, θ_h deg, residual, channel index, outlier), decimated.
    pub points: Vec<(f64, f64, f64, usize, bool)>,
    /// Every finite residual (histogram counts are over all of them, not the drawn subset).
    pub histogram: Vec<(f64, f64, u64)>,
    pub n_total: usize,
    pub n_outliers: usize,
    pub channels: Vec<(String, RGBColor)>,
    pub subtitle: String,
    pub limit: f64,
}

/// The frame of each of the three panels, under its caption.
fn frame(caption: &str, y_label_area: u32) -> Frame<'_> {
    Frame {
        caption: Some(caption),
        margin: 10,
        x_label_area: 42,
        y_label_area,
    }
}

impl Figure for ResidualsFigure {
    fn stem(&self) -> &'static str {
        "residuals"
    }
    fn title(&self) -> String {
        "Normalised residuals against φ and θh, and their distribution".into()
    }
    fn size(&self) -> (u32, u32) {
        (1680, 590)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (head, body) = header(root, LEGEND_HEADER_H, &self.title(), &self.subtitle)?;
        draw_marker_legend(&head, &self.channels, LEGEND_HEADER_H as i32 - 22)?;
        let areas = body.split_evenly((1, 3));
        let phi = ("residual against φ", "φ = φr − φi (deg)");
        self.draw_scatter(&areas[0], phi, |p| p.0, Some((-180.0, 180.0)))?;
        let theta_h = ("residual against θh", "θh = (θi + θr)/2 (deg)");
        self.draw_scatter(&areas[1], theta_h, |p| p.1, None)?;
        self.draw_histogram(&areas[2])
    }
}

impl ResidualsFigure {
    /// Residual against the angle `x_of` picks, under (caption, x description), on `x_range`
    /// or else the range of the drawn points.
    fn draw_scatter<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        (caption, x_desc): (&str, &str),
        x_of: fn(&(f64, f64, f64, usize, bool)) -> f64,
        x_range: Option<(f64, f64)>,
    ) -> Result<()> {
        let m = self.limit;
        let (x0, x1) =
            x_range.unwrap_or_else(|| range_of(self.points.iter().map(x_of), 0.03, (-90.0, 90.0)));
        let mut chart = cartesian(area, frame(caption, 60), x0..x1, -m..m)?;
        let sfmt = |v: &f64| short(*v);
        Axes::new(x_desc, "normalised residual", &sfmt, &sfmt).draw(&mut chart)?;
        chart
            .draw_series(LineSeries::new(vec![(x0, 0.0), (x1, 0.0)], BLACK.mix(0.5)))
            .map_err(de)?;
        for (ci, (_, colour)) in self.channels.iter().enumerate() {
            let colour = *colour;
            chart
                .draw_series(
                    self.points.iter().filter(|p| p.3 == ci && !p.4).map(|p| {
                        Circle::new((x_of(p), p.2.clamp(-m, m)), 2, colour.mix(0.7).filled())
                    }),
                )
                .map_err(de)?;
            chart
                .draw_series(
                    self.points.iter().filter(|p| p.3 == ci && p.4).map(|p| {
                        Cross::new((x_of(p), p.2.clamp(-m, m)), 3, colour.stroke_width(1))
                    }),
                )
                .map_err(de)?;
        }
        Ok(())
    }

    /// Histogram with the standard normal density for reference.
    fn draw_histogram<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()> {
        let hm = self.histogram.last().map_or(self.limit, |b| b.1);
        let total: u64 = self.histogram.iter().map(|b| b.2).sum();
        let width = self.histogram.first().map_or(1.0, |b| b.1 - b.0);
        let normal = |x: f64| {
            total as f64 * width * (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt()
        };
        let top = self
            .histogram
            .iter()
            .map(|b| b.2 as f64)
            .fold(normal(0.0), f64::max)
            .max(1.0)
            * 1.1;
        let caption = "distribution of residuals (edge bins hold the tails)";
        let mut chart: Chart<DB> = cartesian(area, frame(caption, 70), -hm..hm, 0.0..top)?;
        let count_fmt = |v: &f64| format!("{v:.0}");
        let sfmt = |v: &f64| short(*v);
        Axes::new("normalised residual", "count", &sfmt, &count_fmt).draw(&mut chart)?;
        let bar = RGBColor(120, 130, 150).filled();
        chart
            .draw_series(
                self.histogram
                    .iter()
                    .map(|&(a, b, c)| Rectangle::new([(a, 0.0), (b, c as f64)], bar)),
            )
            .map_err(de)?
            .label(format!(
                "{} residuals, {} down-weighted",
                self.n_total, self.n_outliers
            ))
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], bar));
        let curve: Vec<(f64, f64)> = (0..=200)
            .map(|i| {
                let x = -hm + 2.0 * hm * i as f64 / 200.0;
                (x, normal(x))
            })
            .collect();
        chart
            .draw_series(LineSeries::new(curve, RED.stroke_width(2)))
            .map_err(de)?
            .label("standard normal (reference)")
            .legend(line_glyph(RED.stroke_width(2)));
        draw_key(&mut chart, SeriesLabelPosition::UpperRight, 12)
    }
}

/// A legend row for the scatter panels: a dot per channel, and a cross for down-weighted points.
fn draw_marker_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    channels: &[(String, RGBColor)],
    y: i32,
) -> Result<()> {
    let style = (FONT, LABEL_PX)
        .into_font()
        .into_text_style(area)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let mut x = 20;
    for (name, colour) in channels {
        area.draw(&Circle::new((x + 6, y), 4, colour.filled()))
            .map_err(de)?;
        let label = format!("channel {name}");
        area.draw(&Text::new(label.clone(), (x + 16, y), style.clone()))
            .map_err(de)?;
        x += 40 + 8 * label.chars().count() as i32;
    }
    area.draw(&Cross::new((x + 6, y), 5, BLACK.stroke_width(1)))
        .map_err(de)?;
    area.draw(&Text::new(
        "down-weighted by the loss (weight < 0.5), in the channel's colour",
        (x + 16, y),
        style,
    ))
    .map_err(de)?;
    Ok(())
}
