//! The comparison figure (compare.svg/png): per measurement slice, the normalised residual of
//! each sample (RMS over channels) of every compared family's fit, overlaid, one colour per
//! family, named in the legend by the family's title.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::Result;
use crate::family::ModelFamily;
use crate::files::CurveRow;
use crate::plot::{cartesian, de, draw_key, header, line_glyph, range_of, Axes, Figure, Frame};
use crate::slices::decimate::stride_indices;
use crate::slices::{collect_samples, find_slices, short};

/// Most slices drawn (evenly spread over all of them).
const MAX_PANELS: usize = 12;

/// One colour per family, in the order compared (repeated past the last).
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
];

/// The colour of the `i`-th family compared.
pub fn colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// One slice: its title, x label, and per sample its x and each family's residual.
pub struct OverlayPanel {
    pub title: String,
    pub x_label: String,
    pub points: Vec<(f64, Vec<f64>)>,
}

/// The residuals of every family's fit, overlaid per slice.
pub struct OverlayFigure {
    pub families: Vec<ModelFamily>,
    pub panels: Vec<OverlayPanel>,
    pub subtitle: String,
}

/// The figure of several fits' curves of the same samples (same order), one per family.
pub fn overlay(fits: &[(ModelFamily, Vec<CurveRow>)]) -> OverlayFigure {
    let families = fits.iter().map(|f| f.0).collect();
    let samples = collect_samples(fits.first().map_or(&[][..], |f| &f.1));
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
                            fits.iter()
                                .map(|(_, rows)| rms(rows, &sample.rows))
                                .collect(),
                        )
                    })
                    .collect(),
            }
        })
        .collect();
    OverlayFigure {
        families,
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
        let names: Vec<&str> = self.families.iter().map(|f| f.title()).collect();
        format!(
            "Residuals of the {} fits, per slice",
            super::findings::and_list(&names)
        )
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
                panel.points.iter().flat_map(|p| p.1.iter().copied()),
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
            for (i, family) in self.families.iter().enumerate() {
                let c = colour(i);
                let line: Vec<(f64, f64)> = panel.points.iter().map(|p| (p.0, p.1[i])).collect();
                chart
                    .draw_series(LineSeries::new(line.clone(), c.stroke_width(2)))
                    .map_err(de)?
                    .label(family.title())
                    .legend(line_glyph(c.stroke_width(2)));
                chart
                    .draw_series(
                        line.iter()
                            .map(|&(x, y)| Circle::new((x, y), 2, c.filled())),
                    )
                    .map_err(de)?;
            }
            draw_key(&mut chart, SeriesLabelPosition::UpperRight, 12)?;
        }
        Ok(())
    }
}
