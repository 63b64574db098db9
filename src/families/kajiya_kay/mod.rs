//! Kajiya & Kay 1989 ("Rendering fur with three dimensional textures", §4): a fibre as a thin
//! cylinder with a diffuse term `K_d sin(t, l)` and a specular term
//! `K_s cos^p(angle from the mirror cone)`, no azimuthal structure. In MODEL.md's angles the
//! tangent components are `t·l = sin θ_i`, `sin(t, l) = cos θ_i`, and the mirror cone around
//! the fibre is `θ_r = −θ_i`, so the cone's angle to the viewer is `θ_i + θ_r` and
//!
//! `S·cos θ_i = K_d cos θ_i + K_s max(0, cos(θ_i + θ_r))^p`.
//!
//! Kajiya–Kay's shading value is the radiance under a unit light, so it is `S·cos θ_i` here
//! (docs/kajiya-kay.md). The per-channel scale of a fit is the light's colour times `K_s`, so
//! `k_s` stays at 1 and `k_d` is the diffuse-to-specular ratio.

use num_dual::DualNum;

use crate::families::table::{
    LobeColumn, ParamFact, TableFamily, TableParams, Term, TermSet, Terms,
};
use crate::geometry::Angles;
use crate::geometry::{Fitted, Interval, Unit};

/// The Kajiya–Kay family.
pub struct KajiyaKay;

/// Table lines (indices into [`KajiyaKay::PARAMETERS`]).
const K_D: usize = 0;
const K_S: usize = 1;
const EXPONENT: usize = 2;

/// Term indices (into [`KajiyaKay::TERMS`]).
const DIFFUSE: usize = 0;
const SPECULAR: usize = 1;

/// `K_d cos θ_i / cos θ_i = K_d`: the diffuse term of `S` (Kajiya–Kay eq. for Ψ_d).
pub fn diffuse<T: DualNum<f64>>(k_d: &T) -> T {
    k_d.clone()
}

/// `cos(θ_i + θ_r)`, the cosine of the viewer's angle from the mirror cone, clamped at 0 (the
/// far side of the cone does not light up).
pub fn cone_cosine(theta_i: f64, theta_r: f64) -> f64 {
    (theta_i + theta_r).cos().max(0.0)
}

/// `K_s cos^p / cos θ_i`: the specular term of `S` (Kajiya–Kay eq. for Ψ_s, divided by the
/// incidence cosine that turns radiance into `S`). `cos^p` as `exp(p ln cos)` so its
/// derivative in `p` is exact; 0 where the cosine is 0.
pub fn specular<T: DualNum<f64>>(k_s: &T, exponent: &T, cone_cos: f64, cos_theta_i: f64) -> T {
    if cone_cos <= 0.0 {
        return T::zero();
    }
    k_s.clone() * (exponent.clone() * cone_cos.ln()).exp() / cos_theta_i
}

impl TableFamily for KajiyaKay {
    const NAME: &'static str = "kajiya-kay";
    const TITLE: &'static str = "Kajiya-Kay 1989";
    const FIX_EXAMPLE: &'static str = "exponent=80 or --fix k_d=0.2";
    const TERMS: &'static [Term] = &[
        Term {
            name: "diffuse",
            meaning: "K_d: light scattered evenly, the fibre's colour",
            column: LobeColumn::TRT,
        },
        Term {
            name: "specular",
            meaning: "K_s cos^p: the highlight on the mirror cone",
            column: LobeColumn::R,
        },
    ];
    const PARAMETERS: &'static [ParamFact] = &[
        ParamFact {
            name: "k_d",
            symbol: "K_d",
            meaning: "diffuse coefficient, one per colour channel (relative to K_s)",
            unit: Unit::Dimensionless,
            per_channel: true,
            domain: Interval::closed_open(0.0, f64::INFINITY),
            fit_lo: 0.0,
            fit_hi: Some(100.0),
            typical: (0.01, 1.0),
            reference: Some(0.3),
            fitted: Fitted::Yes,
            terms: &["diffuse"],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "k_s",
            symbol: "K_s",
            meaning: "specular coefficient (the fit's per-channel scale absorbs it)",
            unit: Unit::Dimensionless,
            per_channel: false,
            domain: Interval::closed_open(0.0, f64::INFINITY),
            fit_lo: 0.0,
            fit_hi: Some(100.0),
            typical: (0.5, 2.0),
            reference: Some(1.0),
            fitted: Fitted::No,
            terms: &["specular"],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "exponent",
            symbol: "p",
            meaning: "specular exponent (larger: a narrower highlight)",
            unit: Unit::Dimensionless,
            per_channel: false,
            domain: Interval::open(0.0, 1.0e6),
            fit_lo: 0.5,
            fit_hi: Some(5000.0),
            typical: (10.0, 200.0),
            reference: Some(50.0),
            fitted: Fitted::Yes,
            terms: &["specular"],
            ..ParamFact::BASE
        },
    ];

    fn scatter<T: DualNum<f64>>(p: &TableParams<T>, a: &Angles, on: TermSet, out: &mut [Terms<T>]) {
        let cos_i = a.theta_i.cos();
        let cone = cone_cosine(a.theta_i, a.theta_r);
        let spec = on
            .has(SPECULAR)
            .then(|| specular(&p.get(K_S, 0), &p.get(EXPONENT, 0), cone, cos_i));
        for (c, o) in out.iter_mut().enumerate() {
            if let Some(s) = &spec {
                o[SPECULAR] = s.clone();
            }
            if on.has(DIFFUSE) {
                o[DIFFUSE] = diffuse(&p.get(K_D, c));
            }
        }
    }
}
