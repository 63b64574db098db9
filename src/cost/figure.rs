//! The ledger's figure (cost.svg/png): RMS error against time per section on log–log axes, the
//! Pareto front joined and highlighted, points numbered and named in a key below each plot.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{CostRow, ERROR_FLOOR};
use crate::error::Result;
use crate::plot::{cartesian, de, fmt_num, header, Axes, Figure, Frame, YScale, FONT};

/// Error against time per section, log–log, Pareto front joined and highlighted.
pub(super) struct CostFigure {
    pub rows: Vec<CostRow>,
    pub quick: bool,
}

/// (section, caption, x-axis description) of each plot, left to right.
/// Only the sections present in the ledger are drawn (`--model chiang` has its own two).
const SECTIONS: [(&str, &str, &str); 5] = [
    (
        "model",
        "Model: roots × effects",
        "time per evaluation (s, log)",
    ),
    (
        "jacobian",
        "Jacobian: AD vs central differences",
        "time per Jacobian (s, log)",
    ),
    (
        "fit",
        "Fit: stages, starts, samples",
        "fit wall time (s, log)",
    ),
    (
        "chiang-b0.3",
        "Chiang width nodes, beta_m = beta_n = 0.3",
        "time per sample (s, log)",
    ),
    (
        "chiang-b0.05",
        "Chiang width nodes, beta_m = beta_n = 0.05",
        "time per sample (s, log)",
    ),
];

impl Figure for CostFigure {
    fn stem(&self) -> &'static str {
        "cost"
    }
    fn title(&self) -> String {
        "Accuracy against time for each knob (Pareto front in red)".into()
    }
    fn size(&self) -> (u32, u32) {
        (1800, 900)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let sub = format!(
            "RMS error (log) against time (log); filled red: Pareto-optimal, grey: dominated; errors below {ERROR_FLOOR:e} drawn at it (the reference){}",
            if self.quick { "; --quick run" } else { "" }
        );
        let (_, body) = header(root, 70, &self.title(), &sub)?;
        let present: Vec<_> = SECTIONS
            .iter()
            .filter(|(section, _, _)| self.rows.iter().any(|r| r.section == *section))
            .collect();
        let areas = body.split_evenly((1, present.len().max(1)));
        for ((section, caption, x_desc), area) in present.into_iter().zip(areas.iter()) {
            let rows: Vec<&CostRow> = self.rows.iter().filter(|r| r.section == *section).collect();
            draw_section(area, &rows, caption, x_desc)?;
        }
        Ok(())
    }
}

/// A log range around every value, padded by 15 % of the span (at least 0.3 decades).
fn log_span(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
        (lo.min(x), hi.max(x))
    });
    if !lo.is_finite() {
        (-1.0, 1.0)
    } else {
        let pad = ((hi - lo) * 0.15).max(0.3);
        (lo - pad, hi + pad)
    }
}

fn draw_section<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    rows: &[&CostRow],
    caption: &str,
    x_desc: &str,
) -> Result<()> {
    let lx = |r: &CostRow| r.time_s.max(1e-12).log10();
    let ly = |r: &CostRow| r.error_rms.max(ERROR_FLOOR).log10();
    let (x0, x1) = log_span(rows.iter().map(|r| lx(r)));
    let (y0, y1) = log_span(rows.iter().map(|r| ly(r)));
    let (plot, key) = area.split_vertically(600);
    let frame = Frame {
        caption: Some(caption),
        margin: 14,
        x_label_area: 44,
        y_label_area: 70,
    };
    let mut chart = cartesian(&plot, frame, x0..x1, y0..y1)?;
    let log = YScale::Log;
    let x_fmt = |v: &f64| log.label(*v, x1 - x0);
    let y_fmt = |v: &f64| log.label(*v, y1 - y0);
    Axes::new(x_desc, "RMS error (log)", &x_fmt, &y_fmt)
        .ticks(log.ticks(x1 - x0), log.ticks(y1 - y0))
        .text_px(13, 14)
        .draw(&mut chart)?;
    let mut front: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.pareto)
        .map(|r| (lx(r), ly(r)))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(front, RED.mix(0.6).stroke_width(2)))
        .map_err(de)?;
    // Points carry a number; the key below the plot names them (labels would overlap).
    let key_style = (FONT, 13).into_font().into_text_style(&key);
    for (k, r) in rows.iter().enumerate() {
        let p = (lx(r), ly(r));
        let colour = if r.pareto {
            RED.to_rgba()
        } else {
            RGBColor(120, 120, 120).to_rgba()
        };
        let marker = if r.pareto {
            Circle::new(p, 5, colour.filled())
        } else {
            Circle::new(p, 5, colour.stroke_width(2))
        };
        chart.draw_series(std::iter::once(marker)).map_err(de)?;
        chart
            .draw_series(std::iter::once(Text::new(
                format!("{}", k + 1),
                p,
                (FONT, 13)
                    .into_font()
                    .color(&colour)
                    .pos(Pos::new(HPos::Left, VPos::Bottom)),
            )))
            .map_err(de)?;
        let line = format!(
            "{}{}. {}: {} s, RMS error {}",
            if r.pareto { "★ " } else { "" },
            k + 1,
            r.setting,
            fmt_num(r.time_s),
            fmt_num(r.error_rms)
        );
        key.draw(&Text::new(line, (20, 4 + 18 * k as i32), key_style.clone()))
            .map_err(de)?;
    }
    Ok(())
}
