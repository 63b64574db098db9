//! d'Eon's width integral in a gradient pass. The integral reads only η, β_N and σ_a; with η
//! held (the default) its derivatives are taken by hand in `f64` — ∂/∂β_N of the wrapped
//! Gaussian, ∂/∂σ_a of the transmittance carried through the attenuations — and chained into
//! the pass's duals as `N + ∂N/∂β_N·dβ_N + ∂N/∂σ_a·dσ_a`. Dual numbers spent most of the fit's
//! time here, on derivative parts (α, β_R) the integral never touches. The values are the
//! very expressions of [`super::add_azimuthal`], so they keep its bits. Everything of a node
//! but the detector depends on θ_d alone; it is built once per θ_d ([`Held`]).

use std::f64::consts::{PI, TAU};

use num_dual::DualNum;

use super::{Integration, WrappedGaussian, BETA_N, IMAGES, NEGLIGIBLE_EXPONENT, RESIDUAL, SIGMA_A};
use crate::families::shared::cylinder::{
    attenuations, exit_azimuth, fresnel, transmittance, ExitRefraction,
};
use crate::families::table::{DualPass, TableParams, TermSet, Terms};
use crate::geometry::angles::wrap_t;

/// A value and its derivatives in β_N and in the channel's own σ_a.
#[derive(Debug, Clone, Copy, Default)]
struct Grad {
    v: f64,
    beta_n: f64,
    sigma_a: f64,
}

/// [`super::add_azimuthal`] in a gradient pass that holds η, at one `(θ_d, φ)` whose θ_d part
/// is `held`: the integral by hand in `f64`, chained into the pass's duals.
pub(super) fn add_azimuthal<T: DualNum<f64>>(
    p: &TableParams<T>,
    held: &Held,
    phi: f64,
    on: TermSet,
    how: &Integration,
    pass: DualPass,
    out: &mut [Terms<T>],
) {
    let beta_n = p.get(BETA_N, 0);
    let mut n = vec![[Grad::default(); RESIDUAL + 1]; p.n_channels];
    width_integral(held, beta_n.re(), phi, on, how, &mut n);
    // dx: a line's derivative parts in `T` (real part exactly 0), where the pass seeds it.
    let d_beta = pass.seeds(BETA_N).then(|| beta_n.clone() - beta_n.re());
    for (c, (o, n)) in out.iter_mut().zip(&n).enumerate() {
        let s = p.get(SIGMA_A, c);
        let d_sigma = pass.seeds(SIGMA_A).then(|| s.clone() - s.re());
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
}

/// `D(x)` as [`WrappedGaussian::at`] and `∂D/∂β = (norm/β)·Σ_k g_k (x_k²/β² − 1)`.
fn detector(g: &WrappedGaussian<f64>, beta: f64, x: f64) -> (f64, f64) {
    let x = wrap_t(x);
    let h = g.half_inv_variance;
    let central = x.powi(2) * h;
    let mut sum = (-central).exp();
    let mut moment = sum * x.powi(2);
    for k in IMAGES {
        let xk = x + TAU * k;
        let exponent = xk.powi(2) * h;
        if exponent - central < NEGLIGIBLE_EXPONENT {
            let e = (-exponent).exp();
            sum += e;
            moment += e * xk.powi(2);
        }
    }
    // h = 1/(2β²): ∂(−x²h)/∂β = 2h·x²/β, and ∂norm/∂β = −norm/β.
    (sum * g.norm, g.norm / beta * (2.0 * h * moment - sum))
}

/// The part of the width integral a gradient pass holds fixed at one θ_d: per node the Fresnel
/// value, the exit azimuths and, per channel, the attenuations with their ∂/∂σ_a. It reads
/// η, σ_a and θ_d only — never φ or β_N — so the pass builds it once per θ_d and reuses it for
/// every φ there (the demo: 35 θ_d for 1,260 (θ_d, φ) pairs). Each entry is the expression the
/// per-pair loop computed, so the sums keep their bits. Size: nodes·(1 + orders + channels·
/// (7 + 2·(orders − 3))) f64, ≤ 128·32·8 B ≈ 33 kB for three channels, one θ_d at a time.
pub(super) struct Held {
    /// `Φ_p(h)` of orders 0..=highest, node-major.
    exits: Vec<f64>,
    /// `F(h)` per node.
    fresnel: Vec<f64>,
    /// Per node, per channel (node-major).
    attenuated: Vec<Attenuated>,
    /// `(A_p, ∂A_p/∂σ_a)` of p = 3..=highest per node and channel, in that order.
    chain: Vec<(f64, f64)>,
    orders: usize,
    n_channels: usize,
}

/// One channel's attenuations at one node: `(value, ∂/∂σ_a)` pairs.
#[derive(Debug, Clone, Copy)]
struct Attenuated {
    a1: (f64, f64),
    a2: (f64, f64),
    /// The geometric tail `A_P·TF/(1 − TF)·w/(2π)` and its ∂/∂σ_a (`None` where TF = 1).
    tail: Option<(f64, f64)>,
}

impl Held {
    /// The fixed part at `theta_d` for orders 0..=max(`how.highest_order`, 3).
    pub(super) fn new(eta: f64, sigma_a: &[f64], theta_d: f64, how: &Integration) -> Held {
        let refraction = ExitRefraction::new(&eta, theta_d);
        let inv_eta_prime = refraction.eta_prime.recip();
        let two_over_cos_theta_t = refraction.cos_theta_t.recip() * 2.0;
        let orders = how.highest_order.max(RESIDUAL) + 1;
        let n = how.rule.nodes.len();
        let mut held = Held {
            exits: Vec::with_capacity(n * orders),
            fresnel: Vec::with_capacity(n),
            attenuated: Vec::with_capacity(n * sigma_a.len()),
            chain: Vec::with_capacity(n * sigma_a.len() * (orders - RESIDUAL)),
            orders,
            n_channels: sigma_a.len(),
        };
        for node in &how.rule.nodes {
            let f = fresnel(&eta, refraction.cos_theta_r * node.cos_gamma);
            let sin_gamma_t = inv_eta_prime * node.h;
            let gamma_t = sin_gamma_t.asin();
            held.fresnel.push(f);
            held.exits
                .extend((0..orders).map(|p| exit_azimuth(p, node.gamma, &gamma_t)));
            let chord = (-sin_gamma_t.powi(2) + 1.0).sqrt() * two_over_cos_theta_t;
            for s in sigma_a {
                let a = attenuate(f, s, chord, orders, node.weight, &mut held.chain);
                held.attenuated.push(a);
            }
        }
        held
    }
}

/// One channel's [`Attenuated`] at a node, pushing its `A_p` chain onto `chain`.
fn attenuate(
    f: f64,
    s: &f64,
    chord: f64,
    orders: usize,
    weight: f64,
    chain: &mut Vec<(f64, f64)>,
) -> Attenuated {
    let t = transmittance(s, &chord);
    let [_, a1, a2, _] = attenuations(&f, &t);
    // ∂/∂σ_a: T' = −chord·T, A₁' = (1−F)²T', (TF)' = T'F, A₂' = A₁'TF + A₁(TF)'.
    let dt = -chord * t;
    let tf = t * f;
    let dtf = dt * f;
    let da1 = (-f + 1.0).powi(2) * dt;
    let da2 = da1 * tf + a1 * dtf;
    let (mut a_p, mut da_p) = (a2, da2);
    for _ in RESIDUAL..orders {
        da_p = da_p * tf + a_p * dtf;
        a_p *= tf;
        chain.push((a_p, da_p));
    }
    let one_minus = -tf + 1.0;
    // The tail A_P·TF/(1 − TF): (uv/q)' = (u'v + uv')/q + uv·v'/q² with q' = −v'.
    let tail = (one_minus != 0.0).then(|| {
        let w = weight / (2.0 * PI);
        let tail = (da_p * tf + a_p * dtf) / one_minus + a_p * tf * dtf / one_minus.powi(2);
        (a_p * tf / one_minus * w, tail * w)
    });
    Attenuated {
        a1: (a1, da1),
        a2: (a2, da2),
        tail,
    }
}

/// [`super::add_azimuthal`]'s loop in `f64` with its derivatives in β_N and σ_a, the θ_d part
/// from `held`.
fn width_integral(
    held: &Held,
    beta_n: f64,
    phi: f64,
    on: TermSet,
    how: &Integration,
    out: &mut [[Grad; RESIDUAL + 1]],
) {
    let gaussian = WrappedGaussian::new(&beta_n);
    let highest = if on.has(RESIDUAL) {
        how.highest_order.max(RESIDUAL)
    } else {
        2
    };
    let transmitted = (1..=RESIDUAL).any(|k| on.has(k));
    let n_chain = held.orders - RESIDUAL;
    // Weighted detectors per order: (value, ∂/∂β_N).
    let mut d = vec![(0.0, 0.0); highest + 1];
    for (i, node) in how.rule.nodes.iter().enumerate() {
        let f = held.fresnel[i];
        let exits = &held.exits[i * held.orders..];
        for (order, d) in d.iter_mut().enumerate() {
            if on.has(order.min(RESIDUAL)) {
                let (v, dv) = detector(&gaussian, beta_n, -exits[order] + phi);
                *d = (v * node.weight, dv * node.weight);
            }
        }
        if on.has(0) {
            for o in out.iter_mut() {
                o[0].v += f * d[0].0;
                o[0].beta_n += f * d[0].1;
            }
        }
        if !transmitted {
            continue;
        }
        let first = i * held.n_channels;
        for (c, o) in out.iter_mut().enumerate() {
            let at = &held.attenuated[first + c];
            if on.has(1) {
                add(&mut o[1], at.a1, d[1]);
            }
            if on.has(2) {
                add(&mut o[2], at.a2, d[2]);
            }
            if on.has(RESIDUAL) {
                let chain = &held.chain[(first + c) * n_chain..][..n_chain];
                let r = higher_orders(chain, at.tail, &d[3..]);
                o[RESIDUAL].v += r.v;
                o[RESIDUAL].beta_n += r.beta_n;
                o[RESIDUAL].sigma_a += r.sigma_a;
            }
        }
    }
}

/// `o += A·D` with `A = (value, ∂/∂σ_a)` and `D = (value, ∂/∂β_N)`.
fn add(o: &mut Grad, (a, da): (f64, f64), (d, dd): (f64, f64)) {
    o.v += a * d;
    o.beta_n += a * dd;
    o.sigma_a += da * d;
}

/// [`super::higher_orders`] with its derivatives: `chain` holds `(A_p, ∂A_p/∂σ_a)` of
/// p = 3..=P, `tail` the geometric tail; the detectors carry ∂/∂β_N.
fn higher_orders(
    chain: &[(f64, f64)],
    tail: Option<(f64, f64)>,
    weighted_d: &[(f64, f64)],
) -> Grad {
    let mut sum = Grad::default();
    for (&(a_p, da_p), &(d, dd)) in chain.iter().zip(weighted_d) {
        sum.v += a_p * d;
        sum.beta_n += a_p * dd;
        sum.sigma_a += da_p * d;
    }
    let Some((v, ds)) = tail else {
        return sum;
    };
    Grad {
        v: sum.v + v,
        beta_n: sum.beta_n,
        sigma_a: sum.sigma_a + ds,
    }
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
    /// channel's σ_a in the second), over directions, widths and term sets; the values to the bit.
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
                    add_azimuthal(&pd, &held, phi, on, &how, pass, &mut hand);
                    let mut plain = zero_terms::<f64>(3);
                    super::super::add_azimuthal(&p, &a, on, &how, &mut plain);
                    for c in 0..3 {
                        for k in 0..=RESIDUAL {
                            assert_eq!(hand[c][k].re.to_bits(), plain[c][k].to_bits());
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
