//! The comparison figure (compare.svg/png): per measurement slice, the normalised residual of
//! each sample (RMS over channels) of the Marschner fit and of the Chiang fit, overlaid.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::Result;
use crate::files::CurveRow;
use crate::plot::{cartesian, de, draw_key, header, line_glyph, range_of, Axes, Figure, Frame};
use crate::slices::decimate::stride_indices;
use crate::slices::{collect_samples, find_slices, short};

/// Most slices drawn (evenly spread over all of them).
const MAX_PANELS: usize = 12;
const MARSCHNER: RGBColor = RGBColor(31, 119, 180);
const CHIANG: RGBColor = RGBColor(214, 39, 40);

/// One slice: its title, x label, and (x, residual Marschner, residual Chiang) per sample.
pub struct OverlayPanel {
    pub title: String,
    pub x_label: String,
    pub points: Vec<(f64, f64, f64)>,
}

/// The residuals of both fits, overlaid per slice.
pub struct OverlayFigure {
    pub panels: Vec<OverlayPanel>,
    pub subtitle: String,
}

/// The figure of two fits' curves of the same samples (same order).
pub fn overlay(marschner: &[CurveRow], chiang: &[CurveRow]) -> OverlayFigure {
    let samples = collect_samples(marschner);
    let (slices, _) = find_slices(&samples);
    let rms = |rows: &[CurveRow], idx: &[usize]| {
        let v: Vec<f64> = idx
            .iter()
            .map(|&r| rows[r].residual)
            .filter(|r| r.is_finite())
            .collect();
        (v.iter().map(|r| r * r).sum::<f64>() / v.len().max(1) as f64).sqrt()
    };
    let shown = stride_indices(slices.len(), MAX_PANELS);
    let panels = shown
        .iter()
        .map(|&i| {
            let s = &slices[i];
            OverlayPanel {
                title: s.title(),
                x_label: s.x_label().into(),
                points: s
                    .samples
                    .iter()
                    .map(|&k| {
                        let sample = &samples[k];
                        (
                            s.x_of(&sample.angles),
                            rms(marschner, &sample.rows),
                            rms(chiang, &sample.rows),
                        )
                    })
                    .collect(),
            }
        })
        .collect();
    OverlayFigure {
        panels,
        subtitle: format!(
            "{} of {} slices; per sample the RMS over channels of the normalised residual (0 = exact)",
            shown.len(),
            slices.len()
        ),
    }
}

impl Figure for OverlayFigure {
    fn stem(&self) -> &'static str {
        "compare"
    }
    fn title(&self) -> String {
        "Residuals of the Marschner and Chiang fits, per slice".into()
    }
    fn size(&self) -> (u32, u32) {
        let rows = self.panels.len().div_ceil(3).max(1) as u32;
        (1500, 90 + 330 * rows)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (_, body) = header(root, 70, &self.title(), &self.subtitle)?;
        if self.panels.is_empty() {
            return Ok(());
        }
        let rows = self.panels.len().div_ceil(3);
        let areas = body.split_evenly((rows, 3));
        for (panel, area) in self.panels.iter().zip(&areas) {
            let (x0, x1) = range_of(panel.points.iter().map(|p| p.0), 0.03, (-90.0, 90.0));
            let (_, y1) = range_of(
                panel.points.iter().flat_map(|p| [p.1, p.2]),
                0.08,
                (0.0, 1.0),
            );
            let frame = Frame {
                caption: Some(&panel.title),
                margin: 8,
                x_label_area: 40,
                y_label_area: 60,
            };
            let mut chart = cartesian(area, frame, x0..x1, 0.0..y1.max(1e-12))?;
            let sfmt = |v: &f64| short(*v);
            let yfmt = |v: &f64| crate::plot::fmt_num(*v);
            Axes::new(panel.x_label.as_str(), "|residual|", &sfmt, &yfmt)
                .ticks(7, 5)
                .draw(&mut chart)?;
            for (colour, name, pick) in
                [(MARSCHNER, "Marschner", 1usize), (CHIANG, "Chiang", 2usize)]
            {
                let line: Vec<(f64, f64)> = panel
                    .points
                    .iter()
                    .map(|p| (p.0, if pick == 1 { p.1 } else { p.2 }))
                    .collect();
                chart
                    .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))
                    .map_err(de)?
                    .label(name)
                    .legend(line_glyph(colour.stroke_width(2)));
                chart
                    .draw_series(
                        line.iter()
                            .map(|&(x, y)| Circle::new((x, y), 2, colour.filled())),
                    )
                    .map_err(de)?;
            }
            draw_key(&mut chart, SeriesLabelPosition::UpperRight, 12)?;
        }
        Ok(())
    }
}
