//! The exit-angle map `Φ(p, γ_i)` of each root mode, parameterised by `γ_i` (`h = sin γ_i`), with
//! its slope, its caustic (fold) and `d²Φ/dh²` there. One map per evaluation serves roots,
//! derivative and caustic, so the two modes never mix.

use num_dual::DualNum;
use std::f64::consts::{FRAC_PI_2, PI};

use super::RootMode;

/// `Φ(p, ·)` for one lobe at one Bravais index, in the chosen root mode.
#[derive(Debug, Clone)]
pub struct ExitMap<T> {
    pub mode: RootMode,
    /// Lobe index p (1 = TT, 2 = TRT; R is solved in closed form).
    pub p: usize,
    /// `η'`.
    pub eta_p: T,
    /// Cubic coefficients `Φ̂ = aγ³ + bγ + pπ` (cubic mode only; zero in exact mode).
    pub a: T,
    pub b: T,
    /// The caustic `γ_c` inside `(0, π/2)`, found once with the map (roots and glint share it).
    caustic: Option<T>,
}

impl<T: DualNum<f64>> ExitMap<T> {
    /// Build the map; cubic mode: `c = asin(1/η')`, `a = −8pc/π³`, `b = 6pc/π − 2`.
    #[inline]
    pub fn new(mode: RootMode, p: usize, eta_p: T) -> Self {
        let (a, b) = match mode {
            RootMode::Cubic => {
                let c = eta_p.recip().asin();
                let pf = p as f64;
                (
                    c.clone() * (-8.0 * pf / (PI * PI * PI)),
                    c * (6.0 * pf / PI) - 2.0,
                )
            }
            RootMode::Exact => (T::from(0.0), T::from(0.0)),
        };
        let caustic = caustic_of(mode, p, &eta_p, &a, &b);
        ExitMap {
            mode,
            p,
            eta_p,
            a,
            b,
            caustic,
        }
    }

    /// The same map on the real parts (for solving in f64).
    #[inline]
    pub fn real(&self) -> ExitMap<f64> {
        ExitMap {
            mode: self.mode,
            p: self.p,
            eta_p: self.eta_p.re(),
            a: self.a.re(),
            b: self.b.re(),
            caustic: self.caustic.as_ref().map(|g| g.re()),
        }
    }

    /// `Φ(p, γ)`: exact `2p·asin(sin γ/η') − 2γ + pπ`, or the cubic `aγ³ + bγ + pπ`.
    #[inline]
    pub fn value(&self, g: &T) -> T {
        let pf = self.p as f64;
        match self.mode {
            RootMode::Exact => {
                (g.sin() / self.eta_p.clone()).asin() * (2.0 * pf) - g.clone() * 2.0 + pf * PI
            }
            RootMode::Cubic => {
                let g2 = g.clone() * g.clone();
                (self.a.clone() * g2 + self.b.clone()) * g.clone() + pf * PI
            }
        }
    }

    /// `dΦ/dγ = cos γ · dΦ/dh`: exact `2p cos γ/sqrt(η'² − sin²γ) − 2`, cubic `3aγ² + b`.
    #[inline]
    pub fn slope(&self, g: &T) -> T {
        match self.mode {
            RootMode::Exact => {
                let (s, c) = g.sin_cos();
                let e = self.eta_p.clone();
                c * (2.0 * self.p as f64) / (e.clone() * e - s.clone() * s).sqrt() - 2.0
            }
            RootMode::Cubic => self.a.clone() * g.clone() * g.clone() * 3.0 + self.b.clone(),
        }
    }

    /// Caustic `γ_c > 0` where `dΦ/dγ = 0`, if it lies inside `(0, π/2)` ([`caustic_of`]).
    #[inline]
    pub fn caustic(&self) -> Option<T> {
        self.caustic.clone()
    }

    /// `d²Φ/dh²` at a caustic `γ_c` given with `(sin γ_c, cos γ_c)`: exact
    /// `2p·h/(η'²−h²)^{3/2} − 2h/(1−h²)^{3/2}`, cubic `Φ̂''(γ_c)/cos²γ_c = 6aγ_c/cos²γ_c` (valid
    /// where `dΦ̂/dγ = 0`).
    #[inline]
    pub fn curvature_at_caustic(&self, g_c: &T, (sin_gc, cos_gc): &(T, T)) -> T {
        match self.mode {
            RootMode::Exact => {
                let h = sin_gc.clone();
                let h2 = h.clone() * h.clone();
                let e2 = self.eta_p.clone() * self.eta_p.clone();
                let t1 = h.clone() * (2.0 * self.p as f64) / (e2 - h2.clone()).powf(1.5);
                let t2 = h * 2.0 / (-h2 + 1.0).powf(1.5);
                t1 - t2
            }
            RootMode::Cubic => {
                self.a.clone() * g_c.clone() * 6.0 / (cos_gc.clone() * cos_gc.clone())
            }
        }
    }
}

/// Caustic `γ_c > 0` of `Φ(p, ·)` where `dΦ/dγ = 0`, if it lies inside `(0, π/2)`: exact
/// `h_c = sqrt((p² − η'²)/(p² − 1))` (TRT: `sqrt((4 − η'²)/3)`), cubic `sqrt(−b/(3a))`.
#[inline]
fn caustic_of<T: DualNum<f64>>(mode: RootMode, p: usize, eta_p: &T, a: &T, b: &T) -> Option<T> {
    let g = match mode {
        RootMode::Exact => {
            if p < 2 {
                return None;
            }
            let p2 = (p * p) as f64;
            let h2 = (-(eta_p.clone() * eta_p.clone()) + p2) / (p2 - 1.0);
            if !(h2.re() > 0.0 && h2.re() < 1.0) {
                return None;
            }
            h2.sqrt().asin()
        }
        RootMode::Cubic => {
            // b > 0 only when c = asin(1/η') is large enough, so a is far from 0 there.
            if !(b.re() > 0.0 && a.re() < 0.0) {
                return None;
            }
            (-(b.clone() / (a.clone() * 3.0))).sqrt()
        }
    };
    if g.re() < FRAC_PI_2 {
        Some(g)
    } else {
        None
    }
}
