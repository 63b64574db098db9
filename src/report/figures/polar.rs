//! The polar figure: one azimuthal slice with radius = value (log: decades above a floor) and
//! angle = φ, rings and spokes labelled, data points over the fitted curve per channel.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{SlicePanel, HEADER_H};
use crate::error::Result;
use crate::plot::{
    cartesian, de, draw_key, header, line_glyph, range_of, Figure, Frame, YScale, FONT, LABEL_PX,
};
use crate::slices::{short, wrap_deg};

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

    /// The values (plot coordinates) of the labelled rings between centre `c0` and rim `c1`.
    fn rings(&self, c0: f64, c1: f64) -> Vec<f64> {
        match self.scale {
            YScale::Log => {
                let n = (c1 - c0).round() as i64;
                let step = (n as f64 / 6.0).ceil().max(1.0) as i64;
                (0..=n)
                    .step_by(step as usize)
                    .map(|k| c0 + k as f64)
                    .collect()
            }
            YScale::Linear => (1..=4).map(|k| c1 * k as f64 / 4.0).collect(),
        }
    }
}

/// The point at angle `phi_deg` and radius `r` (1 = rim).
fn at(phi_deg: f64, r: f64) -> (f64, f64) {
    let a = phi_deg.to_radians();
    (r * a.cos(), r * a.sin())
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
        let (_, body) = header(root, HEADER_H, &self.title(), &self.subtitle)?;
        let sc = self.scale;
        let (c0, c1) = self.radial_range();
        let radius = |v: f64| ((v - c0) / (c1 - c0)).clamp(0.0, 1.0);
        let frame = Frame {
            caption: None,
            margin: 20,
            x_label_area: 0,
            y_label_area: 0,
        };
        let mut chart = cartesian(&body, frame, -1.25..1.25, -1.25..1.25)?;
        // Rings with their values, spokes every 30° with φ labels.
        let grid = BLACK.mix(0.25);
        let label_style = (FONT, LABEL_PX).into_font().color(&BLACK.mix(0.8));
        for ring in self.rings(c0, c1) {
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
            chart
                .draw_series(std::iter::once(Text::new(
                    format!("φ={}°", short(wrap_deg(d))),
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
                .legend(line_glyph(colour.stroke_width(2)));
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
        draw_key(&mut chart, SeriesLabelPosition::LowerRight, 13)
    }
}
