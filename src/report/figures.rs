//! The report's figures, drawn with plotters onto any backend (the same code writes SVG and PNG):
//! per-slice curves, data against fit, residuals, a polar view, the correlation heatmap and the
//! convergence trace. Figures receive prepared, already decimated data; they only draw.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::slices::short;
use crate::error::{Error, Result};

/// Font family registered with the shipped DejaVu Sans (see `report::register_fonts`).
pub const FONT: &str = "sans-serif";
const TITLE_PX: u32 = 22;
const CAPTION_PX: u32 = 17;
const LABEL_PX: u32 = 14;

/// A figure that can be drawn onto any plotters backend at a fixed pixel size.
pub trait Figure {
    /// File stem (`curves` → curves.svg, curves.png).
    fn stem(&self) -> &'static str;
    /// What the figure shows (also its heading in index.html).
    fn title(&self) -> String;
    /// Size in pixels.
    fn size(&self) -> (u32, u32);
    /// Draw onto a white area of [`Figure::size`].
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>;
}

/// A drawing error as a library error.
pub fn de<E: std::fmt::Display>(e: E) -> Error {
    Error::Other(format!("drawing the report failed: {e}"))
}

/// Log axes spanning at least this many decades label decades only.
const DECADES_ONLY: f64 = 2.5;

/// Log or linear vertical scale; log plots log10(y) on linear axes with 10^k tick labels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum YScale {
    Log,
    Linear,
}

impl YScale {
    /// Plot coordinate of a value, `None` when it cannot be shown (≤ 0 on a log scale, NaN).
    pub fn map(self, y: f64) -> Option<f64> {
        let v = match self {
            YScale::Log if y > 0.0 => y.log10(),
            YScale::Log => return None,
            YScale::Linear => y,
        };
        v.is_finite().then_some(v)
    }

    /// Tick label for a plot coordinate on an axis spanning `span`: on a log axis spanning more
    /// than [`DECADES_ONLY`] decades only decades are labelled (other grid lines stay unlabelled).
    pub fn label(self, v: f64, span: f64) -> String {
        match self {
            YScale::Log if span >= DECADES_ONLY => {
                let k = v.round();
                if (v - k).abs() > 1e-6 {
                    String::new()
                } else if (-3.0..=3.0).contains(&k) {
                    fmt_num(10f64.powf(k))
                } else {
                    format!("1e{k}")
                }
            }
            YScale::Log => sig2(10f64.powf(v)),
            YScale::Linear => fmt_num(v),
        }
    }

    /// How many tick positions to ask plotters for on an axis spanning `span` (log: one per
    /// decade, so ticks fall on decades).
    pub fn ticks(self, span: f64) -> usize {
        match self {
            YScale::Log if span >= DECADES_ONLY => (span.ceil() as usize + 1).clamp(3, 16),
            YScale::Log => 6,
            YScale::Linear => 10,
        }
    }

    /// The axis-label suffix naming the scale.
    pub fn suffix(self) -> &'static str {
        match self {
            YScale::Log => ", log scale",
            YScale::Linear => "",
        }
    }
}

/// A compact number for labels and tables; never prints NaN or inf.
pub fn fmt_num(v: f64) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-3..1e4).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
        // Keep four significant digits at most.
        let digits = s.chars().filter(|c| c.is_ascii_digit()).count();
        if digits > 4 {
            let p = 3 - a.log10().floor() as i32;
            format!("{v:.*}", p.max(0) as usize)
        } else {
            s
        }
    } else {
        format!("{v:.2e}")
    }
}

/// Two significant digits (tick labels between decades), never NaN text.
pub fn sig2(v: f64) -> String {
    if !v.is_finite() || v == 0.0 {
        return fmt_num(v);
    }
    let p = 1 - v.abs().log10().floor() as i32;
    if (0..=5).contains(&p) {
        format!("{v:.*}", p as usize)
    } else {
        format!("{v:.1e}")
    }
}

/// A padded range holding every finite value; `fallback` when none.
pub fn range_of(values: impl Iterator<Item = f64>, pad: f64, fallback: (f64, f64)) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return fallback;
    }
    let span = hi - lo;
    if span <= 1e-12 * hi.abs().max(1.0) {
        let d = if hi == 0.0 { 1.0 } else { 0.5 * hi.abs() };
        return (lo - d, hi + d);
    }
    (lo - pad * span, hi + pad * span)
}

/// Colour of a channel by name (r, g, b and their spelled-out forms), else from a palette.
pub fn channel_color(name: &str, index: usize) -> RGBColor {
    match name.to_ascii_lowercase().as_str() {
        "r" | "red" => RGBColor(205, 35, 35),
        "g" | "green" => RGBColor(30, 145, 50),
        "b" | "blue" => RGBColor(35, 75, 205),
        _ => {
            const OTHERS: [RGBColor; 6] = [
                RGBColor(20, 20, 20),
                RGBColor(230, 120, 0),
                RGBColor(130, 50, 170),
                RGBColor(0, 140, 150),
                RGBColor(150, 90, 40),
                RGBColor(200, 60, 140),
            ];
            OTHERS[index % OTHERS.len()]
        }
    }
}

/// Style of a lobe line (R, TT, TRT): (dash length, gap) in pixels, 0 gap = solid.
const LOBE_STYLE: [(u32, u32); 3] = [(10, 5), (3, 3), (1, 0)];
const LOBE_NAMES: [&str; 3] = ["R", "TT", "TRT"];

/// A measured point as drawn.
#[derive(Debug, Clone, Copy)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    pub sigma: Option<f64>,
    /// Robust-loss weight < 1: marked as down-weighted.
    pub outlier: bool,
}

/// One channel's data and dense model curve in one slice.
#[derive(Debug, Clone)]
pub struct ChannelSeries {
    pub name: String,
    pub color: RGBColor,
    pub points: Vec<Point>,
    /// Model total on the dense grid (empty when the model could not be evaluated).
    pub total: Vec<f64>,
    /// R, TT, TRT on the dense grid (each empty when disabled or unavailable).
    pub lobes: [Vec<f64>; 3],
    /// When there is no dense curve: the fit column at the points, drawn as a line.
    pub fit_at_points: Vec<(f64, f64)>,
}

/// One slice panel.
#[derive(Debug, Clone)]
pub struct SlicePanel {
    pub title: String,
    pub x_label: String,
    pub grid: Vec<f64>,
    pub channels: Vec<ChannelSeries>,
}

/// Measured points and fitted curves of every shown slice, a grid of panels.
pub struct CurvesFigure {
    pub panels: Vec<SlicePanel>,
    /// Channel names and colours, for the legend.
    pub channels: Vec<(String, RGBColor)>,
    pub scale: YScale,
    pub subtitle: String,
}

const PANEL_W: u32 = 560;
const PANEL_H: u32 = 420;
const HEADER_H: u32 = 70;
/// The curves figure's header also holds its legend.
const CURVES_HEADER_H: u32 = 100;

/// Columns of a panel grid with `n` panels.
fn grid_cols(n: usize) -> usize {
    n.clamp(1, 3)
}

impl Figure for CurvesFigure {
    fn stem(&self) -> &'static str {
        "curves"
    }
    fn title(&self) -> String {
        "Measured points and fitted model per slice (total, and R/TT/TRT lobes)".into()
    }
    fn size(&self) -> (u32, u32) {
        let cols = grid_cols(self.panels.len());
        let rows = self.panels.len().div_ceil(cols).max(1);
        (
            cols as u32 * PANEL_W,
            CURVES_HEADER_H + rows as u32 * PANEL_H,
        )
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (header, body) = root.split_vertically(CURVES_HEADER_H);
        draw_header(&header, &self.title(), &self.subtitle)?;
        let cols = grid_cols(self.panels.len());
        let rows = self.panels.len().div_ceil(cols).max(1);
        let areas = body.split_evenly((rows, cols));
        draw_curves_legend(&header, &self.channels, CURVES_HEADER_H as i32 - 22)?;
        for (panel, area) in self.panels.iter().zip(areas.iter()) {
            draw_slice_panel(area, panel, self.scale)?;
        }
        Ok(())
    }
}

/// Figure title and a line of explanation.
fn draw_header<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    sub: &str,
) -> Result<()> {
    let (w, _) = area.dim_in_pixel();
    let centre = Pos::new(HPos::Center, VPos::Top);
    area.draw(&Text::new(
        title.to_string(),
        (w as i32 / 2, 8),
        (FONT, TITLE_PX)
            .into_font()
            .style(FontStyle::Bold)
            .into_text_style(area)
            .pos(centre),
    ))
    .map_err(de)?;
    area.draw(&Text::new(
        sub.to_string(),
        (w as i32 / 2, 40),
        (FONT, LABEL_PX)
            .into_font()
            .into_text_style(area)
            .pos(centre),
    ))
    .map_err(de)?;
    Ok(())
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
    let ys = panel.channels.iter().flat_map(|c| {
        c.points
            .iter()
            .filter_map(move |p| scale.map(p.y))
            .chain(c.total.iter().filter_map(move |&y| scale.map(y)))
            .chain(c.fit_at_points.iter().filter_map(move |p| scale.map(p.1)))
    });
    let pad = if scale == YScale::Log { 0.0 } else { 0.05 };
    let (mut y0, mut y1) = range_of(ys, pad, (-1.0, 1.0));
    if scale == YScale::Log {
        y0 -= 0.15;
        y1 += 0.15;
    } else {
        y0 = y0.min(0.0);
    }
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, (FONT, CAPTION_PX))
        .margin(8)
        .x_label_area_size(42)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(de)?;
    let y_fmt = |v: &f64| scale.label(*v, y1 - y0);
    let x_fmt = |v: &f64| short(*v);
    chart
        .configure_mesh()
        .x_desc(panel.x_label.as_str())
        .y_desc(format!("value (arb. units{})", scale.suffix()))
        .y_label_formatter(&y_fmt)
        .y_labels(scale.ticks(y1 - y0))
        .x_label_formatter(&x_fmt)
        .label_style((FONT, LABEL_PX))
        .axis_desc_style((FONT, LABEL_PX))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(de)?;
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
                .filter_map(|&(x, y)| scale.map(y).map(|v| (x, v)))
                .collect();
            chart.draw_series(LineSeries::new(pts, thick)).map_err(de)?;
        }
        // Error bars, then the points on top.
        let bar = colour.mix(0.6).stroke_width(1);
        chart
            .draw_series(ch.points.iter().filter_map(|p| {
                let s = p.sigma.filter(|s| s.is_finite() && *s > 0.0)?;
                let mid = scale.map(p.y)?;
                let lo = scale.map(p.y - s).unwrap_or(y0).max(y0);
                let hi = scale.map(p.y + s)?.min(y1);
                Some(ErrorBar::new_vertical(p.x, lo, mid, hi, bar, 6))
            }))
            .map_err(de)?;
        chart
            .draw_series(ch.points.iter().filter(|p| !p.outlier).filter_map(|p| {
                scale
                    .map(p.y)
                    .map(|v| Circle::new((p.x, v), 3, colour.filled()))
            }))
            .map_err(de)?;
        chart
            .draw_series(ch.points.iter().filter(|p| p.outlier).filter_map(|p| {
                scale
                    .map(p.y)
                    .map(|v| Cross::new((p.x, v), 5, BLACK.stroke_width(2)))
            }))
            .map_err(de)?;
    }
    Ok(())
}

/// The curves' legend as one row of pixel-space glyphs: channel colours, line styles, markers.
fn draw_curves_legend<DB: DrawingBackend>(
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
    area.draw(&text("down-weighted by the loss (weight < 1)", x + 18))
        .map_err(de)?;
    Ok(())
}

/// A legend row for scatter figures: a dot per channel, and a cross for down-weighted points.
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
        "down-weighted by the loss (weight < 1), in the channel's colour",
        (x + 16, y),
        style,
    ))
    .map_err(de)?;
    Ok(())
}

/// Scattered data (no slices): measured value against fitted value, with the identity line.
pub struct DataVsFitFigure {
    /// (fit, data, channel index, outlier)
    pub points: Vec<(f64, f64, usize, bool)>,
    pub channels: Vec<(String, RGBColor)>,
    pub scale: YScale,
    pub subtitle: String,
}

impl Figure for DataVsFitFigure {
    fn stem(&self) -> &'static str {
        "data_vs_fit"
    }
    fn title(&self) -> String {
        "Measured value against fitted value, every sample (identity line = perfect fit)".into()
    }
    fn size(&self) -> (u32, u32) {
        (900, 820)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (header, body) = root.split_vertically(HEADER_H);
        draw_header(&header, &self.title(), &self.subtitle)?;
        let sc = self.scale;
        let all = self
            .points
            .iter()
            .flat_map(|p| [sc.map(p.0), sc.map(p.1)])
            .flatten();
        let (lo, hi) = range_of(all, 0.05, (0.0, 1.0));
        let mut chart = ChartBuilder::on(&body)
            .margin(12)
            .x_label_area_size(46)
            .y_label_area_size(80)
            .build_cartesian_2d(lo..hi, lo..hi)
            .map_err(de)?;
        let fmt = |v: &f64| sc.label(*v, hi - lo);
        chart
            .configure_mesh()
            .x_labels(sc.ticks(hi - lo))
            .y_labels(sc.ticks(hi - lo))
            .x_desc(format!("fitted value (arb. units{})", sc.suffix()))
            .y_desc(format!("measured value (arb. units{})", sc.suffix()))
            .x_label_formatter(&fmt)
            .y_label_formatter(&fmt)
            .label_style((FONT, LABEL_PX))
            .axis_desc_style((FONT, LABEL_PX + 1))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(de)?;
        chart
            .draw_series(LineSeries::new(
                vec![(lo, lo), (hi, hi)],
                BLACK.mix(0.6).stroke_width(1),
            ))
            .map_err(de)?
            .label("identity")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], BLACK.mix(0.6)));
        for (ci, (name, colour)) in self.channels.iter().enumerate() {
            let colour = *colour;
            chart
                .draw_series(
                    self.points
                        .iter()
                        .filter(|p| p.2 == ci && !p.3)
                        .filter_map(|p| {
                            Some(Circle::new(
                                (sc.map(p.0)?, sc.map(p.1)?),
                                2,
                                colour.mix(0.7).filled(),
                            ))
                        }),
                )
                .map_err(de)?
                .label(format!("data {name}"))
                .legend(move |(x, y)| Circle::new((x + 12, y), 3, colour.filled()));
        }
        chart
            .draw_series(self.points.iter().filter(|p| p.3).filter_map(|p| {
                Some(Cross::new(
                    (sc.map(p.0)?, sc.map(p.1)?),
                    4,
                    BLACK.stroke_width(2),
                ))
            }))
            .map_err(de)?
            .label("down-weighted (weight < 1)")
            .legend(|(x, y)| Cross::new((x + 12, y), 5, BLACK.stroke_width(2)));
        chart
            .configure_series_labels()
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.5))
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(de)?;
        Ok(())
    }
}

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
        let (header, body) = root.split_vertically(CURVES_HEADER_H);
        draw_header(&header, &self.title(), &self.subtitle)?;
        draw_marker_legend(&header, &self.channels, CURVES_HEADER_H as i32 - 22)?;
        let areas = body.split_evenly((1, 3));
        let m = self.limit;
        for (k, (area, label)) in areas
            .iter()
            .take(2)
            .zip(["φ = φr − φi (deg)", "θh = (θi + θr)/2 (deg)"])
            .enumerate()
        {
            let x_of = |p: &(f64, f64, f64, usize, bool)| if k == 0 { p.0 } else { p.1 };
            let (x0, x1) = if k == 0 {
                (-180.0, 180.0)
            } else {
                range_of(self.points.iter().map(x_of), 0.03, (-90.0, 90.0))
            };
            let caption = if k == 0 {
                "residual against φ"
            } else {
                "residual against θh"
            };
            let mut chart = ChartBuilder::on(area)
                .caption(caption, (FONT, CAPTION_PX))
                .margin(10)
                .x_label_area_size(42)
                .y_label_area_size(60)
                .build_cartesian_2d(x0..x1, -m..m)
                .map_err(de)?;
            let sfmt = |v: &f64| short(*v);
            chart
                .configure_mesh()
                .x_desc(label)
                .y_desc("normalised residual")
                .x_label_formatter(&sfmt)
                .y_label_formatter(&sfmt)
                .label_style((FONT, LABEL_PX))
                .axis_desc_style((FONT, LABEL_PX))
                .light_line_style(WHITE.mix(0.0))
                .draw()
                .map_err(de)?;
            chart
                .draw_series(LineSeries::new(vec![(x0, 0.0), (x1, 0.0)], BLACK.mix(0.5)))
                .map_err(de)?;
            for (ci, (_, colour)) in self.channels.iter().enumerate() {
                let colour = *colour;
                chart
                    .draw_series(self.points.iter().filter(|p| p.3 == ci && !p.4).map(|p| {
                        Circle::new((x_of(p), p.2.clamp(-m, m)), 2, colour.mix(0.7).filled())
                    }))
                    .map_err(de)?;
                chart
                    .draw_series(self.points.iter().filter(|p| p.3 == ci && p.4).map(|p| {
                        Cross::new((x_of(p), p.2.clamp(-m, m)), 3, colour.stroke_width(1))
                    }))
                    .map_err(de)?;
            }
        }
        // Histogram with the standard normal density for reference.
        let hm = self.histogram.last().map_or(m, |b| b.1);
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
        let mut chart = ChartBuilder::on(&areas[2])
            .caption(
                "distribution of residuals (edge bins hold the tails)",
                (FONT, CAPTION_PX),
            )
            .margin(10)
            .x_label_area_size(42)
            .y_label_area_size(70)
            .build_cartesian_2d(-hm..hm, 0.0..top)
            .map_err(de)?;
        let count_fmt = |v: &f64| format!("{v:.0}");
        let sfmt = |v: &f64| short(*v);
        chart
            .configure_mesh()
            .x_label_formatter(&sfmt)
            .x_desc("normalised residual")
            .y_desc("count")
            .y_label_formatter(&count_fmt)
            .label_style((FONT, LABEL_PX))
            .axis_desc_style((FONT, LABEL_PX))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(de)?;
        chart
            .draw_series(self.histogram.iter().map(|&(a, b, c)| {
                Rectangle::new([(a, 0.0), (b, c as f64)], RGBColor(120, 130, 150).filled())
            }))
            .map_err(de)?
            .label(format!(
                "{} residuals, {} down-weighted",
                self.n_total, self.n_outliers
            ))
            .legend(|(x, y)| {
                Rectangle::new(
                    [(x, y - 5), (x + 20, y + 5)],
                    RGBColor(120, 130, 150).filled(),
                )
            });
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
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], RED.stroke_width(2)));
        chart
            .configure_series_labels()
            .label_font((FONT, 12))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.5))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(de)?;
        Ok(())
    }
}

/// Decades shown on the log radius of the polar view.
const POLAR_DECADES: f64 = 6.0;

/// One azimuthal slice in polar form: radius = value (log: decades above a floor), angle = φ.
pub struct PolarFigure {
    pub panel: SlicePanel,
    pub scale: YScale,
    pub subtitle: String,
}

impl PolarFigure {
    /// Radial range in plot coordinates (mapped values): (centre, rim).
    fn radial_range(&self) -> (f64, f64) {
        let sc = self.scale;
        let vals = self.panel.channels.iter().flat_map(|c| {
            c.points
                .iter()
                .filter_map(move |p| sc.map(p.y))
                .chain(c.total.iter().filter_map(move |&y| sc.map(y)))
        });
        match sc {
            YScale::Log => {
                // At most POLAR_DECADES decades: deeper values sit at the centre, so a few
                // near-zero samples do not shrink the lobes to a ring.
                let (lo, hi) = range_of(vals, 0.0, (-1.0, 0.0));
                let top = hi.ceil().max(lo.floor() + 1.0);
                (lo.floor().max(top - POLAR_DECADES), top)
            }
            YScale::Linear => {
                let (_, hi) = range_of(vals, 0.0, (0.0, 1.0));
                (0.0, if hi > 0.0 { hi * 1.05 } else { 1.0 })
            }
        }
    }
}

impl Figure for PolarFigure {
    fn stem(&self) -> &'static str {
        "polar"
    }
    fn title(&self) -> String {
        format!("Polar view of the {} slice", self.panel.title)
    }
    fn size(&self) -> (u32, u32) {
        (900, 960)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (header, body) = root.split_vertically(HEADER_H);
        draw_header(&header, &self.title(), &self.subtitle)?;
        let sc = self.scale;
        let (c0, c1) = self.radial_range();
        let radius = |v: f64| ((v - c0) / (c1 - c0)).clamp(0.0, 1.0);
        let at = |phi_deg: f64, r: f64| {
            let a = phi_deg.to_radians();
            (r * a.cos(), r * a.sin())
        };
        let mut chart = ChartBuilder::on(&body)
            .margin(20)
            .build_cartesian_2d(-1.25..1.25, -1.25..1.25)
            .map_err(de)?;
        // Rings with their values, spokes every 30° with φ labels.
        let grid = BLACK.mix(0.25);
        let rings: Vec<f64> = match sc {
            YScale::Log => {
                let n = (c1 - c0).round() as i64;
                let step = (n as f64 / 6.0).ceil().max(1.0) as i64;
                (0..=n)
                    .step_by(step as usize)
                    .map(|k| c0 + k as f64)
                    .collect()
            }
            YScale::Linear => (1..=4).map(|k| c1 * k as f64 / 4.0).collect(),
        };
        let label_style = (FONT, LABEL_PX).into_font().color(&BLACK.mix(0.8));
        for &ring in &rings {
            let r = radius(ring);
            let circle: Vec<(f64, f64)> = (0..=360).map(|d| at(d as f64, r)).collect();
            chart
                .draw_series(LineSeries::new(circle, grid))
                .map_err(de)?;
            if r > 0.0 {
                chart
                    .draw_series(std::iter::once(Text::new(
                        sc.label(ring, POLAR_DECADES),
                        at(97.0, r),
                        label_style.clone(),
                    )))
                    .map_err(de)?;
            }
        }
        for d in (0..360).step_by(30) {
            let d = d as f64;
            chart
                .draw_series(LineSeries::new(vec![(0.0, 0.0), at(d, 1.0)], grid))
                .map_err(de)?;
            let label = format!("φ={}°", super::slices::short(super::slices::wrap_deg(d)));
            chart
                .draw_series(std::iter::once(Text::new(
                    label,
                    at(d, 1.12),
                    label_style
                        .clone()
                        .pos(Pos::new(HPos::Center, VPos::Center)),
                )))
                .map_err(de)?;
        }
        for ch in &self.panel.channels {
            let colour = ch.color;
            let curve: Vec<(f64, f64)> = self
                .panel
                .grid
                .iter()
                .zip(&ch.total)
                .filter_map(|(&x, &y)| sc.map(y).map(|v| at(x, radius(v))))
                .collect();
            chart
                .draw_series(LineSeries::new(curve, colour.stroke_width(2)))
                .map_err(de)?
                .label(format!("fit {}", ch.name))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(ch.points.iter().filter_map(|p| {
                    let (x, y) = at(p.x, radius(sc.map(p.y)?));
                    Some(if p.outlier {
                        Circle::new((x, y), 4, BLACK.stroke_width(2))
                    } else {
                        Circle::new((x, y), 3, colour.filled())
                    })
                }))
                .map_err(de)?
                .label(format!("data {}", ch.name))
                .legend(move |(x, y)| Circle::new((x + 12, y), 3, colour.filled()));
        }
        chart
            .configure_series_labels()
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.5))
            .position(SeriesLabelPosition::LowerRight)
            .draw()
            .map_err(de)?;
        Ok(())
    }
}

/// The parameter correlation matrix as a heatmap with the value in each cell.
pub struct CorrelationFigure {
    pub names: Vec<String>,
    pub matrix: Vec<Vec<Option<f64>>>,
}

const CELL: u32 = 64;
const NAME_W: u32 = 150;

/// Diverging colour for a correlation in [−1, 1]: blue through white to red.
fn corr_color(v: f64) -> RGBColor {
    let t = v.clamp(-1.0, 1.0);
    let mix = |a: u8, b: u8, s: f64| (a as f64 + (b as f64 - a as f64) * s).round() as u8;
    if t >= 0.0 {
        RGBColor(mix(255, 200, t), mix(255, 30, t), mix(255, 30, t))
    } else {
        RGBColor(mix(255, 30, -t), mix(255, 70, -t), mix(255, 200, -t))
    }
}

impl Figure for CorrelationFigure {
    fn stem(&self) -> &'static str {
        "correlation"
    }
    fn title(&self) -> String {
        "Parameter correlation matrix".into()
    }
    fn size(&self) -> (u32, u32) {
        let n = self.names.len() as u32;
        (
            (NAME_W + n * CELL + 40).max(560),
            HEADER_H + NAME_W + n * CELL + 40,
        )
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (header, body) = root.split_vertically(HEADER_H);
        draw_header(
            &header,
            &self.title(),
            "red: positive, blue: negative; — where undefined (fixed or undetermined)",
        )?;
        let n = self.names.len();
        let x0 = NAME_W as i32;
        let y0 = NAME_W as i32;
        let cell = CELL as i32;
        let centre = Pos::new(HPos::Center, VPos::Center);
        for i in 0..n {
            for j in 0..n {
                let v = self.matrix.get(i).and_then(|r| r.get(j)).copied().flatten();
                let v = v.filter(|v| v.is_finite());
                let (px, py) = (x0 + j as i32 * cell, y0 + i as i32 * cell);
                let fill = v.map_or(RGBColor(225, 225, 225), corr_color);
                body.draw(&Rectangle::new(
                    [(px, py), (px + cell, py + cell)],
                    fill.filled(),
                ))
                .map_err(de)?;
                body.draw(&Rectangle::new(
                    [(px, py), (px + cell, py + cell)],
                    WHITE.stroke_width(1),
                ))
                .map_err(de)?;
                let text = v.map_or("—".to_string(), |v| format!("{v:.2}"));
                let colour = if v.is_some_and(|v| v.abs() > 0.6) {
                    WHITE
                } else {
                    BLACK
                };
                body.draw(&Text::new(
                    text,
                    (px + cell / 2, py + cell / 2),
                    (FONT, 15).into_font().color(&colour).pos(centre),
                ))
                .map_err(de)?;
            }
            let name = self.names[i].clone();
            body.draw(&Text::new(
                name.clone(),
                (x0 - 8, y0 + i as i32 * cell + cell / 2),
                (FONT, LABEL_PX)
                    .into_font()
                    .into_text_style(&body)
                    .pos(Pos::new(HPos::Right, VPos::Center)),
            ))
            .map_err(de)?;
            body.draw(&Text::new(
                name,
                (x0 + i as i32 * cell + cell / 2, y0 - 8),
                (FONT, LABEL_PX)
                    .into_font()
                    .transform(FontTransform::Rotate270)
                    .into_text_style(&body)
                    .pos(Pos::new(HPos::Left, VPos::Center)),
            ))
            .map_err(de)?;
        }
        Ok(())
    }
}

/// Cost against iteration for every solver stage.
pub struct ConvergenceFigure {
    /// (stage name, cost per iteration)
    pub stages: Vec<(String, Vec<f64>)>,
}

impl Figure for ConvergenceFigure {
    fn stem(&self) -> &'static str {
        "convergence"
    }
    fn title(&self) -> String {
        "Convergence: cost ½‖r‖² against iteration, per solver stage".into()
    }
    fn size(&self) -> (u32, u32) {
        (1000, 620)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (header, body) = root.split_vertically(HEADER_H);
        draw_header(
            &header,
            &self.title(),
            "iterations are numbered across stages; dotted lines mark stage boundaries",
        )?;
        let sc = YScale::Log;
        let total: usize = self.stages.iter().map(|s| s.1.len()).sum();
        let ys = self
            .stages
            .iter()
            .flat_map(|s| s.1.iter().filter_map(|&c| sc.map(c)));
        let (y0, y1) = range_of(ys, 0.05, (-1.0, 1.0));
        let x1 = (total.max(2) - 1) as f64;
        let mut chart = ChartBuilder::on(&body)
            .margin(14)
            .x_label_area_size(46)
            .y_label_area_size(80)
            .build_cartesian_2d(0.0..x1, y0..y1)
            .map_err(de)?;
        let fmt = |v: &f64| sc.label(*v, y1 - y0);
        let ifmt = |v: &f64| format!("{v:.0}");
        chart
            .configure_mesh()
            .x_desc("iteration (cumulative over stages)")
            .y_desc("cost ½‖r‖² (log scale)")
            .x_label_formatter(&ifmt)
            .y_label_formatter(&fmt)
            .y_labels(sc.ticks(y1 - y0))
            .label_style((FONT, LABEL_PX))
            .axis_desc_style((FONT, LABEL_PX + 1))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(de)?;
        let mut start = 0usize;
        for (k, (name, history)) in self.stages.iter().enumerate() {
            let colour = Palette99::pick(k).to_rgba();
            let pts: Vec<(f64, f64)> = history
                .iter()
                .enumerate()
                .filter_map(|(i, &c)| sc.map(c).map(|v| ((start + i) as f64, v)))
                .collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                .map_err(de)?
                .label(format!("{name} ({} iterations)", history.len()))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                .map_err(de)?;
            if k > 0 {
                chart
                    .draw_series(DashedLineSeries::new(
                        vec![(start as f64 - 0.5, y0), (start as f64 - 0.5, y1)],
                        2,
                        4,
                        BLACK.mix(0.5).stroke_width(1),
                    ))
                    .map_err(de)?;
            }
            start += history.len();
        }
        chart
            .configure_series_labels()
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.5))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(de)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_never_print_nan() {
        assert_eq!(fmt_num(f64::NAN), "n/a");
        assert_eq!(fmt_num(f64::INFINITY), "n/a");
        assert_eq!(fmt_num(0.0), "0");
        assert_eq!(fmt_num(1.5), "1.5");
        assert_eq!(fmt_num(123.456789), "123.5");
        assert_eq!(fmt_num(2.5e-5), "2.50e-5");
    }

    #[test]
    fn log_scale_hides_non_positive_values() {
        assert_eq!(YScale::Log.map(0.0), None);
        assert_eq!(YScale::Log.map(-1.0), None);
        assert_eq!(YScale::Log.map(100.0), Some(2.0));
        assert_eq!(YScale::Linear.map(-1.0), Some(-1.0));
        assert_eq!(YScale::Linear.map(f64::NAN), None);
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
