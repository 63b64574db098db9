//! The curves figure: a grid of slice panels, each with the measured points (error bars,
//! down-weighted points crossed) and the dense model curve with its R, TT and TRT lobes, under
//! a header whose legend row names channels, lobe line styles and markers.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{SlicePanel, LEGEND_HEADER_H};
use crate::error::Result;
use crate::plot::{cartesian, de, header, range_of, Axes, Figure, Frame, YScale, FONT, LABEL_PX};
use crate::slices::short;

/// Style of a lobe line (R, TT, TRT): (dash length, gap) in pixels, 0 gap = solid.
const LOBE_STYLE: [(u32, u32); 3] = [(10, 5), (3, 3), (1, 0)];
const LOBE_NAMES: [&str; 3] = ["R", "TT", "TRT"];

const PANEL_W: u32 = 560;
const PANEL_H: u32 = 420;

/// Measured points and fitted curves of every shown slice, a grid of panels.
pub struct CurvesFigure {
    pub panels: Vec<SlicePanel>,
    /// Channel names and colours, for the legend.
    pub channels: Vec<(String, RGBColor)>,
    pub scale: YScale,
    pub subtitle: String,
}

impl CurvesFigure {
    /// (columns, rows) of the panel grid.
    fn grid(&self) -> (usize, usize) {
        let cols = self.panels.len().clamp(1, 3);
        (cols, self.panels.len().div_ceil(cols).max(1))
    }
}

impl Figure for CurvesFigure {
    fn stem(&self) -> &'static str {
        "curves"
    }
    fn title(&self) -> String {
        "Measured points and fitted model per slice (total, and R/TT/TRT lobes)".into()
    }
    fn size(&self) -> (u32, u32) {
        let (cols, rows) = self.grid();
        (
            cols as u32 * PANEL_W,
            LEGEND_HEADER_H + rows as u32 * PANEL_H,
        )
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (head, body) = header(root, LEGEND_HEADER_H, &self.title(), &self.subtitle)?;
        let (cols, rows) = self.grid();
        let areas = body.split_evenly((rows, cols));
        draw_legend(&head, &self.channels, LEGEND_HEADER_H as i32 - 22)?;
        for (panel, area) in self.panels.iter().zip(areas.iter()) {
            draw_slice_panel(area, panel, self.scale)?;
        }
        Ok(())
    }
}

/// Consecutive runs of drawable (x, mapped y) points, broken where the value cannot be shown
/// or falls below the axis floor.
fn segments(xs: &[f64], ys: &[f64], scale: YScale, floor: f64) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    let mut run = Vec::new();
    for (&x, &y) in xs.iter().zip(ys) {
        match scale.map(y) {
            Some(v) if v >= floor => run.push((x, v)),
            _ => {
                if run.len() > 1 {
                    out.push(std::mem::take(&mut run));
                }
                run.clear();
            }
        }
    }
    if run.len() > 1 {
        out.push(run);
    }
    out
}

/// A log axis shows at most this many decades below a panel's largest value: one stray tiny
/// value (a model's zero at φ = ±180°, a dark sample) must not squash the lobes into a strip.
pub const MAX_LOG_DECADES: f64 = 5.0;

/// The curves figure's subtitle says where lower values go.
pub const LOG_FLOOR_NOTE: &str =
    "; log axes span at most 5 decades below each panel's peak: lower points sit on the floor";

/// The low end of a log axis holding mapped values `lo..hi`, capped [`MAX_LOG_DECADES`] below
/// `hi`.
pub fn log_floor(lo: f64, hi: f64) -> f64 {
    lo.max(hi - MAX_LOG_DECADES)
}

/// The value range of a panel in plot coordinates: log axes get a fixed margin and at most
/// [`MAX_LOG_DECADES`], linear ones start at zero at the latest.
fn value_range(panel: &SlicePanel, scale: YScale) -> (f64, f64) {
    let ys = panel.channels.iter().flat_map(|c| {
        c.points
            .iter()
            .filter_map(move |p| scale.map(p.y))
            .chain(c.total.iter().filter_map(move |&y| scale.map(y)))
            .chain(c.fit_at_points.iter().filter_map(move |p| scale.map(p.1)))
    });
    let pad = if scale == YScale::Log { 0.0 } else { 0.05 };
    let (y0, y1) = range_of(ys, pad, (-1.0, 1.0));
    match scale {
        YScale::Log => (log_floor(y0, y1) - 0.15, y1 + 0.15),
        YScale::Linear => (y0.min(0.0), y1),
    }
}

fn draw_slice_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &SlicePanel,
    scale: YScale,
) -> Result<()> {
    let xs = panel
        .channels
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.x))
        .chain(panel.grid.iter().copied());
    let (x0, x1) = range_of(xs, 0.03, (-180.0, 180.0));
    let (y0, y1) = value_range(panel, scale);
    let frame = Frame {
        caption: Some(&panel.title),
        margin: 8,
        x_label_area: 42,
        y_label_area: 70,
    };
    let mut chart = cartesian(area, frame, x0..x1, y0..y1)?;
    let y_fmt = |v: &f64| scale.label(*v, y1 - y0);
    let x_fmt = |v: &f64| short(*v);
    let y_desc = format!("value (arb. units{})", scale.suffix());
    Axes::new(panel.x_label.as_str(), y_desc, &x_fmt, &y_fmt)
        .ticks(11, scale.ticks(y1 - y0))
        .draw(&mut chart)?;
    for ch in &panel.channels {
        let colour = ch.color;
        for (li, lobe) in ch.lobes.iter().enumerate() {
            let (dash, gap) = LOBE_STYLE[li];
            let style = colour.mix(0.75).stroke_width(1);
            for seg in segments(&panel.grid, lobe, scale, y0) {
                if gap == 0 {
                    chart.draw_series(LineSeries::new(seg, style)).map_err(de)?;
                } else {
                    chart
                        .draw_series(DashedLineSeries::new(seg, dash, gap, style))
                        .map_err(de)?;
                }
            }
        }
        let thick = colour.stroke_width(2);
        for seg in segments(&panel.grid, &ch.total, scale, y0) {
            chart.draw_series(LineSeries::new(seg, thick)).map_err(de)?;
        }
        if !ch.fit_at_points.is_empty() {
            let pts: Vec<(f64, f64)> = ch
                .fit_at_points
                .iter()
                .filter_map(|&(x, y)| scale.map(y).map(|v| (x, v.max(y0))))
                .collect();
            chart.draw_series(LineSeries::new(pts, thick)).map_err(de)?;
        }
        // Error bars, then the points on top.
        let bar = colour.mix(0.6).stroke_width(1);
        chart
            .draw_series(ch.points.iter().filter_map(|p| {
                let s = p.sigma.filter(|s| s.is_finite() && *s > 0.0)?;
                let mid = scale.map(p.y)?.max(y0);
                let lo = scale.map(p.y - s).unwrap_or(y0).max(y0);
                let hi = scale.map(p.y + s)?.clamp(y0, y1);
                Some(ErrorBar::new_vertical(p.x, lo, mid, hi, bar, 6))
            }))
            .map_err(de)?;
        chart
            .draw_series(ch.points.iter().filter(|p| !p.outlier).filter_map(|p| {
                scale
                    .map(p.y)
                    .map(|v| Circle::new((p.x, v.max(y0)), 3, colour.filled()))
            }))
            .map_err(de)?;
        chart
            .draw_series(ch.points.iter().filter(|p| p.outlier).filter_map(|p| {
                scale
                    .map(p.y)
                    .map(|v| Cross::new((p.x, v.max(y0)), 5, BLACK.stroke_width(2)))
            }))
            .map_err(de)?;
    }
    Ok(())
}

/// The legend as one row of pixel-space glyphs: channel colours, line styles, markers.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    channels: &[(String, RGBColor)],
    y: i32,
) -> Result<()> {
    let grey = RGBColor(90, 90, 90);
    let text = |s: &str, x: i32| {
        Text::new(
            s.to_string(),
            (x, y),
            (FONT, LABEL_PX)
                .into_font()
                .into_text_style(area)
                .pos(Pos::new(HPos::Left, VPos::Center)),
        )
    };
    let seg = |x0: i32, x1: i32, style: ShapeStyle| PathElement::new(vec![(x0, y), (x1, y)], style);
    let mut x = 20;
    for (name, colour) in channels {
        area.draw(&Circle::new((x + 6, y), 4, colour.filled()))
            .map_err(de)?;
        area.draw(&seg(x + 14, x + 40, colour.stroke_width(2)))
            .map_err(de)?;
        let label = format!("channel {name}: data, fit");
        area.draw(&text(&label, x + 46)).map_err(de)?;
        x += 60 + 8 * label.chars().count() as i32;
    }
    for (li, name) in LOBE_NAMES.iter().enumerate() {
        let (dash, gap) = LOBE_STYLE[li];
        let style = grey.stroke_width(1);
        if gap == 0 {
            area.draw(&seg(x, x + 36, style)).map_err(de)?;
        } else {
            let mut a = x;
            while a < x + 36 {
                area.draw(&seg(a, (a + dash as i32).min(x + 36), style))
                    .map_err(de)?;
                a += (dash + gap) as i32;
            }
        }
        let label = format!("{name} lobe");
        area.draw(&text(&label, x + 42)).map_err(de)?;
        x += 56 + 8 * label.chars().count() as i32;
    }
    area.draw(&ErrorBar::new_vertical(
        x + 6,
        y - 7,
        y,
        y + 7,
        grey.stroke_width(1),
        6,
    ))
    .map_err(de)?;
    area.draw(&text("± σ", x + 16)).map_err(de)?;
    x += 60;
    area.draw(&Cross::new((x + 6, y), 5, BLACK.stroke_width(2)))
        .map_err(de)?;
    area.draw(&text("down-weighted by the loss (weight < 0.5)", x + 18))
        .map_err(de)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stray_tiny_value_does_not_stretch_a_log_axis() {
        // The old demo: peak 3 (log 0.48), one model value 1e-26 at φ = −180°: the axis keeps
        // 5 decades, not 26, and the figure's note names that number.
        assert_eq!(log_floor(-26.0, 0.48), 0.48 - MAX_LOG_DECADES);
        assert_eq!(log_floor(-2.0, 0.48), -2.0);
        assert!(LOG_FLOOR_NOTE.contains(&format!("{MAX_LOG_DECADES} decades")));
    }

    #[test]
    fn segments_break_at_gaps() {
        let xs = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let ys = [1.0, 1.0, 0.0, 1.0, 1.0, 1.0];
        let s = segments(&xs, &ys, YScale::Log, -10.0);
        assert_eq!(s.len(), 2);
        assert_eq!(s[1].len(), 3);
    }
}
