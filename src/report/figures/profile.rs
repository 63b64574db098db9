//! The profile-likelihood figure: one panel per profiled parameter, Δχ² against the pinned
//! value (re-minimised over the others), with the 68% and 95% thresholds (Δχ² = 1, 3.84) and the
//! linearised parabola `((v − v̂)/SE)²` that the standard error stands for. Where the two
//! differ, the profile interval is the honest one.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::HEADER_H;
use crate::error::Result;
use crate::plot::{cartesian, de, fmt_tick, header, Axes, Figure, Frame, LABEL_PX};

/// Δχ² of the two thresholds drawn.
const LEVELS: [f64; 2] = [1.0, crate::fit::profile::CHI2_95];
/// The vertical axis ends here (a profile rising far beyond the 95% level adds nothing).
const Y_MAX: f64 = 6.0;
/// A little room below 0 shows a profile point that found a lower cost than the fit.
const Y_MIN: f64 = -0.3;

/// One parameter's profile as drawn (reporting units).
#[derive(Debug, Clone)]
pub struct ProfilePanel {
    /// Name with unit, e.g. `w_c_deg (deg)`.
    pub title: String,
    pub value: f64,
    /// Linearised standard error, when there is one.
    pub std_error: Option<f64>,
    /// `(value, Δχ²)` ascending in value.
    pub points: Vec<(f64, f64)>,
    /// `[below, above]`: the 95% end a side took from the local quadratic through its one
    /// solved point (fit.json `profile_method` `extrapolated`), drawn dashed up to that end.
    pub quadratic_ends: [Option<f64>; 2],
}

/// Every profiled parameter, in fit.json's order.
pub struct ProfileFigure {
    pub panels: Vec<ProfilePanel>,
}

impl ProfileFigure {
    fn grid(&self) -> (usize, usize) {
        let n = self.panels.len().max(1);
        let cols = n.min(3);
        (cols, n.div_ceil(cols))
    }
}

impl Figure for ProfileFigure {
    fn stem(&self) -> &'static str {
        "profiles"
    }
    fn title(&self) -> String {
        "Profile likelihood: Δχ² against each parameter, the others re-fitted".into()
    }
    fn size(&self) -> (u32, u32) {
        let (cols, rows) = self.grid();
        (420 * cols as u32 + 40, HEADER_H + 330 * rows as u32)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (_, body) = header(
            root,
            HEADER_H,
            &self.title(),
            "blue: profile (dots: solved points, joined by a curve exact for a quadratic profile; dashed to a ring: the local quadratic's 95% end); grey: Δχ² = 1 (68%), 3.84 (95%); orange: the linearised SE's parabola",
        )?;
        let (cols, rows) = self.grid();
        let areas = body.split_evenly((rows, cols));
        for (panel, area) in self.panels.iter().zip(areas.iter()) {
            draw_panel(area, panel)?;
        }
        Ok(())
    }
}

/// The profile drawn as a curve through its solved points: between neighbours it interpolates
/// the signed root `z = sign(v − v̂)·√Δχ²` linearly (MINOS's variable, linear in `v` for a
/// quadratic profile) and draws `z²`, so three points of a parabola draw that parabola rather
/// than a V. `steps` points per gap; points below the minimum (Δχ² < 0) count as Δχ² = 0.
pub fn profile_curve(points: &[(f64, f64)], value: f64, steps: usize) -> Vec<(f64, f64)> {
    let z = |(x, y): (f64, f64)| (x - value).signum() * y.max(0.0).sqrt();
    let mut out = Vec::new();
    for pair in points.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (za, zb) = (z(a), z(b));
        // A gap that straddles the fit's value passes through Δχ² = 0 there.
        let through_min = a.0 < value && value < b.0;
        for i in 0..steps {
            let t = i as f64 / steps as f64;
            let x = a.0 + (b.0 - a.0) * t;
            let zx = if through_min {
                if x < value {
                    za * (value - x) / (value - a.0)
                } else {
                    zb * (x - value) / (b.0 - value)
                }
            } else {
                za + (zb - za) * t
            };
            out.push((x, zx * zx));
        }
    }
    if let Some(&(x, y)) = points.last() {
        out.push((x, y.max(0.0)));
    }
    out
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &ProfilePanel) -> Result<()> {
    let ends = p.quadratic_ends.iter().flatten().copied();
    let xs = p.points.iter().map(|q| q.0).chain(ends);
    let (mut x0, mut x1) = xs.fold((p.value, p.value), |(a, b), x| (a.min(x), b.max(x)));
    if x1 - x0 <= 0.0 {
        let pad = p.std_error.unwrap_or(1e-3 * p.value.abs().max(1e-3));
        (x0, x1) = (p.value - pad, p.value + pad);
    }
    let pad = 0.04 * (x1 - x0);
    let frame = Frame {
        caption: Some(&p.title),
        margin: 8,
        x_label_area: 40,
        y_label_area: 46,
    };
    let mut chart = cartesian(area, frame, (x0 - pad)..(x1 + pad), Y_MIN..Y_MAX)?;
    let span = x1 - x0 + 2.0 * pad;
    let x_fmt = |v: &f64| fmt_tick(*v, span);
    let y_fmt = |v: &f64| format!("{v:.0}");
    Axes::new("value", "Δχ²", &x_fmt, &y_fmt)
        .ticks(5, 7)
        .text_px(LABEL_PX - 2, LABEL_PX)
        .draw(&mut chart)?;
    for level in LEVELS {
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x0 - pad, level), (x1 + pad, level)],
                4,
                4,
                BLACK.mix(0.45).stroke_width(1),
            ))
            .map_err(de)?;
    }
    if let Some(se) = p.std_error.filter(|s| s.is_finite() && *s > 0.0) {
        let n = 80;
        let parabola: Vec<(f64, f64)> = (0..=n)
            .map(|i| x0 - pad + (x1 - x0 + 2.0 * pad) * i as f64 / n as f64)
            .map(|x| (x, ((x - p.value) / se).powi(2)))
            .filter(|&(_, y)| y <= Y_MAX)
            .collect();
        chart
            .draw_series(LineSeries::new(
                parabola,
                RGBColor(230, 120, 0).stroke_width(2),
            ))
            .map_err(de)?;
    }
    let blue = RGBColor(35, 75, 205);
    let shown: Vec<(f64, f64)> = p
        .points
        .iter()
        .map(|&(x, y)| (x, y.clamp(Y_MIN, Y_MAX)))
        .collect();
    let curve: Vec<(f64, f64)> = profile_curve(&p.points, p.value, 16)
        .into_iter()
        .map(|(x, y)| (x, y.clamp(Y_MIN, Y_MAX)))
        .collect();
    chart
        .draw_series(LineSeries::new(curve, blue.stroke_width(2)))
        .map_err(de)?;
    chart
        .draw_series(shown.iter().map(|&q| Circle::new(q, 3, blue.filled())))
        .map_err(de)?;
    // A side whose 95% end is the local quadratic's: Δχ² = d₁·((v − v̂)/h₁)² from its solved
    // point (the outermost on that side) to the end.
    let outer = [p.points.first(), p.points.last()];
    for (end, solved) in p.quadratic_ends.iter().zip(outer) {
        let (Some(&end), Some(&(x1, d1))) = (end.as_ref(), solved) else {
            continue;
        };
        let h1 = x1 - p.value;
        if h1 == 0.0 || d1.is_nan() || d1 <= 0.0 {
            continue;
        }
        let n = 24;
        let curve: Vec<(f64, f64)> = (0..=n)
            .map(|i| x1 + (end - x1) * i as f64 / n as f64)
            .map(|x| (x, (d1 * ((x - p.value) / h1).powi(2)).min(Y_MAX)))
            .collect();
        chart
            .draw_series(DashedLineSeries::new(curve, 5, 4, blue.stroke_width(2)))
            .map_err(de)?;
        let top = (d1 * ((end - p.value) / h1).powi(2)).min(Y_MAX);
        chart
            .draw_series(std::iter::once(Circle::new(
                (end, top),
                4,
                blue.stroke_width(2),
            )))
            .map_err(de)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_points_of_a_parabola_draw_the_parabola_not_a_v() {
        // fits/demo's profiles: the fit and one solved point each side, on ((v − 2)/0.1)².
        let d = |x: f64| ((x - 2.0) / 0.1f64).powi(2);
        let points = [(1.85, d(1.85)), (2.0, 0.0), (2.12, d(2.12))];
        let curve = profile_curve(&points, 2.0, 16);
        assert_eq!(curve.first(), Some(&(1.85, d(1.85))));
        assert_eq!(curve.last(), Some(&(2.12, d(2.12))));
        for (x, y) in curve {
            // Exact for a quadratic up to rounding; straight segments would be off by up to
            // ~0.56 at the segments' middles.
            assert!((y - d(x)).abs() < 1e-9, "{x}: {y} vs {}", d(x));
        }
        // A negative Δχ² (a point below the fit's cost) draws at 0, never below.
        let curve = profile_curve(&[(1.9, 1.0), (2.0, -0.01), (2.1, 1.0)], 2.0, 4);
        assert!(curve.iter().all(|&(_, y)| y >= 0.0));
    }
}
