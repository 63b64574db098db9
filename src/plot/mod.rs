//! The plotting kit shared by the report and the cost ledger: the bundled font, text sizes, the
//! [`Figure`] trait and its SVG + PNG rendering, scales and number formats for axes, and the
//! chart set-up every figure repeats (header, framed cartesian chart, axes, series key).
//! Figures built on it only decide what to draw.

mod chart;
mod render;
mod scale;

use plotters::coord::Shift;
use plotters::prelude::{DrawingArea, DrawingBackend};

use crate::error::{Error, Result};

pub use chart::{cartesian, draw_key, header, line_glyph, Axes, Chart, Frame};
pub use render::{escape, render, FigureInfo};
pub use scale::{fmt_interval, fmt_num, fmt_tick, fmt_value_se, range_of, YScale};

/// Font family registered with the shipped DejaVu Sans (see [`render`]).
pub const FONT: &str = "sans-serif";
/// Text sizes in pixels: figure titles, panel captions, tick labels and notes.
pub const TITLE_PX: u32 = 22;
pub const CAPTION_PX: u32 = 17;
pub const LABEL_PX: u32 = 14;

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
    Error::Other(format!("drawing a figure failed: {e}"))
}
