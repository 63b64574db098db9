//! The comparison figure (compare.svg/png): per measurement slice, the normalised residual of
//! each sample (RMS over channels) of every compared family's fit, overlaid, one colour per
//! family, named in the legend by the family's title. When the families' overall RMS differ
//! more than [`LOG_WHEN`]-fold the residual axis is logarithmic, so the best fit's residuals
//! (about 1 when it fits to the noise) are not flattened by the worst one's.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::Result;
use crate::families::ModelFamily;
use crate::files::CurveRow;
use crate::plot::{cartesian, de, header, range_of, Axes, Figure, Frame, YScale, FONT};
use crate::slices::decimate::stride_indices;
use crate::slices::{collect_samples, find_slices, short};

/// Most slices drawn (evenly spread over all of them).
const MAX_PANELS: usize = 12;
/// A log residual axis when the largest overall RMS of a family is this many times the smallest.
pub const LOG_WHEN: f64 = 10.0;
/// On a log axis, residuals below this are drawn at it.
const LOG_FLOOR: f64 = 0.01;
/// Height of the key under the header, pixels.
const LEGEND_PX: u32 = 30;

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
    pub scale: YScale,
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
    // Each family's RMS over every residual, to choose the axis.
    let overall: Vec<f64> = fits
        .iter()
        .map(|(_, rows)| rms(rows, &(0..rows.len()).collect::<Vec<_>>()))
        .collect();
    let (lo, hi) = overall
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let scale = if hi > LOG_WHEN * lo.max(1e-300) {
        YScale::Log
    } else {
        YScale::Linear
    };
    OverlayFigure {
        families,
        panels,
        subtitle: format!(
            "{} of {} slices; per sample the RMS over channels of the normalised residual ({})",
            shown.len(),
            slices.len(),
            match scale {
                YScale::Log => format!("log scale: the fits differ more than {LOG_WHEN}-fold; below {LOG_FLOOR} drawn at {LOG_FLOOR}"),
                YScale::Linear => "0 = exact".into(),
            }
        ),
        scale,
    }
}

impl Figure for OverlayFigure {
    fn stem(&self) -> &'static str {
        "compare"
    }
    fn title(&self) -> String {
        let names: Vec<&str> = self.families.iter().map(|f| f.title()).collect();
        let full = format!(
            "Residuals of the {} fits, per slice",
            super::findings::and_list(&names)
        );
        // Beyond ~90 characters the 1500-pixel header cuts the title at both ends (six
        // families' titles); the key under it names each family.
        if full.chars().count() <= 90 {
            full
        } else {
            format!("Residuals of the {} families' fits, per slice", names.len())
        }
    }
    fn size(&self) -> (u32, u32) {
        let rows = self.panels.len().div_ceil(3).max(1) as u32;
        (1500, 90 + LEGEND_PX + 330 * rows)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (_, body) = header(root, 70, &self.title(), &self.subtitle)?;
        let (legend, body) = body.split_vertically(LEGEND_PX);
        self.draw_legend(&legend)?;
        if self.panels.is_empty() {
            return Ok(());
        }
        let rows = self.panels.len().div_ceil(3);
        let areas = body.split_evenly((rows, 3));
        for (panel, area) in self.panels.iter().zip(&areas) {
            let y_of = |v: f64| match self.scale {
                YScale::Log => v.max(LOG_FLOOR).log10(),
                YScale::Linear => v,
            };
            let (x0, x1) = range_of(panel.points.iter().map(|p| p.0), 0.03, (-90.0, 90.0));
            let (y0, y1) = range_of(
                panel
                    .points
                    .iter()
                    .flat_map(|p| p.1.iter().map(|&v| y_of(v))),
                0.08,
                (0.0, 1.0),
            );
            let y0 = match self.scale {
                YScale::Log => y0.min(0.0),
                YScale::Linear => 0.0,
            };
            let frame = Frame {
                caption: Some(&panel.title),
                margin: 8,
                x_label_area: 40,
                y_label_area: 60,
            };
            let y1 = y1.max(y0 + 1e-12);
            let mut chart = cartesian(area, frame, x0..x1, y0..y1)?;
            let sfmt = |v: &f64| short(*v);
            let yfmt = |v: &f64| self.scale.label(*v, y1 - y0);
            let y_desc = format!("|residual|{}", self.scale.suffix());
            let y_ticks = match self.scale {
                YScale::Log => self.scale.ticks(y1 - y0),
                YScale::Linear => 5,
            };
            Axes::new(panel.x_label.as_str(), y_desc, &sfmt, &yfmt)
                .ticks(7, y_ticks)
                .draw(&mut chart)?;
            for i in 0..self.families.len() {
                let c = colour(i);
                let line: Vec<(f64, f64)> =
                    panel.points.iter().map(|p| (p.0, y_of(p.1[i]))).collect();
                chart
                    .draw_series(LineSeries::new(line.clone(), c.stroke_width(2)))
                    .map_err(de)?;
                chart
                    .draw_series(
                        line.iter()
                            .map(|&(x, y)| Circle::new((x, y), 2, c.filled())),
                    )
                    .map_err(de)?;
            }
        }
        Ok(())
    }
}

impl OverlayFigure {
    /// One key for every panel, centred under the header: a line of each family's colour and
    /// its title (a key inside each panel hid the data in its corner).
    fn draw_legend<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()> {
        const SWATCH: i32 = 28;
        const GAP: i32 = 36;
        let style = TextStyle::from((FONT, 15).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
        let widths: Vec<i32> = self
            .families
            .iter()
            .map(|f| {
                let (w, _) = area
                    .estimate_text_size(f.title(), &style)
                    .unwrap_or((120, 0));
                SWATCH + 8 + w as i32
            })
            .collect();
        let total = widths.iter().sum::<i32>() + GAP * (widths.len() as i32 - 1).max(0);
        let (w, h) = area.dim_in_pixel();
        let (mut x, y) = ((w as i32 - total) / 2, h as i32 / 2);
        for ((i, family), width) in self.families.iter().enumerate().zip(&widths) {
            let c = colour(i);
            area.draw(&PathElement::new(
                vec![(x, y), (x + SWATCH, y)],
                c.stroke_width(3),
            ))
            .map_err(de)?;
            area.draw(&Circle::new((x + SWATCH / 2, y), 3, c.filled()))
                .map_err(de)?;
            area.draw(&Text::new(
                family.title().to_string(),
                (x + SWATCH + 8, y),
                style.clone(),
            ))
            .map_err(de)?;
            x += width + GAP;
        }
        Ok(())
    }
}
