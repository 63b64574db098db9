//! The fibre's cross-section: an ellipse of semi-axes 1 and `a` (a ≤ 1) in the normal plane
//! `(v, w)`, its major axis at angle ψ from `v`; line intersections and outward normals.

/// An oriented elliptical cross-section (a circle when `a` = 1).
#[derive(Debug, Clone, Copy)]
pub struct Section {
    /// Minor semi-axis (the major is 1).
    a: f64,
    /// 1/a².
    pub(super) ia2: f64,
    /// cos ψ, sin ψ of the major axis' angle from `v` (exactly 1 and 0 for a circle, so the
    /// sampler's lanes can use the ellipse's formulas for both).
    pub(super) c: f64,
    pub(super) s: f64,
}

impl Section {
    pub fn new(a: f64, psi: f64) -> Section {
        let (s, c) = if a == 1.0 { (0.0, 1.0) } else { psi.sin_cos() };
        Section {
            a,
            ia2: 1.0 / (a * a),
            c,
            s,
        }
    }

    /// A 2-D vector in the ellipse's own axes.
    #[inline]
    fn local(&self, x: [f64; 2]) -> [f64; 2] {
        [
            self.c * x[0] + self.s * x[1],
            -self.s * x[0] + self.c * x[1],
        ]
    }

    /// Half the width the section presents across the in-plane direction `dir` (unit).
    #[inline]
    pub fn half_width(&self, dir: [f64; 2]) -> f64 {
        let perp = self.local([-dir[1], dir[0]]);
        (perp[0] * perp[0] + self.a * self.a * perp[1] * perp[1]).sqrt()
    }

    /// Quadratic coefficients `(A, B, C)` of `|p + t d|_ellipse² = 1` for the in-plane
    /// components `p`, `d` (`d` need not be unit: its length is the 3-D direction's).
    #[inline]
    fn quadratic(&self, p: [f64; 2], d: [f64; 2]) -> (f64, f64, f64) {
        let (p, d) = (self.local(p), self.local(d));
        let ia2 = self.ia2;
        let qa = d[0] * d[0] + d[1] * d[1] * ia2;
        let qb = 2.0 * (p[0] * d[0] + p[1] * d[1] * ia2);
        let qc = p[0] * p[0] + p[1] * p[1] * ia2 - 1.0;
        (qa, qb, qc)
    }

    /// Distance along `d` from outside point `p` to the section's boundary, if the line hits it.
    #[inline]
    pub fn entry(&self, p: [f64; 2], d: [f64; 2]) -> Option<f64> {
        let (qa, qb, qc) = self.quadratic(p, d);
        let disc = qb * qb - 4.0 * qa * qc;
        if !(disc > 0.0 && qa > 0.0) {
            return None;
        }
        // The nearer root without cancellation (qb < 0 when the line heads toward the section).
        let q = -0.5 * (qb - disc.sqrt());
        let t = qc / q;
        (t.is_finite() && t > 0.0).then_some(t)
    }

    /// Distance along `d` from boundary point `p` to the boundary's other side: the quadratic's
    /// second root, `−B/A` (its first is 0); `None` for a direction along the axis.
    pub fn chord(&self, p: [f64; 2], d: [f64; 2]) -> Option<f64> {
        let (qa, qb, _) = self.quadratic(p, d);
        let t = -qb / qa;
        (qa > 0.0 && t.is_finite() && t > 0.0).then_some(t)
    }

    /// Outward unit normal at boundary point `p`, in `(v, w)`.
    #[inline]
    pub fn normal(&self, p: [f64; 2]) -> [f64; 2] {
        if self.a == 1.0 {
            // On the unit circle up to rounding; normalised so the rounding does not accumulate.
            let k = 1.0 / (p[0] * p[0] + p[1] * p[1]).sqrt();
            return [p[0] * k, p[1] * k];
        }
        let l = self.local(p);
        let g = [l[0], l[1] * self.ia2];
        let n = (g[0] * g[0] + g[1] * g[1]).sqrt();
        let g = [g[0] / n, g[1] / n];
        [self.c * g[0] - self.s * g[1], self.s * g[0] + self.c * g[1]]
    }
}
