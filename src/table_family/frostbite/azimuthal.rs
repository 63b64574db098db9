//! The pre-integrated azimuthal distributions of the Frostbite/HDRP hair model: for each lobe
//! p = 0 (R), 1 (TT), 2 (TRT), the trimmed logistic of Chiang 2016 (eq. 8) averaged over the
//! fibre width,
//!
//! `N_p(φ, θ_d; β_N) = ½ ∫₋₁¹ D_s(φ − Φ_p(h)) dh`,  `Φ_p = 2p·asin(h/η′) − 2·asin h + pπ`,
//!
//! with Karis's fit of the modified index `η′ = 1.19/cos θ_d + 0.36 cos θ_d` (η = 1.55) and the
//! logistic scale `s(β_N)` of Chiang eq. 8. HDRP tabulates the same integral on a 64³ texture;
//! hairfit computes its own table once per process ([`AzimuthalLut::shared`]) and reads it
//! with Catmull–Rom interpolation in all three axes (C¹, so the derivative in β_N that a fit
//! takes is continuous). The table's error against [`integrate_directly`] is measured in
//! tests/frostbite_table.rs and docs/frostbite.md.
//!
//! How the table is built: N_p is the circular convolution of the distribution of exit
//! azimuths `Φ_p(h)` (h uniform) with the trimmed logistic, so its Fourier coefficients are the
//! products `μ̂_k · D̂_k(s)`. `μ̂_k = ½∫cos(kΦ_p) dh` is integrated once per (p, θ_d) by
//! Gauss–Legendre in γ = asin h; `D̂_k(s)` of the logistic trimmed to [−π, π] has a closed form
//! ([`trimmed_logistic_cosine`]). That costs a fraction of a second where sampling the integral
//! at every node would take minutes.

use std::f64::consts::PI;
use std::sync::OnceLock;

use num_dual::DualNum;
use rayon::prelude::*;

use crate::chiang::azimuthal::{
    exit_azimuth, logistic_scale, trimmed_logistic, trimmed_logistic_norm,
};
use crate::chiang::quadrature::WidthRule;
use crate::model::angles::wrap;

/// Smallest azimuthal roughness β_N the table covers (radial smoothness 0.9): below it the TRT
/// caustics are narrower than the table's 1° azimuth step (docs/frostbite.md, "The table").
pub const BETA_N_MIN: f64 = 0.1;
/// Largest β_N (radial smoothness 0).
pub const BETA_N_MAX: f64 = 1.0;

/// Azimuth step of the table: 1°.
const PHI_STEPS: usize = 180;
/// Steps in x = 1/η′ over [0, 1/1.55].
const X_STEPS: usize = 96;
/// Steps in u = ln s(β_N) over [ln s(0.1), ln s(1)].
const U_STEPS: usize = 36;
/// Fourier terms at most, and at least (the logistic trimmed to [−π, π] has a kink where the
/// periodic extension joins, so its coefficients fall only as 1/k² at large s).
const K_MAX: usize = 256;
const K_MIN: usize = 48;
/// Gauss–Legendre nodes in γ for μ̂_k: k·Φ_p turns through at most ~1200 periods at K_MAX.
const MU_NODES: usize = 2048;

/// Karis 2016's fit of Bravais' modified index for η = 1.55: `η′ = 1.19/cos θ_d + 0.36 cos θ_d`.
#[inline]
pub fn modified_index(cos_theta_d: f64) -> f64 {
    1.19 / cos_theta_d + 0.36 * cos_theta_d
}

/// `1/η′` without dividing by cos θ_d (finite as cos θ_d → 0): the table's second axis.
#[inline]
pub fn inverse_modified_index(cos_theta_d: f64) -> f64 {
    cos_theta_d / (1.19 + 0.36 * cos_theta_d * cos_theta_d)
}

/// `Φ_p(h)` for `x = 1/η′` (Marschner 2003 eq. 3 with γ_t = asin(h x)).
#[inline]
pub fn exit_azimuth_at(p: usize, h: f64, x: f64) -> f64 {
    exit_azimuth(p, h.asin(), &(h * x).asin())
}

/// `N_p(φ, θ_d; β_N)` by Gauss–Legendre in γ with `nodes` nodes: the integral the table holds.
pub fn integrate_directly(p: usize, phi: f64, cos_theta_d: f64, beta_n: f64, nodes: usize) -> f64 {
    let rule = WidthRule::cached(nodes).expect("node count in range");
    let s = logistic_scale(&beta_n);
    let (inv_s, norm) = (s.recip(), trimmed_logistic_norm(&s));
    let x = inverse_modified_index(cos_theta_d);
    rule.nodes
        .iter()
        .map(|n| {
            let d = wrap(phi - exit_azimuth_at(p, n.h, x));
            n.weight * trimmed_logistic(&d, &inv_s, &norm)
        })
        .sum()
}

/// `∫_{−π}^{π} D_s(x) cos(kx) dx` for the logistic of scale `s` trimmed to [−π, π]: the whole
/// line's `πsk/sinh(πsk)` less both tails `∫_π^∞`, summed from the series
/// `L(x) = (1/s)Σ_n (−1)^{n+1} n e^{−nx/s}`, over the trimmed mass `tanh(π/2s)`.
pub fn trimmed_logistic_cosine(k: usize, s: f64) -> f64 {
    let kf = k as f64;
    let a = PI * s * kf;
    let whole = if k == 0 {
        1.0
    } else {
        // πsk/sinh(πsk) without overflow.
        2.0 * a * (-a).exp() / (1.0 - (-2.0 * a).exp())
    };
    let q = (-PI / s).exp();
    let mut tail = 0.0;
    let mut qn = 1.0;
    for n in 1..=400 {
        qn *= q;
        let nf = n as f64;
        let term = qn * nf * nf / (nf * nf + kf * kf * s * s);
        tail += if n % 2 == 1 { term } else { -term };
        if qn * nf * nf < 1e-18 {
            break;
        }
    }
    if k % 2 == 1 {
        tail = -tail;
    }
    (whole - 2.0 * tail) / (PI / (2.0 * s)).tanh()
}

/// `μ̂_k = ½∫₋₁¹ cos(kΦ_p(h)) dh` for k = 0..=k_max (e^{ikΦ} by repeated rotation). The
/// integrand is even in h (`Φ_p(−h) = 2pπ − Φ_p(h)`), so the nodes with h ≥ 0 carry it twice.
fn exit_azimuth_cosines(p: usize, x: f64, k_max: usize) -> Vec<f64> {
    let rule = WidthRule::cached(MU_NODES).expect("node count in range");
    let mut mu = vec![0.0; k_max + 1];
    for n in rule.nodes.iter().filter(|n| n.h >= 0.0) {
        let w = if n.h == 0.0 { n.weight } else { 2.0 * n.weight };
        let (sin_phi, cos_phi) = exit_azimuth_at(p, n.h, x).sin_cos();
        let (mut c, mut s) = (1.0, 0.0);
        for m in mu.iter_mut() {
            *m += w * c;
            (c, s) = (c * cos_phi - s * sin_phi, s * cos_phi + c * sin_phi);
        }
    }
    mu
}

/// Fourier terms kept at scale `s`: until `D̂_k ≈ e^{−πsk}` falls below 1e-6, within
/// [`K_MIN`, `K_MAX`].
fn terms_at(s: f64) -> usize {
    ((14.0 / (PI * s)).ceil() as usize).clamp(K_MIN, K_MAX)
}

/// The table's axes: node `i` of an axis is `start + i·step`, for i = −1 ..= steps + 1 (one
/// ghost node past each end so that every cell has the four nodes Catmull–Rom reads).
#[derive(Debug, Clone, Copy)]
struct Axis {
    start: f64,
    step: f64,
    steps: usize,
}

impl Axis {
    const fn new(start: f64, end: f64, steps: usize) -> Axis {
        Axis {
            start,
            step: (end - start) / steps as f64,
            steps,
        }
    }

    /// Stored nodes, ghosts included.
    fn len(self) -> usize {
        self.steps + 3
    }

    /// The value at stored node `j` (j = 0 is the ghost before `start`).
    fn at(self, j: usize) -> f64 {
        self.start + (j as f64 - 1.0) * self.step
    }

    /// The cell holding `v` (clamped to the axis) and the position in it, as the stored index
    /// of the cell's first node and t ∈ [0, 1].
    fn cell(self, v: f64) -> (usize, f64) {
        let f = ((v - self.start) / self.step).clamp(0.0, self.steps as f64);
        let i = (f.floor() as usize).min(self.steps - 1);
        (i + 1, f - i as f64)
    }
}

/// Catmull–Rom weights of the nodes −1, 0, 1, 2 around a point at `t` ∈ [0, 1] of its cell.
#[inline]
fn catmull_rom<T: DualNum<f64>>(t: &T) -> [T; 4] {
    let t2 = t.clone() * t.clone();
    let t3 = t2.clone() * t.clone();
    [
        (-t3.clone() + t2.clone() * 2.0 - t.clone()) * 0.5,
        (t3.clone() * 3.0 - t2.clone() * 5.0 + 2.0) * 0.5,
        (-t3.clone() * 3.0 + t2.clone() * 4.0 + t.clone()) * 0.5,
        (t3 - t2) * 0.5,
    ]
}

/// `N_R, N_TT, N_TRT` on the grid (φ, x = 1/η′, u = ln s), built once per process.
pub struct AzimuthalLut {
    phi: Axis,
    x: Axis,
    u: Axis,
    /// `values[((p·U + u)·X + x)·Φ + φ]` over the stored nodes.
    values: Vec<f32>,
}

/// Where one direction pair reads the table: the φ and x cells with their (plain) weights,
/// the u cell with weights in the number type (β_N is a fitted parameter).
pub struct LutPoint<T> {
    phi_cell: usize,
    x_cell: usize,
    u_cell: usize,
    phi_w: [f64; 4],
    x_w: [f64; 4],
    u_w: [T; 4],
}

impl AzimuthalLut {
    /// The process's table (built on first use: 0.35 s of CPU, split over the cores by rayon).
    pub fn shared() -> &'static AzimuthalLut {
        static TABLE: OnceLock<AzimuthalLut> = OnceLock::new();
        TABLE.get_or_init(AzimuthalLut::build)
    }

    fn build() -> AzimuthalLut {
        let phi = Axis::new(0.0, PI, PHI_STEPS);
        let x = Axis::new(0.0, inverse_modified_index(1.0), X_STEPS);
        let u = Axis::new(
            logistic_scale(&BETA_N_MIN).ln(),
            logistic_scale(&BETA_N_MAX).ln(),
            U_STEPS,
        );
        // cos(kφ_i) for φ_i = (i − 1)·1°: an exact lookup by (k·(i − 1)) mod 360.
        let cos_deg: Vec<f64> = (0..360).map(|d| (d as f64).to_radians().cos()).collect();
        let scales: Vec<f64> = (0..u.len()).map(|j| u.at(j).exp()).collect();
        let kernel: Vec<Vec<f64>> = scales
            .iter()
            .map(|&s| {
                (0..=terms_at(s))
                    .map(|k| trimmed_logistic_cosine(k, s))
                    .collect()
            })
            .collect();
        let slabs: Vec<(usize, usize)> = (0..3)
            .flat_map(|p| (0..x.len()).map(move |j| (p, j)))
            .collect();
        // One slab per (lobe, x): μ̂_k once, then every (u, φ) node from it.
        let built: Vec<Vec<f32>> = slabs
            .par_iter()
            .map(|&(p, j)| {
                let mu = exit_azimuth_cosines(p, x.at(j), K_MAX);
                let mut out = vec![0.0f32; u.len() * phi.len()];
                for (l, d_hat) in kernel.iter().enumerate() {
                    let coeff: Vec<f64> = d_hat
                        .iter()
                        .zip(&mu)
                        .enumerate()
                        .map(|(k, (d, m))| d * m * if k == 0 { 0.5 } else { 1.0 } / PI)
                        .collect();
                    for i in 0..phi.len() {
                        // cos(k·d°) for d = i − 1: the index steps by d (mod 360) with k.
                        let step = (i as i64 - 1).rem_euclid(360) as usize;
                        let mut at = 0;
                        let mut n = 0.0;
                        for c in &coeff {
                            n += c * cos_deg[at];
                            at += step;
                            if at >= 360 {
                                at -= 360;
                            }
                        }
                        out[l * phi.len() + i] = n as f32;
                    }
                }
                out
            })
            .collect();
        let (nu, nx, nphi) = (u.len(), x.len(), phi.len());
        let mut values = vec![0.0f32; 3 * nu * nx * nphi];
        for (&(p, j), slab) in slabs.iter().zip(&built) {
            for l in 0..nu {
                let dst = ((p * nu + l) * nx + j) * nphi;
                values[dst..dst + nphi].copy_from_slice(&slab[l * nphi..(l + 1) * nphi]);
            }
        }
        AzimuthalLut { phi, x, u, values }
    }

    /// Where `(φ, cos θ_d, β_N)` reads the table (φ by its magnitude: N_p is even in φ).
    pub fn locate<T: DualNum<f64>>(&self, phi: f64, cos_theta_d: f64, beta_n: &T) -> LutPoint<T> {
        let (phi_cell, tp) = self.phi.cell(wrap(phi).abs());
        let (x_cell, tx) = self.x.cell(inverse_modified_index(cos_theta_d));
        let u = logistic_scale(beta_n).ln();
        let (u_cell, _) = self.u.cell(u.re());
        // The position in the u cell carries β_N's derivative (the cell is fixed by its value).
        let tu = (u - self.u.at(u_cell)) / self.u.step;
        LutPoint {
            phi_cell,
            x_cell,
            u_cell,
            phi_w: catmull_rom(&tp),
            x_w: catmull_rom(&tx),
            u_w: catmull_rom(&tu),
        }
    }

    /// `N_p` at `at` (p = 0, 1, 2 for R, TT, TRT).
    pub fn value<T: DualNum<f64>>(&self, p: usize, at: &LutPoint<T>) -> T {
        let (nu, nx, nphi) = (self.u.len(), self.x.len(), self.phi.len());
        let mut out = T::zero();
        for (a, wu) in at.u_w.iter().enumerate() {
            let mut slice = 0.0;
            for (b, wx) in at.x_w.iter().enumerate() {
                let row = ((p * nu + at.u_cell + a - 1) * nx + at.x_cell + b - 1) * nphi;
                let v = &self.values[row + at.phi_cell - 1..row + at.phi_cell + 3];
                let along: f64 = v.iter().zip(&at.phi_w).map(|(v, w)| *v as f64 * w).sum();
                slice += wx * along;
            }
            out += wu.clone() * slice;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed-form D̂_k against Gauss–Legendre on [−π, π], at a narrow and a wide logistic
    /// (the wide one is where trimming matters): agreement to 1e-12 absolute.
    #[test]
    fn trimmed_logistic_cosine_matches_quadrature() {
        let rule = WidthRule::cached(4000).unwrap();
        for s in [0.03, 0.3, 1.5, 4.28] {
            let (inv_s, norm) = (1.0 / s, trimmed_logistic_norm(&s));
            for k in [0, 1, 2, 7, 40] {
                // x = 2γ over γ ∈ [−π/2, π/2]: dx = 2dγ; the rule's weights carry cos γ, undo it.
                let q: f64 = rule
                    .nodes
                    .iter()
                    .map(|n| {
                        let xv = 2.0 * n.gamma;
                        (n.weight / n.cos_gamma)
                            * 4.0
                            * trimmed_logistic(&xv, &inv_s, &norm)
                            * (k as f64 * xv).cos()
                    })
                    .sum();
                let c = trimmed_logistic_cosine(k, s);
                assert!((q - c).abs() < 1e-12, "s {s} k {k}: {q} vs {c}");
            }
        }
    }

    /// μ̂_k is converged at MU_NODES: doubling the nodes moves no coefficient by 1e-12.
    #[test]
    fn exit_azimuth_cosines_are_converged() {
        for p in 0..3 {
            let a = exit_azimuth_cosines(p, 0.5, K_MAX);
            let rule = WidthRule::cached(2 * MU_NODES).unwrap();
            for k in [0, 1, 50, K_MAX] {
                let b: f64 = rule
                    .nodes
                    .iter()
                    .map(|n| n.weight * (k as f64 * exit_azimuth_at(p, n.h, 0.5)).cos())
                    .sum();
                assert!((a[k] - b).abs() < 1e-12, "p {p} k {k}: {} vs {b}", a[k]);
            }
        }
    }
}
