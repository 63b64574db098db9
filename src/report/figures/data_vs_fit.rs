//! The data-against-fit figure: every sample's measured value against its fitted value, with
//! the identity line; the only view of scattered data.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::HEADER_H;
use crate::error::Result;
use crate::plot::{
    cartesian, de, draw_key, header, line_glyph, range_of, Axes, Figure, Frame, YScale, LABEL_PX,
};

/// Measured value against fitted value, one point per (decimated) sample.
pub struct DataVsFitFigure {
    /// (fit, data, channel index, outlier)
    pub points: Vec<(f64, f64, usize, bool)>,
    pub channels: Vec<(String, RGBColor)>,
    pub scale: YScale,
    pub subtitle: String,
}

impl Figure for DataVsFitFigure {
    fn stem(&self) -> &'static str {
        "data_vs_fit"
    }
    fn title(&self) -> String {
        "Measured value against fitted value, every sample (identity line = perfect fit)".into()
    }
    fn size(&self) -> (u32, u32) {
        (900, 820)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (_, body) = header(root, HEADER_H, &self.title(), &self.subtitle)?;
        let sc = self.scale;
        let all = self
            .points
            .iter()
            .flat_map(|p| [sc.map(p.0), sc.map(p.1)])
            .flatten();
        let (lo, hi) = range_of(all, 0.05, (0.0, 1.0));
        let frame = Frame {
            caption: None,
            margin: 12,
            x_label_area: 46,
            y_label_area: 80,
        };
        let mut chart = cartesian(&body, frame, lo..hi, lo..hi)?;
        let fmt = |v: &f64| sc.label(*v, hi - lo);
        Axes::new(
            format!("fitted value (arb. units{})", sc.suffix()),
            format!("measured value (arb. units{})", sc.suffix()),
            &fmt,
            &fmt,
        )
        .ticks(sc.ticks(hi - lo), sc.ticks(hi - lo))
        .text_px(LABEL_PX, LABEL_PX + 1)
        .draw(&mut chart)?;
        chart
            .draw_series(LineSeries::new(
                vec![(lo, lo), (hi, hi)],
                BLACK.mix(0.6).stroke_width(1),
            ))
            .map_err(de)?
            .label("identity")
            .legend(line_glyph(BLACK.mix(0.6)));
        for (ci, (name, colour)) in self.channels.iter().enumerate() {
            let colour = *colour;
            chart
                .draw_series(
                    self.points
                        .iter()
                        .filter(|p| p.2 == ci && !p.3)
                        .filter_map(|p| {
                            Some(Circle::new(
                                (sc.map(p.0)?, sc.map(p.1)?),
                                2,
                                colour.mix(0.7).filled(),
                            ))
                        }),
                )
                .map_err(de)?
                .label(format!("data {name}"))
                .legend(move |(x, y)| Circle::new((x + 12, y), 3, colour.filled()));
        }
        chart
            .draw_series(self.points.iter().filter(|p| p.3).filter_map(|p| {
                Some(Cross::new(
                    (sc.map(p.0)?, sc.map(p.1)?),
                    4,
                    BLACK.stroke_width(2),
                ))
            }))
            .map_err(de)?
            .label("down-weighted (weight < 0.5)")
            .legend(|(x, y)| Cross::new((x + 12, y), 5, BLACK.stroke_width(2)));
        draw_key(&mut chart, SeriesLabelPosition::UpperLeft, 13)
    }
}
