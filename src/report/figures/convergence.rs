//! The convergence figure: cost ½‖r‖² against iteration on a log axis, one line per solver
//! stage, iterations numbered across stages with dotted lines at the stage boundaries.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::HEADER_H;
use crate::error::Result;
use crate::plot::{
    cartesian, de, draw_key, header, line_glyph, range_of, Axes, Figure, Frame, YScale, LABEL_PX,
};

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
        let (_, body) = header(
            root,
            HEADER_H,
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
        let frame = Frame {
            caption: None,
            margin: 14,
            x_label_area: 46,
            y_label_area: 80,
        };
        let mut chart = cartesian(&body, frame, 0.0..x1, y0..y1)?;
        let fmt = |v: &f64| sc.label(*v, y1 - y0);
        let ifmt = |v: &f64| format!("{v:.0}");
        Axes::new(
            "iteration (cumulative over stages)",
            "cost ½‖r‖² (log scale)",
            &ifmt,
            &fmt,
        )
        .ticks(11, sc.ticks(y1 - y0))
        .text_px(LABEL_PX, LABEL_PX + 1)
        .draw(&mut chart)?;
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
                .legend(line_glyph(colour.stroke_width(2)));
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
        draw_key(&mut chart, SeriesLabelPosition::UpperRight, 13)
    }
}
