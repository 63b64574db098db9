//! d'Eon's width integral with η held (the default): every value pass and every gradient pass
//! that does not seed η. The integral reads only η, β_N and σ_a; its derivatives are taken by
//! hand in `f64` — ∂/∂β_N of the wrapped Gaussian, ∂/∂σ_a of the transmittance carried through
//! the attenuations — and chained into the pass's duals as `N + ∂N/∂β_N·dβ_N + ∂N/∂σ_a·dσ_a`
//! (dual numbers had spent most of the fit's time here, on derivative parts the integral never
//! touches). A value pass is the same loop without the chaining, so a gradient pass's values are
//! the value pass's bits. Everything of a node but the detector depends on θ_d alone; it is
//! built once per θ_d ([`Held`]); the detectors run on the lanes ([`super::detector`]).

use std::cell::Cell;
use std::f64::consts::PI;

use num_dual::DualNum;

use super::detector::{self, Detector};
use super::{Integration, BETA_N, RESIDUAL, SIGMA_A};
use crate::families::shared::cylinder::{
    attenuations, exit_azimuth, fresnel, transmittance, ExitRefraction,
};
use crate::families::table::{DualPass, TableParams, TermSet, Terms};

/// A value and its derivatives in β_N and in the channel's own σ_a.
#[derive(Debug, Clone, Copy, Default)]
struct Grad {
    v: f64,
    beta_n: f64,
    sigma_a: f64,
}

/// [`super::add_azimuthal`] in a pass that holds η, at one `(θ_d, φ)` whose θ_d part is
/// `held`: the integral in `f64`, chained into the duals of a gradient pass on the lines it
/// seeds (`pass`; none in a value pass).
pub(super) fn add_azimuthal<T: DualNum<f64>>(
    p: &TableParams<T>,
    held: &Held,
    phi: f64,
    on: TermSet,
    pass: DualPass,
    out: &mut [Terms<T>],
) {
    let beta_n = p.get(BETA_N, 0);
    let mut integrals = held.integrals.take();
    integrals.clear();
    integrals.resize(p.n_channels, [Grad::default(); RESIDUAL + 1]);
    let n = &mut integrals;
    // dx: a line's derivative parts in `T` (real part exactly 0), where the pass seeds it.
    let d_beta = (T::NDERIV > 0 && pass.seeds(BETA_N)).then(|| beta_n.clone() - beta_n.re());
    let wanted = Wanted {
        beta_n: d_beta.is_some(),
        sigma_a: T::NDERIV > 0 && pass.seeds(SIGMA_A),
    };
    width_integral(held, beta_n.re(), phi, on, wanted, n);
    for (c, (o, n)) in out.iter_mut().zip(n.iter()).enumerate() {
        let s = p.get(SIGMA_A, c);
        let d_sigma = (T::NDERIV > 0 && pass.seeds(SIGMA_A)).then(|| s.clone() - s.re());
        for k in (0..=RESIDUAL).filter(|&k| on.has(k)) {
            let mut v = T::from(n[k].v);
            if let Some(d) = &d_beta {
                v += d.clone() * n[k].beta_n;
            }
            if let Some(d) = &d_sigma {
                v += d.clone() * n[k].sigma_a;
            }
            o[k] += v;
        }
    }
    held.integrals.set(integrals);
}

/// The part of the width integral a pass holds fixed at one θ_d: per node the Fresnel value and
/// the exit azimuths and, per channel, the attenuations with their ∂/∂σ_a. It reads η, σ_a and
/// θ_d only — never φ or β_N — so a pass builds it once per θ_d and reuses it for every φ there
/// (the demo: 35 θ_d for 1,260 (θ_d, φ) pairs). Every quantity is a line of values node by
/// node, so the integral is a handful of dot products. Size: nodes·(2 + orders + channels·
/// (6 + 2·(orders − 3))) f64, ≤ 128·24·8 B ≈ 25 kB for three channels, one θ_d at a time.
pub(super) struct Held {
    /// `Φ_p(h)` of orders 0..=highest, order-major: order p's at `p·n..(p + 1)·n`.
    exits: Vec<f64>,
    /// The rule's weights.
    weights: Vec<f64>,
    /// `F(h)`.
    fresnel: Vec<f64>,
    /// Per channel [`Held::lines_per_channel`] lines: `A₁`, `∂A₁/∂σ_a`, `A₂`, `∂A₂/∂σ_a`, then
    /// `A_p`, `∂A_p/∂σ_a` of p = 3..=highest, then the geometric tail `A_P·TF/(1 − TF)·w/(2π)`
    /// and its ∂/∂σ_a (0 where TF = 1).
    lines: Vec<f64>,
    /// Per channel the tail line's sum over the nodes and its ∂/∂σ_a: the part of the residual
    /// that does not depend on φ.
    tail_sums: Vec<(f64, f64)>,
    orders: usize,
    n: usize,
    /// Scratch of [`width_integral`] (the weighted detectors and their slopes) and of
    /// [`add_azimuthal`] (each channel's integrals), kept between the pairs of one θ_d.
    detectors: Cell<Vec<f64>>,
    integrals: Cell<Vec<[Grad; RESIDUAL + 1]>>,
}

/// Line indices within a channel's lines of [`Held`].
const A1: usize = 0;
const A2: usize = 2;
const CHAIN: usize = 4;

impl Held {
    /// The fixed part at `theta_d` for orders 0..=max(`how.highest_order`, 3).
    pub(super) fn new(eta: f64, sigma_a: &[f64], theta_d: f64, how: &Integration) -> Held {
        let refraction = ExitRefraction::new(&eta, theta_d);
        let inv_eta_prime = refraction.eta_prime.recip();
        let two_over_cos_theta_t = refraction.cos_theta_t.recip() * 2.0;
        let orders = how.highest_order.max(RESIDUAL) + 1;
        let n = how.rule.nodes.len();
        let mut held = Held {
            exits: vec![0.0; n * orders],
            weights: how.rule.nodes.iter().map(|node| node.weight).collect(),
            fresnel: Vec::with_capacity(n),
            lines: Vec::new(),
            tail_sums: Vec::new(),
            orders,
            n,
            detectors: Cell::default(),
            integrals: Cell::default(),
        };
        held.lines = vec![0.0; sigma_a.len() * held.lines_per_channel() * n];
        let mut node_lines = vec![0.0; held.lines_per_channel()];
        for (i, node) in how.rule.nodes.iter().enumerate() {
            let f = fresnel(&eta, refraction.cos_theta_r * node.cos_gamma);
            let sin_gamma_t = inv_eta_prime * node.h;
            let gamma_t = sin_gamma_t.asin();
            held.fresnel.push(f);
            for p in 0..orders {
                held.exits[p * n + i] = exit_azimuth(p, node.gamma, &gamma_t);
            }
            let chord = (-sin_gamma_t.powi(2) + 1.0).sqrt() * two_over_cos_theta_t;
            for (c, s) in sigma_a.iter().enumerate() {
                attenuate(f, s, chord, node.weight, &mut node_lines);
                for (line, &v) in node_lines.iter().enumerate() {
                    let at = held.line_at(c, line);
                    held.lines[at + i] = v;
                }
            }
        }
        let tail = CHAIN + 2 * (orders - RESIDUAL);
        held.tail_sums = (0..sigma_a.len())
            .map(|c| {
                let sum = |line: usize| held.line(c, line).iter().sum::<f64>();
                (sum(tail), sum(tail + 1))
            })
            .collect();
        held
    }

    fn lines_per_channel(&self) -> usize {
        CHAIN + 2 * (self.orders - RESIDUAL) + 2
    }

    /// Where channel `c`'s line `line` starts in `lines`.
    fn line_at(&self, c: usize, line: usize) -> usize {
        (c * self.lines_per_channel() + line) * self.n
    }

    /// Channel `c`'s line `line`.
    fn line(&self, c: usize, line: usize) -> &[f64] {
        &self.lines[self.line_at(c, line)..][..self.n]
    }
}

/// One channel's lines of [`Held`] at a node, into `out` (their order there).
fn attenuate(f: f64, s: &f64, chord: f64, weight: f64, out: &mut [f64]) {
    let t = transmittance(s, &chord);
    let [_, a1, a2, _] = attenuations(&f, &t);
    // ∂/∂σ_a: T' = −chord·T, A₁' = (1−F)²T', (TF)' = T'F, A₂' = A₁'TF + A₁(TF)'.
    let dt = -chord * t;
    let tf = t * f;
    let dtf = dt * f;
    let da1 = (-f + 1.0).powi(2) * dt;
    let da2 = da1 * tf + a1 * dtf;
    out[A1..A1 + 2].copy_from_slice(&[a1, da1]);
    out[A2..A2 + 2].copy_from_slice(&[a2, da2]);
    let (mut a_p, mut da_p) = (a2, da2);
    let chain_len = out.len() - CHAIN - 2;
    let (chain, tail) = out[CHAIN..].split_at_mut(chain_len);
    for pair in chain.chunks_exact_mut(2) {
        da_p = da_p * tf + a_p * dtf;
        a_p *= tf;
        pair.copy_from_slice(&[a_p, da_p]);
    }
    let one_minus = -tf + 1.0;
    // The tail A_P·TF/(1 − TF): (uv/q)' = (u'v + uv')/q + uv·v'/q² with q' = −v'.
    if one_minus != 0.0 {
        let w = weight / (2.0 * PI);
        let d = (da_p * tf + a_p * dtf) / one_minus + a_p * tf * dtf / one_minus.powi(2);
        tail.copy_from_slice(&[a_p * tf / one_minus * w, d * w]);
    } else {
        tail.fill(0.0);
    }
}

/// Which derivatives a pass wants of the integral (the others stay 0).
#[derive(Debug, Clone, Copy)]
struct Wanted {
    beta_n: bool,
    sigma_a: bool,
}

/// [`super::add_azimuthal`]'s integral in `f64` with the derivatives `wanted`, the θ_d part from
/// `held`: per term and channel the dot products of its attenuation lines with the weighted
/// detectors.
fn width_integral(
    held: &Held,
    beta_n: f64,
    phi: f64,
    on: TermSet,
    wanted: Wanted,
    out: &mut [[Grad; RESIDUAL + 1]],
) {
    let with_slopes = wanted.beta_n;
    let det = Detector::new(beta_n);
    let highest = if on.has(RESIDUAL) { held.orders - 1 } else { 2 };
    let n = held.n;
    // Weighted detectors per order and node, order-major: values, then ∂/∂β_N.
    let mut detectors = held.detectors.take();
    let len = (highest + 1) * n;
    detectors.clear();
    detectors.resize(if with_slopes { 2 * len } else { len }, 0.0);
    let (values, slopes) = detectors.split_at_mut(len);
    for order in (0..=highest).filter(|&k| on.has(k.min(RESIDUAL))) {
        let at = order * n..(order + 1) * n;
        detector::weighted(
            det,
            phi,
            &held.exits[at.clone()],
            &held.weights,
            &mut values[at.clone()],
            with_slopes.then(|| &mut slopes[at]),
        );
    }
    let (values, slopes) = (&*values, &*slopes);
    let d = |order: usize| &values[order * n..][..n];
    let dd = |order: usize| &slopes[order * n..][..n];
    // `(Σ A·D, Σ A·∂D/∂β, Σ ∂A/∂σ·D)` of one attenuation line pair and one order's detectors.
    let term = |c: usize, line: usize, order: usize| Grad {
        v: dot(held.line(c, line), d(order)),
        beta_n: if with_slopes {
            dot(held.line(c, line), dd(order))
        } else {
            0.0
        },
        sigma_a: if wanted.sigma_a {
            dot(held.line(c, line + 1), d(order))
        } else {
            0.0
        },
    };
    if on.has(0) {
        let r = Grad {
            v: dot(&held.fresnel, d(0)),
            beta_n: if with_slopes {
                dot(&held.fresnel, dd(0))
            } else {
                0.0
            },
            sigma_a: 0.0,
        };
        for o in out.iter_mut() {
            o[0] = r;
        }
    }
    for (c, o) in out.iter_mut().enumerate() {
        if on.has(1) {
            o[1] = term(c, A1, 1);
        }
        if on.has(2) {
            o[2] = term(c, A2, 2);
        }
        if on.has(RESIDUAL) {
            let mut r = Grad::default();
            for order in RESIDUAL..held.orders {
                let t = term(c, CHAIN + 2 * (order - RESIDUAL), order);
                r.v += t.v;
                r.beta_n += t.beta_n;
                r.sigma_a += t.sigma_a;
            }
            let (tail, d_tail) = held.tail_sums[c];
            r.v += tail;
            if wanted.sigma_a {
                r.sigma_a += d_tail;
            }
            o[RESIDUAL] = r;
        }
    }
    held.detectors.set(detectors);
}

/// `Σ aᵢbᵢ` in eight running sums (which the compiler keeps in vector registers), added up at
/// the end: the same bits on every CPU.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut sums = [0.0; 8];
    let (a8, b8) = (a.chunks_exact(8), b.chunks_exact(8));
    let (ra, rb) = (a8.remainder(), b8.remainder());
    for (x, y) in a8.zip(b8) {
        for l in 0..8 {
            sums[l] += x[l] * y[l];
        }
    }
    for (l, (x, y)) in ra.iter().zip(rb).enumerate() {
        sums[l] += x * y;
    }
    sums.iter().sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::families::deon::{azimuthal_angles, ETA};
    use crate::families::table::zero_terms;
    use crate::geometry::Angles;
    use nalgebra::{Const, U1};
    use num_dual::{Derivative, DualVec64};

    /// The hand derivatives against dual numbers seeded in β_N and σ_a (one slot each, every
    /// channel's σ_a in the second), over directions, widths and term sets; the values to the
    /// bit against the value pass's loop, and to 1e-14 against the number type's in libm.
    #[test]
    fn hand_derivatives_match_dual_numbers() {
        type D2 = DualVec64<Const<2>>;
        let seed = |x: f64, j: usize| D2::new(x, Derivative::derivative_generic(Const::<2>, U1, j));
        for (beta_n_deg, sigma) in [
            (5.0, [0.05, 0.4, 1.9]),
            (15.0, [0.0, 0.7, 3.0]),
            (60.0, [0.2; 3]),
        ] {
            let mut p = TableParams::<f64> {
                values: vec![
                    vec![1.55],
                    sigma.to_vec(),
                    vec![0.12],
                    vec![0.0],
                    vec![-0.05],
                ],
                n_channels: 3,
            };
            p.values[BETA_N][0] = f64::to_radians(beta_n_deg);
            let pd = TableParams::<D2> {
                values: vec![
                    vec![D2::from_re(1.55)],
                    sigma.iter().map(|&s| seed(s, 1)).collect(),
                    vec![D2::from_re(0.12)],
                    vec![seed(p.values[BETA_N][0], 0)],
                    vec![D2::from_re(-0.05)],
                ],
                n_channels: 3,
            };
            let how = Integration::standard(p.values[BETA_N][0]);
            let pass = DualPass {
                screening: false,
                seeded: 1 << BETA_N | 1 << SIGMA_A,
            };
            for on in [TermSet::all(4), TermSet(0b0110), TermSet(0b1000)] {
                for (ti, tr, phi) in [(10.0, 30.0, 0.0), (-40.0, 20.0, 170.0), (5.0, 5.0, -60.0)] {
                    let a = Angles::from_degrees(ti, 0.0, tr, phi);
                    let mut dual = zero_terms::<D2>(3);
                    super::super::add_azimuthal(&pd, &a, on, &how, &mut dual);
                    let mut hand = zero_terms::<D2>(3);
                    let (theta_d, phi) = azimuthal_angles(&a);
                    let held = Held::new(p.values[ETA][0], &sigma, theta_d, &how);
                    add_azimuthal(&pd, &held, phi, on, pass, &mut hand);
                    let values_only = DualPass {
                        screening: false,
                        seeded: 0,
                    };
                    let mut plain = zero_terms::<f64>(3);
                    add_azimuthal(&p, &held, phi, on, values_only, &mut plain);
                    let mut generic = zero_terms::<f64>(3);
                    super::super::add_azimuthal(&p, &a, on, &how, &mut generic);
                    for c in 0..3 {
                        for k in 0..=RESIDUAL {
                            assert_eq!(hand[c][k].re.to_bits(), plain[c][k].to_bits());
                            // The lanes' exp against libm's: a few ulp of each node's terms.
                            let (v, g) = (plain[c][k], generic[c][k]);
                            assert!((v - g).abs() <= 1e-14 * g.abs(), "{v} vs {g}");
                            let e = |x: &D2| x.eps.unwrap_generic(Const::<2>, U1);
                            let (h, d) = (e(&hand[c][k]), e(&dual[c][k]));
                            for j in 0..2 {
                                let tol = 1e-12 * d[j].abs().max(1e-6 * plain[c][k].abs());
                                assert!(
                                    (h[j] - d[j]).abs() <= tol,
                                    "β_N {beta_n_deg}, {a:?}, c {c}, term {k}, slot {j}: {} vs {}",
                                    h[j],
                                    d[j]
                                );
                            }
                        }
                    }
                }
            }
        }
    }
}
