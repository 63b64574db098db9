//! Azimuthal scattering: the lobe `N_p`, where its logistic wraps, and the width integral
//! `Ñ_p = ⟨A_p N_p⟩_h`, `Ā₃ = ⟨A₃⟩_h` (the cylinder's optics and the logistic are
//! [`crate::families::shared`]'s).
//!
//! Everything here depends on θ_r and φ only, never on θ_i: one [`AzimuthalTable`] serves every
//! incidence that shares an exit direction (see [`super::evaluator`]).

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use num_dual::DualNum;

use super::{ChiangEffects, ChiangParams};
use crate::families::shared::cylinder::{
    attenuations, exit_azimuth, fresnel, transmittance, ExitRefraction,
};
use crate::families::shared::logistic::{logistic_scale, trimmed_logistic, trimmed_logistic_norm};
use crate::families::shared::quadrature::WidthNode;
use crate::geometry::angles::wrap_t;

/// `N_p = ℓ(wrap(−φ − Φ_p))` (pbrt's azimuth difference is `φ_i − φ_o = −φ`).
#[inline]
pub fn azimuthal_lobe<T: DualNum<f64>>(phi: f64, exit: &T, inv_s: &T, norm: &T) -> T {
    trimmed_logistic(&wrap_t(-exit.clone() - phi), inv_s, norm)
}

/// Where lobe `p`'s integrand has its kink: the offsets γ ∈ (−π/2, π/2) at which the logistic's
/// argument `−φ − Φ_p(γ)` crosses π (mod 2π), where the trimmed logistic wraps with a jump in
/// slope. Appended to `out`. `Φ_p` is monotone in γ except for TRT's caustic at
/// `sin²γ_c = (4 − η'²)/3` (η' < 2), so each monotone piece is searched for every crossing.
pub fn wrap_kinks(p: usize, eta_prime: f64, phi: f64, out: &mut Vec<f64>) {
    let pf = p as f64;
    let excess = |gamma: f64| {
        let gamma_t = (gamma.sin() / eta_prime).asin();
        -phi - exit_azimuth(p, gamma, &gamma_t) - PI
    };
    let slope = |gamma: f64| {
        let s = gamma.sin();
        2.0 - 2.0 * pf * gamma.cos() / (eta_prime * eta_prime - s * s).sqrt()
    };
    let mut ends = vec![-FRAC_PI_2];
    if p == 2 && eta_prime < 2.0 {
        let caustic = ((4.0 - eta_prime * eta_prime) / 3.0).sqrt().asin();
        ends.extend([-caustic, caustic]);
    }
    ends.push(FRAC_PI_2);
    for piece in ends.windows(2) {
        let (a, b) = (piece[0], piece[1]);
        let (ga, gb) = (excess(a), excess(b));
        let (lo, hi) = (ga.min(gb), ga.max(gb));
        let mut k = (lo / TAU).ceil();
        while k * TAU <= hi {
            let target = k * TAU;
            if target > lo && target < hi {
                out.push(monotone_root(|g| excess(g) - target, slope, a, b));
            }
            k += 1.0;
        }
    }
}

/// The root of `f` in `[a, b]` (`f(a)`, `f(b)` of opposite signs, `f` monotone): Newton steps
/// with `slope = f'`, bisection whenever a step leaves the bracket, to ~1 ulp of γ.
fn monotone_root(f: impl Fn(f64) -> f64, slope: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let rising = f(b) > f(a);
    let (mut lo, mut hi) = (a, b);
    let mut x = 0.5 * (a + b);
    for _ in 0..100 {
        let fx = f(x);
        if fx == 0.0 {
            return x;
        }
        if (fx < 0.0) == rising {
            lo = x;
        } else {
            hi = x;
        }
        let d = slope(x);
        let newton = x - fx / d;
        let next = if d != 0.0 && newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - x).abs() <= 2.0 * f64::EPSILON || hi - lo <= 2.0 * f64::EPSILON {
            return next;
        }
        x = next;
    }
    x
}

/// The nodes of one exit direction's width integral: the lobes' and the residual's (the same
/// slice for a plain rule; the smooth `Ā₃` needs no breaks at the logistics' kinks).
#[derive(Debug, Clone, Copy)]
pub struct WidthSet<'a> {
    pub lobes: &'a [WidthNode],
    pub residual: &'a [WidthNode],
}

/// The width-averaged azimuthal factors of one exit direction, per channel:
/// `lobes[c][p] = Ñ_p = ⟨A_p N_p⟩_h` (p < 3) and `residual[c] = Ā₃ = ⟨A₃⟩_h`. Disabled terms are 0.
#[derive(Debug, Clone, PartialEq)]
pub struct AzimuthalTable<T> {
    pub lobes: Vec<[T; 3]>,
    pub residual: Vec<T>,
}

impl<T: DualNum<f64>> AzimuthalTable<T> {
    /// Zeros for `n` channels (the buffers are reused by [`AzimuthalTable::fill`]).
    pub fn zeros(n: usize) -> Self {
        AzimuthalTable {
            lobes: vec![[T::from(0.0), T::from(0.0), T::from(0.0)]; n],
            residual: vec![T::from(0.0); n],
        }
    }

    /// The width integral for exit inclination `theta_r` and azimuth `phi` (radians) over the
    /// width rule's nodes (see [`super::ChiangModel::width_nodes_for`]): the lobes over
    /// `nodes.lobes`, `Ā₃` over `nodes.residual` (one pass when they are the same rule).
    pub fn fill(
        &mut self,
        params: &ChiangParams<T>,
        effects: &ChiangEffects,
        nodes: WidthSet<'_>,
        theta_r: f64,
        phi: f64,
    ) {
        let n = params.sigma_a.len();
        assert_eq!(self.lobes.len(), n, "one table row per channel");
        for c in 0..n {
            self.lobes[c] = [T::from(0.0), T::from(0.0), T::from(0.0)];
            self.residual[c] = T::from(0.0);
        }
        if std::ptr::eq(nodes.lobes, nodes.residual) {
            return self.accumulate(params, effects, nodes.lobes, theta_r, phi);
        }
        let (lobes, residual) = effects.split_residual();
        if lobes.r || lobes.tt || lobes.trt {
            self.accumulate(params, &lobes, nodes.lobes, theta_r, phi);
        }
        if residual.residual {
            self.accumulate(params, &residual, nodes.residual, theta_r, phi);
        }
    }

    /// Add the enabled terms' integrals over `nodes`. Per node: one `asin`, one Fresnel, the
    /// enabled logistics (channel independent), then per channel one `exp` for T and a few
    /// products.
    fn accumulate(
        &mut self,
        params: &ChiangParams<T>,
        effects: &ChiangEffects,
        nodes: &[WidthNode],
        theta_r: f64,
        phi: f64,
    ) {
        let n = params.sigma_a.len();
        let on = [effects.r, effects.tt, effects.trt];
        let transmitted = effects.tt || effects.trt || effects.residual;
        let any_lobe = effects.r || effects.tt || effects.trt;
        let refraction = ExitRefraction::new(&params.eta, theta_r);
        let (inv_s, norm) = if any_lobe {
            let s = logistic_scale(&params.beta_n);
            (s.recip(), trimmed_logistic_norm(&s))
        } else {
            (T::from(0.0), T::from(0.0))
        };
        let inv_eta_prime = refraction.eta_prime.recip();
        let two_over_cos_tt = refraction.cos_theta_t.recip() * 2.0;
        let mut lobe_n: [T; 3] = [T::from(0.0), T::from(0.0), T::from(0.0)];
        for node in nodes {
            let f = fresnel(&params.eta, refraction.cos_theta_r * node.cos_gamma);
            let sin_gt = inv_eta_prime.clone() * node.h;
            let gamma_t = sin_gt.asin();
            for p in 0..3 {
                if on[p] {
                    let exit = exit_azimuth(p, node.gamma, &gamma_t);
                    lobe_n[p] = azimuthal_lobe(phi, &exit, &inv_s, &norm) * node.weight;
                }
            }
            if effects.r {
                // A₀ = F is the same in every channel.
                let r = f.clone() * lobe_n[0].clone();
                for row in self.lobes.iter_mut() {
                    row[0] += r.clone();
                }
            }
            if !transmitted {
                continue;
            }
            let cos_gt = (-sin_gt.powi(2) + 1.0).sqrt();
            let chord = cos_gt * two_over_cos_tt.clone();
            for c in 0..n {
                let t = transmittance(&params.sigma_a[c], &chord);
                let a = attenuations(&f, &t);
                for p in 1..3 {
                    if on[p] {
                        self.lobes[c][p] += a[p].clone() * lobe_n[p].clone();
                    }
                }
                if effects.residual {
                    self.residual[c] += a[3].clone() * node.weight;
                }
            }
        }
    }
}
