//! The chart set-up every figure repeats: a header with title and explanation, a framed
//! cartesian chart of f64 × f64, its axes (descriptions, tick formatters and counts, no light
//! grid), the boxed series key and the line glyph of a key entry.

use std::ops::Range;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{de, CAPTION_PX, FONT, LABEL_PX, TITLE_PX};
use crate::error::Result;

/// A cartesian chart with f64 coordinates on both axes.
pub type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Split a header of `height` pixels off `root` and write the figure's title (bold) and a line
/// of explanation into it: (header, body). The header keeps room below for a legend row.
pub fn header<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    height: u32,
    title: &str,
    explanation: &str,
) -> Result<(DrawingArea<DB, Shift>, DrawingArea<DB, Shift>)> {
    let (header, body) = root.split_vertically(height);
    let (w, _) = header.dim_in_pixel();
    let centre = Pos::new(HPos::Center, VPos::Top);
    let line = |text: &str, y: i32, font: FontDesc<'static>| {
        Text::new(
            text.to_string(),
            (w as i32 / 2, y),
            TextStyle::from(font).pos(centre),
        )
    };
    let bold = (FONT, TITLE_PX).into_font().style(FontStyle::Bold);
    header.draw(&line(title, 8, bold)).map_err(de)?;
    let plain = (FONT, LABEL_PX).into_font();
    header.draw(&line(explanation, 40, plain)).map_err(de)?;
    Ok((header, body))
}

/// How a chart sits in its area: an optional caption above, the margin around it and the room
/// for tick labels below (x) and to the left (y), in pixels.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    pub caption: Option<&'a str>,
    pub margin: u32,
    pub x_label_area: u32,
    pub y_label_area: u32,
}

/// A chart spanning `x` × `y` in `area`, framed as `frame` says.
pub fn cartesian<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    frame: Frame,
    x: Range<f64>,
    y: Range<f64>,
) -> Result<Chart<'a, DB>> {
    let mut builder = ChartBuilder::on(area);
    if let Some(caption) = frame.caption {
        builder.caption(caption, (FONT, CAPTION_PX));
    }
    builder
        .margin(frame.margin)
        .x_label_area_size(frame.x_label_area)
        .y_label_area_size(frame.y_label_area)
        .build_cartesian_2d(x, y)
        .map_err(de)
}

/// A tick-label formatter.
pub type Formatter<'f> = &'f dyn Fn(&f64) -> String;

/// The axes of a chart: descriptions, tick formatters, how many ticks to ask for and the text
/// sizes of tick labels and descriptions. Drawn without the light grid.
pub struct Axes<'f> {
    x_desc: String,
    y_desc: String,
    x_fmt: Formatter<'f>,
    y_fmt: Formatter<'f>,
    ticks: (usize, usize),
    text_px: (u32, u32),
}

impl<'f> Axes<'f> {
    /// Axes with plotters' default tick count (11) and [`LABEL_PX`] text.
    pub fn new(
        x_desc: impl Into<String>,
        y_desc: impl Into<String>,
        x_fmt: Formatter<'f>,
        y_fmt: Formatter<'f>,
    ) -> Self {
        Axes {
            x_desc: x_desc.into(),
            y_desc: y_desc.into(),
            x_fmt,
            y_fmt,
            ticks: (11, 11),
            text_px: (LABEL_PX, LABEL_PX),
        }
    }

    /// Ask for `x` and `y` tick positions.
    pub fn ticks(mut self, x: usize, y: usize) -> Self {
        self.ticks = (x, y);
        self
    }

    /// Tick labels of `labels` pixels, axis descriptions of `descriptions` pixels.
    pub fn text_px(mut self, labels: u32, descriptions: u32) -> Self {
        self.text_px = (labels, descriptions);
        self
    }

    /// Draw the axes, tick labels and descriptions of `chart`.
    pub fn draw<DB: DrawingBackend>(&self, chart: &mut Chart<DB>) -> Result<()> {
        chart
            .configure_mesh()
            .x_desc(self.x_desc.as_str())
            .y_desc(self.y_desc.as_str())
            .x_label_formatter(self.x_fmt)
            .y_label_formatter(self.y_fmt)
            .x_labels(self.ticks.0)
            .y_labels(self.ticks.1)
            .label_style((FONT, self.text_px.0))
            .axis_desc_style((FONT, self.text_px.1))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(de)
    }
}

/// The key of the labelled series of `chart`, boxed, at `position`, in `px`-pixel text.
pub fn draw_key<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    position: SeriesLabelPosition,
    px: u32,
) -> Result<()> {
    chart
        .configure_series_labels()
        .label_font((FONT, px))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.5))
        .position(position)
        .draw()
        .map_err(de)
}

/// The glyph of a line series in a key: a 24-pixel stroke.
pub fn line_glyph(style: impl Into<ShapeStyle>) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    let style = style.into();
    move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style)
}
