//! The report's figures, one file each, drawn with the plotting kit ([`crate::plot`]) onto any
//! backend (the same code writes SVG and PNG): per-slice curves, data against fit, residuals, a
//! polar view, the correlation heatmap, the profile likelihoods and the convergence trace. This module owns what they
//! share: the drawn form of a slice ([`SlicePanel`] and its parts), channel colours and the
//! header heights. Figures receive prepared, already decimated data; they only draw.

mod convergence;
mod correlation;
mod curves;
mod data_vs_fit;
mod polar;
mod profile;
mod residuals;

use plotters::style::RGBColor;

pub use convergence::ConvergenceFigure;
pub use correlation::CorrelationFigure;
pub use curves::CurvesFigure;
pub use curves::LOG_FLOOR_NOTE;
pub use data_vs_fit::DataVsFitFigure;
pub use polar::PolarFigure;
pub use profile::{ProfileFigure, ProfilePanel};
pub use residuals::ResidualsFigure;

/// Height of a figure's header (title and explanation).
const HEADER_H: u32 = 70;
/// Height of a header that also holds a legend row.
const LEGEND_HEADER_H: u32 = 100;

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

/// A measured point as drawn.
#[derive(Debug, Clone, Copy)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    pub sigma: Option<f64>,
    /// Robust-loss weight below `files::DOWN_WEIGHT`: marked as down-weighted.
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
