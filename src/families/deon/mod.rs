//! d'Eon, Francois, Hill, Letteri & Aubry 2011, "An Energy-Conserving Hair Reflectance Model"
//! (EGSR 2011), as a table family (docs/deon.md): per order p a longitudinal lobe `M_p` (the
//! paper's Eq. 7, the same function Chiang 2016 uses) times an azimuthal lobe
//! `N_p(φ) = ½∫₋₁¹ A_p(h) D(φ − Φ_p(h)) dh` whose detector `D` is a Gaussian wrapped around the
//! circle (Eqs. 10–11). This module owns the family's table, the wrapped Gaussian and the
//! h-integral; `M_p`, Fresnel, `A_p`, `Φ_p` and the Gauss–Legendre rule are `crate::families::shared`'s.
//!
//! The lobe sum is what a renderer multiplies by the light's irradiance (the paper's `f`, no
//! `1/cos²θ_d`), so `S = Σ_p M_p N_p / cos θ_i`.

use std::f64::consts::{PI, TAU};
use std::sync::{Arc, OnceLock};

use num_dual::DualNum;

mod detector;
mod held;

use crate::families::shared::cylinder::{
    attenuations, exit_azimuth, fresnel, transmittance, ExitRefraction,
};
use crate::families::shared::longitudinal::{lobe_variance, longitudinal_lobe, rotated_exit};
use crate::families::shared::quadrature::WidthRule;
use crate::families::table::{
    clear_terms, zero_terms, DualPass, LobeColumn, ParamFact, TableFamily, TableParams, Term,
    TermSet, Terms,
};
use crate::geometry::angles::{wrap, wrap_t};
use crate::geometry::Angles;
use crate::geometry::{Fitted, Interval, Unit};

/// The d'Eon 2011 family.
pub struct DEon;

/// Table lines (indices into [`DEon::PARAMETERS`]).
const ETA: usize = 0;
const SIGMA_A: usize = 1;
const BETA_R: usize = 2;
const BETA_N: usize = 3;
const ALPHA: usize = 4;

/// Term indices (into [`DEon::TERMS`]); terms 0–2 are the orders p = 0, 1, 2.
const RESIDUAL: usize = 3;

/// Gauss–Legendre node counts in γ = asin h of the h-integral, one picked per β_N: the fewest
/// with `nodes·β_N ≥ NODES_TIMES_WIDTH_DEG` (degrees), else the last. A narrow detector is a
/// narrow peak in h; docs/deon.md "Width quadrature" measures the rule at worst 1.5e-7 relative
/// to 1024 nodes for β_N ≥ 5° (the fit's bound).
pub const NODE_COUNTS: [usize; 6] = [48, 64, 80, 96, 112, 128];

/// The product of node count and β_N (in degrees) each count must reach.
pub const NODES_TIMES_WIDTH_DEG: f64 = 640.0;

/// The highest order the residual term integrates with its own exit azimuth; the orders above it
/// are spread evenly over φ (their `Φ_p` sweeps the circle several times across the fibre).
pub const HIGHEST_EXPLICIT_ORDER: usize = 3;

/// Rotation of θ_r per term in units of α, `θ' = θ_r + EXIT_TILT[k]·α`: the lobes sit at
/// θ_h = α, −α/2, −3α/2 (Marschner's pattern, which d'Eon keeps); the residual is untilted.
pub const EXIT_TILT: [f64; 4] = [-2.0, 1.0, 3.0, 0.0];

/// How the azimuthal integral is taken: the Gauss–Legendre rule in γ and the highest order the
/// residual term integrates with its own exit azimuth.
#[derive(Debug, Clone, Copy)]
pub struct Integration<'a> {
    pub rule: &'a WidthRule,
    pub highest_order: usize,
}

impl Integration<'static> {
    /// The family's own: the rule of [`nodes_for`] `beta_n` (radians; each built once per
    /// process) and [`HIGHEST_EXPLICIT_ORDER`].
    pub fn standard(beta_n: f64) -> Integration<'static> {
        Self::with_nodes(nodes_for(beta_n), 1)
    }

    /// The multi-start's screening rule: half the nodes of [`Integration::standard`] (basins,
    /// not values: the polish and everything reported use the standard rule).
    pub fn screening(beta_n: f64) -> Integration<'static> {
        Self::with_nodes(nodes_for(beta_n), 2)
    }

    /// The rule of `n / divisor` nodes, `n` one of [`NODE_COUNTS`] and `divisor` 1 or 2.
    fn with_nodes(n: usize, divisor: usize) -> Integration<'static> {
        static RULES: [[OnceLock<Arc<WidthRule>>; NODE_COUNTS.len()]; 2] =
            [const { [const { OnceLock::new() }; NODE_COUNTS.len()] }; 2];
        let k = NODE_COUNTS
            .iter()
            .position(|&c| c == n)
            .expect("one of NODE_COUNTS");
        let rule =
            RULES[divisor - 1][k].get_or_init(|| WidthRule::cached(n / divisor).expect("in range"));
        Integration {
            rule,
            highest_order: HIGHEST_EXPLICIT_ORDER,
        }
    }
}

/// The node count for detector width `beta_n` (radians): see [`NODE_COUNTS`].
pub fn nodes_for(beta_n: f64) -> usize {
    let width_deg = beta_n.to_degrees();
    let last = NODE_COUNTS[NODE_COUNTS.len() - 1];
    NODE_COUNTS
        .into_iter()
        .find(|&n| n as f64 * width_deg >= NODES_TIMES_WIDTH_DEG)
        .unwrap_or(last)
}

/// `v_R = (2β_R)²`: d'Eon's variance whose lobe has the θ_h width β_R of Marschner's Gaussian
/// (at small v the lobe's standard deviation is √v in θ_r at fixed θ_i, half that in θ_h).
#[inline]
pub fn variance_r<T: DualNum<f64>>(beta_r: &T) -> T {
    (beta_r.clone() * 2.0).powi(2)
}

/// `M_k(θ_i, θ_r)` of term k: d'Eon's lobe with variance `v_R·(1, ¼, 4, 4)_k` at the exit
/// inclination rotated by [`EXIT_TILT`].
#[inline]
pub fn longitudinal<T: DualNum<f64>>(
    k: usize,
    theta_i: f64,
    theta_r: f64,
    alpha: &T,
    v_r: &T,
) -> T {
    let (sin_i, cos_i) = theta_i.sin_cos();
    let (sin_e, cos_e) = rotated_exit(theta_r, alpha, EXIT_TILT[k]);
    longitudinal_lobe(sin_i, cos_i, &sin_e, &cos_e, &lobe_variance(k, v_r))
}

/// Images of the wrapped Gaussian beside the one at the wrapped offset (which is always summed).
const IMAGES: [f64; 4] = [-1.0, 1.0, -2.0, 2.0];

/// An image whose exponent exceeds the central one's by more than this adds < 4e-18 of `D` and
/// is skipped (the sum then moves by less than its own rounding).
const NEGLIGIBLE_EXPONENT: f64 = 40.0;

/// The detector `D(x) = Σ_k g(x + 2πk; β_N)`, `g` the normal density: a Gaussian of standard
/// deviation β_N wrapped around the circle, with unit integral over one turn.
#[derive(Debug, Clone)]
pub struct WrappedGaussian<T> {
    half_inv_variance: T,
    norm: T,
}

impl<T: DualNum<f64>> WrappedGaussian<T> {
    /// `1/(2β²)` and `1/(β√(2π))` of width `beta`.
    pub fn new(beta: &T) -> Self {
        const INV_SQRT_TAU: f64 = 0.398_942_280_401_432_7;
        WrappedGaussian {
            half_inv_variance: beta.powi(2).recip() * 0.5,
            norm: beta.recip() * INV_SQRT_TAU,
        }
    }

    /// `D(x)` for any `x` (wrapped to (−π, π] first). Images k = 0, ±1, ±2 cover every width up to
    /// 90°: the first one left out, |k| = 3, is ≥ 5π from x against ≤ π for k = 0, e^{−48} of `D`.
    pub fn at(&self, x: &T) -> T {
        let x = wrap_t(x.clone());
        let central = x.powi(2) * self.half_inv_variance.clone();
        let mut sum = (-central.clone()).exp();
        for k in IMAGES {
            let exponent = (x.clone() + TAU * k).powi(2) * self.half_inv_variance.clone();
            if exponent.re() - central.re() < NEGLIGIBLE_EXPONENT {
                sum += (-exponent).exp();
            }
        }
        sum * self.norm.clone()
    }
}

/// Adds the width integral `N_k = ½∫₋₁¹ A_k(h) D(φ − Φ_k(h)) dh` of every term `on` to
/// `out[c][k]` for the directions `a`, integrated as `how` says. Per node: one Fresnel, one
/// `asin`, one detector per order (all channel independent), then per channel one `exp` for
/// `T`. The residual adds `Σ_{3≤p≤P} A_p D(φ − Φ_p)` and the orders above P as
/// `Σ_{p>P} A_p/(2π)`. Passes whose η carries a derivative take it here; every other pass
/// takes [`held`]'s `f64` loop: the same rule, its detectors on the lanes and its node sums
/// as dot products (within 1e-14 of this one).
pub fn add_azimuthal<T: DualNum<f64>>(
    p: &TableParams<T>,
    a: &Angles,
    on: TermSet,
    how: &Integration,
    out: &mut [Terms<T>],
) {
    let eta = p.get(ETA, 0);
    let theta_d = 0.5 * (a.theta_r - a.theta_i);
    let phi = wrap(a.phi_r - a.phi_i);
    // η' and cos θ_t from θ_d (not from one of the two angles), so f stays reciprocal.
    let refraction = ExitRefraction::new(&eta, theta_d);
    let inv_eta_prime = refraction.eta_prime.recip();
    let two_over_cos_theta_t = refraction.cos_theta_t.recip() * 2.0;
    let detector = WrappedGaussian::new(&p.get(BETA_N, 0));
    let highest = if on.has(RESIDUAL) {
        how.highest_order.max(RESIDUAL)
    } else {
        2
    };
    let transmitted = (1..=RESIDUAL).any(|k| on.has(k));
    let sigma_a: Vec<T> = (0..p.n_channels).map(|c| p.get(SIGMA_A, c)).collect();
    let mut d = vec![T::zero(); highest + 1];
    for node in &how.rule.nodes {
        let f = fresnel(&eta, refraction.cos_theta_r * node.cos_gamma);
        let sin_gamma_t = inv_eta_prime.clone() * node.h;
        let gamma_t = sin_gamma_t.clone().asin();
        for (order, d) in d.iter_mut().enumerate() {
            // Orders 0–2 are terms of their own; every order from 3 up is the residual's.
            if on.has(order.min(RESIDUAL)) {
                let exit = exit_azimuth(order, node.gamma, &gamma_t);
                *d = detector.at(&(-exit + phi)) * node.weight;
            }
        }
        if on.has(0) {
            let r = f.clone() * d[0].clone();
            for o in out.iter_mut() {
                o[0] += r.clone();
            }
        }
        if !transmitted {
            continue;
        }
        let chord = (-sin_gamma_t.powi(2) + 1.0).sqrt() * two_over_cos_theta_t.clone();
        for (o, s) in out.iter_mut().zip(&sigma_a) {
            let t = transmittance(s, &chord);
            let [_, a1, a2, _] = attenuations(&f, &t);
            if on.has(1) {
                o[1] += a1 * d[1].clone();
            }
            if on.has(2) {
                o[2] += a2.clone() * d[2].clone();
            }
            if on.has(RESIDUAL) {
                o[RESIDUAL] += higher_orders(a2, &(t * f.clone()), &d[3..], node.weight);
            }
        }
    }
}

/// `Σ_{p=3}^{P} A_p D_p + w·Σ_{p>P} A_p/(2π)` at one node, with `A_p = A₂(TF)^{p−2}`, the
/// weighted detectors `D_p` of p = 3..=P in `weighted_d` and the node weight `w`; the tail is
/// the geometric series `A_P·TF/(1 − TF)` (0 where TF = 1, as in `chiang::azimuthal`).
pub fn higher_orders<T: DualNum<f64>>(a2: T, tf: &T, weighted_d: &[T], weight: f64) -> T {
    let mut a_p = a2;
    let mut sum = T::zero();
    for d in weighted_d {
        a_p *= tf.clone();
        sum += a_p.clone() * d.clone();
    }
    let one_minus = -tf.clone() + 1.0;
    if one_minus.re() == 0.0 {
        return sum;
    }
    sum + a_p * tf.clone() / one_minus * (weight / (2.0 * PI))
}

/// `S` term by term, the azimuthal integral taken as `how` says (the family's `scatter` uses
/// [`Integration::standard`]).
pub fn scatter_with<T: DualNum<f64>>(
    p: &TableParams<T>,
    a: &Angles,
    on: TermSet,
    how: &Integration,
    out: &mut [Terms<T>],
) {
    add_width_integral(p, a, &held_part(p, a, how), on, how, None, out);
    apply_longitudinal(p, a, on, out);
}

/// The width integral's θ_d part at `a` for the values of `p`.
fn held_part<T: DualNum<f64>>(p: &TableParams<T>, a: &Angles, how: &Integration) -> held::Held {
    let sigma_a: Vec<f64> = (0..p.n_channels).map(|c| p.get(SIGMA_A, c).re()).collect();
    held::Held::new(p.get(ETA, 0).re(), &sigma_a, azimuthal_angles(a).0, how)
}

/// Adds the width integral of every term `on` at `a` to `out`, `held` its θ_d part. Where η
/// carries no derivative (every value pass, and a gradient pass `pass` that does not seed it)
/// in `f64` with derivatives by hand ([`held::add_azimuthal`]); else in the number type
/// ([`add_azimuthal`]), its values then replaced by the `f64` loop's, so that every pass's
/// values are the value pass's bits.
fn add_width_integral<T: DualNum<f64>>(
    p: &TableParams<T>,
    a: &Angles,
    held: &held::Held,
    on: TermSet,
    how: &Integration,
    pass: Option<DualPass>,
    out: &mut [Terms<T>],
) {
    let phi = azimuthal_angles(a).1;
    let values_only = DualPass {
        screening: false,
        seeded: 0,
    };
    match pass {
        _ if T::NDERIV == 0 => held::add_azimuthal(p, held, phi, on, values_only, out),
        Some(pass) if !pass.seeds(ETA) => held::add_azimuthal(p, held, phi, on, pass, out),
        _ => {
            add_azimuthal(p, a, on, how, out);
            let mut values = zero_terms::<f64>(p.n_channels);
            held::add_azimuthal(&p.map(|x| x.re()), held, phi, on, values_only, &mut values);
            for (o, v) in out.iter_mut().zip(&values) {
                for (o, &v) in o.iter_mut().zip(v) {
                    *o = o.clone() - o.re() + v;
                }
            }
        }
    }
}

/// Multiply each term `on` of `out` (its width integral) by its longitudinal factor `M_k / cos θ_i`.
fn apply_longitudinal<T: DualNum<f64>>(
    p: &TableParams<T>,
    a: &Angles,
    on: TermSet,
    out: &mut [Terms<T>],
) {
    let v_r = variance_r(&p.get(BETA_R, 0));
    let v_r_value = variance_r(&p.get(BETA_R, 0).re());
    let alpha = p.get(ALPHA, 0);
    let inv_cos_i = a.theta_i.cos().recip();
    for k in (0..=RESIDUAL).filter(|&k| on.has(k)) {
        let mut m = longitudinal(k, a.theta_i, a.theta_r, &alpha, &v_r);
        if T::NDERIV > 0 {
            // The value part as the f64 pass computes it: a gradient pass's values are then
            // the value pass's bits (`cheap_gradients`).
            let re = longitudinal(k, a.theta_i, a.theta_r, &alpha.re(), &v_r_value);
            m = m.clone() - m.re() + re;
        }
        let m = m * inv_cos_i;
        for o in out.iter_mut() {
            o[k] *= m.clone();
        }
    }
}

impl TableFamily for DEon {
    const NAME: &'static str = "deon";
    const TITLE: &'static str = "d'Eon et al. 2011";
    const FIX_EXAMPLE: &'static str = "beta_n_deg=15 or --fix alpha_deg=-3";
    const TERMS: &'static [Term] = &[
        Term {
            name: "R",
            meaning: "p = 0: reflection at the surface",
            column: LobeColumn::R,
        },
        Term {
            name: "TT",
            meaning: "p = 1: transmission through the fibre",
            column: LobeColumn::TT,
        },
        Term {
            name: "TRT",
            meaning: "p = 2: one internal reflection",
            column: LobeColumn::TRT,
        },
        Term {
            name: "residual",
            meaning: "p >= 3 summed: TRRT with its own azimuth, higher orders even in phi",
            column: LobeColumn::TRT,
        },
    ];
    const PARAMETERS: &'static [ParamFact] = &[
        ParamFact {
            name: "eta",
            symbol: "η",
            meaning: "cortex index of refraction",
            unit: Unit::Dimensionless,
            per_channel: false,
            // As the Marschner and Chiang tables: refraction needs η > 1; 10 keeps η² finite.
            domain: Interval::open_closed(1.0, 10.0),
            fit_lo: 1.000001,
            fit_hi: Some(2.5),
            typical: (1.5, 1.6),
            reference: Some(1.55),
            fitted: Fitted::OnRequest,
            terms: &[],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "sigma_a",
            symbol: "σ_a",
            meaning: "absorption per unit fibre radius, one value per colour channel",
            unit: Unit::PerFiberRadius,
            per_channel: true,
            domain: Interval::closed_open(0.0, f64::INFINITY),
            // σ_a = 50 per radius already removes all transmitted light.
            fit_lo: 0.0,
            fit_hi: Some(50.0),
            typical: (0.05, 2.0),
            reference: Some(0.4),
            fitted: Fitted::Yes,
            terms: &["TT", "TRT", "residual"],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "beta_r_deg",
            symbol: "β_R",
            meaning: "longitudinal roughness: the R lobe's width in theta_h (v_R = (2 beta_R)^2)",
            unit: Unit::Degrees,
            per_channel: false,
            domain: Interval::open_closed(0.0, 90.0),
            fit_lo: 0.1,
            fit_hi: Some(30.0),
            typical: (4.0, 12.0),
            reference: Some(7.0),
            fitted: Fitted::Yes,
            terms: &[],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "beta_n_deg",
            symbol: "β_N",
            meaning: "azimuthal roughness: standard deviation of the wrapped Gaussian detector",
            unit: Unit::Degrees,
            per_channel: false,
            // Five images of the Gaussian are exact up to 90°; below 4° the width rule no
            // longer holds S to 1e-6 (docs/deon.md "Width quadrature"), 5° leaves a margin.
            domain: Interval::open_closed(0.0, 90.0),
            fit_lo: 5.0,
            fit_hi: Some(90.0),
            typical: (8.0, 30.0),
            reference: Some(15.0),
            fitted: Fitted::Yes,
            terms: &[],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "alpha_deg",
            symbol: "α",
            meaning: "cuticle-scale tilt; the R peak sits at theta_h = +alpha_deg",
            unit: Unit::Degrees,
            per_channel: false,
            domain: Interval::open(-90.0, 90.0),
            fit_lo: -30.0,
            fit_hi: Some(30.0),
            typical: (-6.0, -1.0),
            reference: Some(-3.0),
            fitted: Fitted::Yes,
            terms: &["R", "TT", "TRT"],
            ..ParamFact::BASE
        },
    ];

    fn scatter<T: DualNum<f64>>(p: &TableParams<T>, a: &Angles, on: TermSet, out: &mut [Terms<T>]) {
        // The node count is piecewise constant in β_N; at each step S moves by less than the
        // rule's error (≤ 2e-7 relative), far below anything a fit resolves.
        let how = Integration::standard(p.get(BETA_N, 0).re());
        scatter_with(p, a, on, &how, out);
    }

    /// The width integral depends on a sample only through (θ_d, φ), which a goniometer's
    /// samples share (the demo's 2,340 have 1,260 distinct pairs): it is taken once per pair,
    /// then each sample's longitudinal factors multiply a copy, so every value is the one
    /// [`DEon::scatter`] gives, bit for bit.
    fn scatter_each<T: DualNum<f64>>(
        p: &TableParams<T>,
        angles: &[Angles],
        on: TermSet,
        each: &mut dyn FnMut(usize, &[Terms<T>]),
    ) {
        let how = Integration::standard(p.get(BETA_N, 0).re());
        scatter_shared(p, angles, on, &how, None, each);
    }

    /// With η held a gradient pass's width integral is the value pass's f64 loop plus a few
    /// products per node (`held`), and its values are the value pass's bits.
    fn cheap_gradients(seeded: u32) -> bool {
        seeded & (1 << ETA) == 0
    }

    const SCREENING: Option<&'static str> = Some("with half the width nodes");

    fn screen_each<T: DualNum<f64>>(
        p: &TableParams<T>,
        angles: &[Angles],
        on: TermSet,
        each: &mut dyn FnMut(usize, &[Terms<T>]),
    ) {
        let how = Integration::screening(p.get(BETA_N, 0).re());
        scatter_shared(p, angles, on, &how, None, each);
    }

    /// [`DEon::scatter_each`] or `screen_each` with the width integral's derivatives taken by
    /// hand in `f64` where they can be ([`held::add_azimuthal`]).
    fn dual_each<T: DualNum<f64>>(
        p: &TableParams<T>,
        angles: &[Angles],
        on: TermSet,
        pass: DualPass,
        each: &mut dyn FnMut(usize, &[Terms<T>]),
    ) {
        let beta_n = p.get(BETA_N, 0).re();
        let how = if pass.screening {
            Integration::screening(beta_n)
        } else {
            Integration::standard(beta_n)
        };
        scatter_shared(p, angles, on, &how, Some(pass), each);
    }
}

/// [`DEon::scatter_each`] with the width integral taken as `how` says: once per (θ_d, φ), its
/// derivatives by hand when `pass` names a gradient pass's seeded lines.
fn scatter_shared<T: DualNum<f64>>(
    p: &TableParams<T>,
    angles: &[Angles],
    on: TermSet,
    how: &Integration,
    pass: Option<DualPass>,
    each: &mut dyn FnMut(usize, &[Terms<T>]),
) {
    let mut order: Vec<(AzimuthalKey, usize)> = angles
        .iter()
        .enumerate()
        .map(|(i, a)| (azimuthal_key(a), i))
        .collect();
    order.sort_unstable();
    let mut shared = zero_terms::<T>(p.n_channels);
    let mut terms = zero_terms::<T>(p.n_channels);
    // The integral's θ_d part (`held::Held`) is built once per θ_d: the sort puts each θ_d's
    // groups together.
    let mut held: Option<(u64, held::Held)> = None;
    for group in order.chunk_by(|x, y| x.0 == y.0) {
        clear_terms(&mut shared);
        let a = &angles[group[0].1];
        let key = group[0].0 .0;
        if held.as_ref().is_none_or(|h| h.0 != key) {
            held = Some((key, held_part(p, a, how)));
        }
        let (_, h) = held.as_ref().expect("just built");
        add_width_integral(p, a, h, on, how, pass, &mut shared);
        for &(_, i) in group {
            terms.clone_from_slice(&shared);
            apply_longitudinal(p, &angles[i], on, &mut terms);
            each(i, &terms);
        }
    }
}

/// What [`add_azimuthal`] reads of a sample: the bits of θ_d and of the wrapped φ.
type AzimuthalKey = (u64, u64);

fn azimuthal_key(a: &Angles) -> AzimuthalKey {
    let (theta_d, phi) = azimuthal_angles(a);
    (theta_d.to_bits(), phi.to_bits())
}

/// θ_d and the wrapped φ of a sample, as [`add_azimuthal`] computes them.
fn azimuthal_angles(a: &Angles) -> (f64, f64) {
    (0.5 * (a.theta_r - a.theta_i), wrap(a.phi_r - a.phi_i))
}
