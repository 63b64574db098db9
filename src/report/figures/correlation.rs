//! The correlation figure: the parameter correlation matrix as a heatmap (blue through white to
//! red) with the value in each cell and the parameter names along both edges.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::HEADER_H;
use crate::error::Result;
use crate::plot::{de, header, Figure, FONT, LABEL_PX};

/// The parameter correlation matrix as a heatmap with the value in each cell.
pub struct CorrelationFigure {
    pub names: Vec<String>,
    pub matrix: Vec<Vec<Option<f64>>>,
}

const CELL: u32 = 64;
const NAME_W: u32 = 150;

/// Diverging colour for a correlation in [−1, 1]: blue through white to red.
fn corr_color(v: f64) -> RGBColor {
    let t = v.clamp(-1.0, 1.0);
    let mix = |a: u8, b: u8, s: f64| (a as f64 + (b as f64 - a as f64) * s).round() as u8;
    if t >= 0.0 {
        RGBColor(mix(255, 200, t), mix(255, 30, t), mix(255, 30, t))
    } else {
        RGBColor(mix(255, 30, -t), mix(255, 70, -t), mix(255, 200, -t))
    }
}

impl Figure for CorrelationFigure {
    fn stem(&self) -> &'static str {
        "correlation"
    }
    fn title(&self) -> String {
        "Parameter correlation matrix".into()
    }
    fn size(&self) -> (u32, u32) {
        let n = self.names.len() as u32;
        (
            (NAME_W + n * CELL + 40).max(560),
            HEADER_H + NAME_W + n * CELL + 40,
        )
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (_, body) = header(
            root,
            HEADER_H,
            &self.title(),
            "red: positive, blue: negative; — where undefined (fixed or undetermined)",
        )?;
        let n = self.names.len();
        let x0 = NAME_W as i32;
        let y0 = NAME_W as i32;
        let cell = CELL as i32;
        let centre = Pos::new(HPos::Center, VPos::Center);
        for i in 0..n {
            for j in 0..n {
                let v = self.matrix.get(i).and_then(|r| r.get(j)).copied().flatten();
                let v = v.filter(|v| v.is_finite());
                let (px, py) = (x0 + j as i32 * cell, y0 + i as i32 * cell);
                let fill = v.map_or(RGBColor(225, 225, 225), corr_color);
                body.draw(&Rectangle::new(
                    [(px, py), (px + cell, py + cell)],
                    fill.filled(),
                ))
                .map_err(de)?;
                body.draw(&Rectangle::new(
                    [(px, py), (px + cell, py + cell)],
                    WHITE.stroke_width(1),
                ))
                .map_err(de)?;
                let text = v.map_or("—".to_string(), |v| format!("{v:.2}"));
                let colour = if v.is_some_and(|v| v.abs() > 0.6) {
                    WHITE
                } else {
                    BLACK
                };
                body.draw(&Text::new(
                    text,
                    (px + cell / 2, py + cell / 2),
                    (FONT, 15).into_font().color(&colour).pos(centre),
                ))
                .map_err(de)?;
            }
            let name = self.names[i].clone();
            body.draw(&Text::new(
                name.clone(),
                (x0 - 8, y0 + i as i32 * cell + cell / 2),
                (FONT, LABEL_PX)
                    .into_font()
                    .into_text_style(&body)
                    .pos(Pos::new(HPos::Right, VPos::Center)),
            ))
            .map_err(de)?;
            body.draw(&Text::new(
                name,
                (x0 + i as i32 * cell + cell / 2, y0 - 8),
                (FONT, LABEL_PX)
                    .into_font()
                    .transform(FontTransform::Rotate270)
                    .into_text_style(&body)
                    .pos(Pos::new(HPos::Left, VPos::Center)),
            ))
            .map_err(de)?;
        }
        Ok(())
    }
}
