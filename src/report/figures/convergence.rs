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
    /// (stage name, iterations the stage table counts, cost per iteration of its winning run)
    pub stages: Vec<(String, u64, Vec<f64>)>,
}

/// The legend entry of one stage: its drawn iterations, and the stage table's total when that
/// counts more (a multistart's count sums every start; only the winner's costs are drawn).
pub fn stage_label(name: &str, drawn: usize, total: u64) -> String {
    let plural = |n: u64| if n == 1 { "iteration" } else { "iterations" };
    if total > drawn as u64 {
        format!(
            "{name} (best start: {drawn} {} of {total} in all)",
            plural(drawn as u64)
        )
    } else {
        format!("{name} ({drawn} {})", plural(drawn as u64))
    }
}

/// An iteration axis label: integers only (a tick between two iterations stays unlabelled,
/// so a short run never reads "0 0 1 2 2").
pub fn iteration_label(v: f64) -> String {
    if (v - v.round()).abs() < 1e-9 {
        format!("{:.0}", v.round().abs())
    } else {
        String::new()
    }
}

/// How many x ticks to ask for: one per iteration on a short run, at most 11.
pub fn iteration_ticks(last: f64) -> usize {
    (last.max(1.0) as usize + 1).min(11)
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
        let total: usize = self.stages.iter().map(|s| s.2.len()).sum();
        let ys = self
            .stages
            .iter()
            .flat_map(|s| s.2.iter().filter_map(|&c| sc.map(c)));
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
        let ifmt = |v: &f64| iteration_label(*v);
        Axes::new(
            "iteration (cumulative over stages)",
            "cost ½‖r‖² (log scale)",
            &ifmt,
            &fmt,
        )
        .ticks(iteration_ticks(x1), sc.ticks(y1 - y0))
        .text_px(LABEL_PX, LABEL_PX + 1)
        .draw(&mut chart)?;
        let mut start = 0usize;
        for (k, (name, iterations, history)) in self.stages.iter().enumerate() {
            let colour = Palette99::pick(k).to_rgba();
            let pts: Vec<(f64, f64)> = history
                .iter()
                .enumerate()
                .filter_map(|(i, &c)| sc.map(c).map(|v| ((start + i) as f64, v)))
                .collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                .map_err(de)?
                .label(stage_label(name, history.len(), *iterations))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legend_counts_agree_with_the_stage_table() {
        // fits/demo: the multistart's table row says 73 (all starts), its winner drew 5.
        assert_eq!(
            stage_label("multistart", 5, 73),
            "multistart (best start: 5 iterations of 73 in all)"
        );
        assert_eq!(stage_label("polish", 1, 1), "polish (1 iteration)");
        assert_eq!(stage_label("polish", 23, 23), "polish (23 iterations)");
    }

    #[test]
    fn iteration_ticks_are_distinct_integers() {
        assert_eq!(iteration_label(3.0), "3");
        assert_eq!(iteration_label(0.0), "0");
        assert_eq!(iteration_label(2.5), "");
        assert_eq!(iteration_label(-0.0), "0");
        // Six iterations (0..=5): six ticks, one per iteration; long runs stay at 11.
        assert_eq!(iteration_ticks(5.0), 6);
        assert_eq!(iteration_ticks(1.0), 2);
        assert_eq!(iteration_ticks(700.0), 11);
    }
}
