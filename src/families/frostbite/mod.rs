//! The Frostbite 2019 hair model (Tafuri, "Strand-based Hair Rendering in Frostbite", SIGGRAPH
//! 2019 Advances in Real-Time Rendering) as its one public implementation evaluates it: the
//! Physical (Marschner) path of Unity HDRP's hair shader, which credits Tafuri 2019 with Chiang
//! 2016, Karis 2016, d'Eon 2011 and Marschner 2003 (docs/frostbite.md says which HDRP revision
//! and what could not be confirmed in Tafuri's slides). Per lobe p ∈ {R, TT, TRT}
//!
//! `S_p = M_p(θ_h) · A_p · N_p(φ, θ_d; β_N)`:
//!
//! a Gaussian in θ_h (Marschner's shifts and widths from Cuticle Angle and Smoothness), an
//! attenuation at one offset h per lobe (Schlick Fresnel, Beer's law along the chord), and the
//! azimuthal distribution integrated over the fibre width ([`azimuthal`]). HDRP's shader value is `S·cos θ_i`
//! (the light-facing cosine is applied after the lobes), so the lobes' sum is hairfit's `S`.
//! The parameters are the Unity artist's: Base Color (linear, per channel; absorption by
//! Chiang 2016 eq. 9 with β_N), Smoothness, Radial Smoothness, Cuticle Angle in degrees, and
//! η fixed at 1.55 as HDRP fixes it (`--free eta` moves only Fresnel and the refracted angle).

pub mod azimuthal;
pub mod export;
mod nodes;

use std::f64::consts::PI;

use num_dual::DualNum;

use crate::families::table::{
    LobeColumn, ParamFact, TableFamily, TableParams, Term, TermSet, Terms,
};
use crate::geometry::angles::wrap;
use crate::geometry::Angles;
use crate::geometry::{Fitted, Interval, Unit};
use azimuthal::{Logistic, BETA_N_MIN};

/// The Frostbite/HDRP family.
pub struct Frostbite;

/// Table lines (indices into [`Frostbite::PARAMETERS`]).
pub const BASE_COLOR: usize = 0;
pub const SMOOTHNESS: usize = 1;
pub const RADIAL_SMOOTHNESS: usize = 2;
pub const CUTICLE_ANGLE: usize = 3;
pub const ETA: usize = 4;

/// Term indices (into [`Frostbite::TERMS`]), also the lobe index p of [`azimuthal`].
const R: usize = 0;
const TT: usize = 1;
const TRT: usize = 2;

/// HDRP's largest Smoothness (it clamps above, "to prevent NaNs").
pub const SMOOTHNESS_MAX: f64 = 0.99;
/// The largest Radial Smoothness accepted (β_N ≥ [`BETA_N_MIN`]).
pub const RADIAL_SMOOTHNESS_MAX: f64 = 1.0 - BETA_N_MIN;
/// HDRP's smallest Base Color (it clamps below before taking the logarithm).
pub const BASE_COLOR_MIN: f64 = 1e-3;
/// The offset h at which TRT's attenuation is taken (HDRP: "√3/2"); TT's is h = 0.
pub const H_TRT: f64 = 0.866_025_403_784_438_6;

/// `exp(−x²/2σ²)/(√(2π)σ)`: the longitudinal lobe, a unit-area Gaussian in θ_h (Marschner 2003
/// eq. 4 as HDRP evaluates it; it integrates to 2 over θ_i at fixed θ_r).
pub fn gaussian<T: DualNum<f64>>(x: &T, sigma: &T) -> T {
    let z = x.clone() / sigma.clone();
    (-(z.clone() * z) * 0.5).exp() / (sigma.clone() * (2.0 * PI).sqrt())
}

/// The lobes' longitudinal standard deviations from the R width `r = 1 − Smoothness` (radians):
/// `r, r/2, 2r` (HDRP squares `r`, `r/2`, `2r` into variances).
pub fn lobe_widths<T: DualNum<f64>>(r: &T) -> [T; 3] {
    [r.clone(), r.clone() * 0.5, r.clone() * 2.0]
}

/// The lobes' θ_h centres from the Cuticle Angle `a` (radians): `−a, a/2, 3a/2` (Marschner
/// 2003's α_R = −a, α_TT = −α_R/2, α_TRT = −3α_R/2; R toward the root for a > 0).
pub fn lobe_shifts<T: DualNum<f64>>(a: &T) -> [T; 3] {
    [-a.clone(), a.clone() * 0.5, a.clone() * 1.5]
}

/// `F₀ = ((η − 1)/(η + 1))²`, the reflectance at normal incidence (0.0465 at η = 1.55).
pub fn normal_reflectance<T: DualNum<f64>>(eta: &T) -> T {
    ((eta.clone() - 1.0) / (eta.clone() + 1.0)).powi(2)
}

/// Schlick's Fresnel `F₀ + (1 − F₀)(1 − cos)⁵`.
pub fn schlick<T: DualNum<f64>>(f0: &T, cos: f64) -> T {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    (-f0.clone() + 1.0) * m.powi(5) + f0.clone()
}

/// `cos(angle(L, V)/2) = √(½ + ½ L·V)`, with `L·V = cos θ_i cos θ_r cos φ + sin θ_i sin θ_r`:
/// where R's Fresnel is taken (d'Eon 2011's half angle, as HDRP writes it). Computed as
/// `√(sin²θ_h + cos θ_i cos θ_r cos²(φ/2))`, which does not cancel as L → −V.
pub fn half_angle_cosine(a: &Angles) -> f64 {
    use crate::families::shared::half_angle;
    half_angle::half_angle_cosine(
        a.theta_i,
        a.theta_r,
        half_angle::half_phi_cosine(a.phi_r - a.phi_i),
    )
}

/// Chiang 2016 eq. 9's denominator `D(β) = 5.969 − 0.215β + 2.532β² − 10.73β³ + 5.574β⁴ + 0.245β⁵`.
pub fn absorption_denominator<T: DualNum<f64>>(beta_n: &T) -> T {
    let b = beta_n.clone();
    ((((b.clone() * 0.245 + 5.574) * b.clone() - 10.73) * b.clone() + 2.532) * b.clone() - 0.215)
        * b
        + 5.969
}

/// `σ_a = (ln C / D(β_N))²` (Chiang 2016 eq. 9), C clamped below at [`BASE_COLOR_MIN`] as HDRP
/// does: per fibre radius, with the chord path of [`chord_transmittance`].
pub fn absorption_from_base_color<T: DualNum<f64>>(base_color: &T, beta_n: &T) -> T {
    let c = if base_color.re() < BASE_COLOR_MIN {
        T::from(BASE_COLOR_MIN)
    } else {
        base_color.clone()
    };
    (c.ln() / absorption_denominator(beta_n)).powi(2)
}

/// `cos θ_t` of the refracted ray, `sin θ_t = sin θ_r / η` (HDRP refracts the view direction).
pub fn refracted_cosine<T: DualNum<f64>>(sin_theta_r: f64, eta: &T) -> T {
    let s = eta.recip() * sin_theta_r;
    (-(s.clone() * s) + 1.0).sqrt()
}

/// `exp(−σ_a · 2cos γ_t / cos θ_t)`: Beer's law along one chord at offset h, `sin γ_t = h/η′`.
pub fn chord_transmittance<T: DualNum<f64>>(sigma_a: &T, cos_gamma_t: f64, cos_theta_t: &T) -> T {
    (-(sigma_a.clone() * (2.0 * cos_gamma_t)) / cos_theta_t.clone()).exp()
}

/// `A_R = F(√(½ + ½ L·V))`.
pub fn attenuation_r<T: DualNum<f64>>(f0: &T, half_angle_cos: f64) -> T {
    schlick(f0, half_angle_cos)
}

/// `A_TT = (1 − F)² T` at h = 0: Fresnel at `cos θ_r`, one chord through the centre.
pub fn attenuation_tt<T: DualNum<f64>>(f0: &T, cos_theta_r: f64, transmittance: &T) -> T {
    let f = schlick(f0, cos_theta_r);
    (-f + 1.0).powi(2) * transmittance.clone()
}

/// `A_TRT = (1 − F)² F T²` at h = √3/2: Fresnel at `cos θ_r · cos γ = ½ cos θ_r`.
pub fn attenuation_trt<T: DualNum<f64>>(f0: &T, cos_theta_r: f64, transmittance: &T) -> T {
    let f = schlick(f0, cos_theta_r * (1.0 - H_TRT * H_TRT).sqrt());
    (-f.clone() + 1.0).powi(2) * f * transmittance.clone() * transmittance.clone()
}

/// `[lo, hi]`.
const fn closed(lo: f64, hi: f64) -> Interval {
    Interval {
        lo,
        lo_open: false,
        hi,
        hi_open: false,
    }
}

/// `cos γ_t` at offset h for the modified index η′ (Bravais' law in the normal plane).
fn refracted_offset_cosine(h: f64, eta_prime: f64) -> f64 {
    let s = h / eta_prime;
    (1.0 - s * s).sqrt()
}

impl TableFamily for Frostbite {
    const NAME: &'static str = "frostbite";
    const TITLE: &'static str = "Frostbite 2019 (Unity HDRP physical hair)";
    const FIX_EXAMPLE: &'static str = "cuticle_angle_deg=3 or --fix radial_smoothness=0.7";
    const TERMS: &'static [Term] = &[
        Term {
            name: "R",
            meaning: "reflection at the cuticle",
            column: LobeColumn::R,
        },
        Term {
            name: "TT",
            meaning: "transmission through the fibre",
            column: LobeColumn::TT,
        },
        Term {
            name: "TRT",
            meaning: "one internal reflection",
            column: LobeColumn::TRT,
        },
    ];
    const PARAMETERS: &'static [ParamFact] = &[
        ParamFact {
            name: "base_color",
            symbol: "C",
            meaning: "Base Color (linear), one per colour channel: absorption (ln C/D(β_N))²",
            unit: Unit::Dimensionless,
            per_channel: true,
            domain: closed(BASE_COLOR_MIN, 1.0),
            fit_lo: BASE_COLOR_MIN,
            fit_hi: Some(1.0),
            typical: (0.05, 0.9),
            reference: Some(0.5),
            fitted: Fitted::Yes,
            terms: &["TT", "TRT"],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "smoothness",
            symbol: "s_L",
            meaning: "Smoothness: R's longitudinal width 1 - s_L in radians (TT half, TRT twice)",
            unit: Unit::Dimensionless,
            per_channel: false,
            domain: closed(0.0, SMOOTHNESS_MAX),
            fit_lo: 0.0,
            fit_hi: Some(SMOOTHNESS_MAX),
            typical: (0.75, 0.95),
            reference: Some(0.85),
            fitted: Fitted::Yes,
            terms: &[],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "radial_smoothness",
            symbol: "s_N",
            meaning: "Radial Smoothness: azimuthal roughness beta_N = 1 - s_N",
            unit: Unit::Dimensionless,
            per_channel: false,
            domain: closed(0.0, RADIAL_SMOOTHNESS_MAX),
            fit_lo: 0.0,
            fit_hi: Some(RADIAL_SMOOTHNESS_MAX),
            typical: (0.5, 0.85),
            reference: Some(0.7),
            fitted: Fitted::Yes,
            terms: &[],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "cuticle_angle_deg",
            symbol: "a",
            meaning:
                "Cuticle Angle: R's centre at theta_h = -a (toward the root), TT +a/2, TRT +3a/2",
            unit: Unit::Degrees,
            per_channel: false,
            domain: Interval::open(-45.0, 45.0),
            fit_lo: -15.0,
            fit_hi: Some(15.0),
            typical: (1.0, 5.0),
            reference: Some(3.0),
            fitted: Fitted::Yes,
            terms: &[],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "eta",
            symbol: "η",
            meaning: "index of refraction (HDRP fixes 1.55; it moves Fresnel and theta_t only)",
            unit: Unit::Dimensionless,
            per_channel: false,
            domain: Interval::open(1.0, 3.0),
            fit_lo: 1.2,
            fit_hi: Some(2.2),
            typical: (1.5, 1.6),
            reference: Some(1.55),
            fitted: Fitted::OnRequest,
            terms: &[],
            ..ParamFact::BASE
        },
    ];

    fn scatter<T: DualNum<f64>>(p: &TableParams<T>, a: &Angles, on: TermSet, out: &mut [Terms<T>]) {
        let theta_h = 0.5 * (a.theta_i + a.theta_r);
        let cos_theta_d = (0.5 * (a.theta_r - a.theta_i)).cos();
        let phi = wrap(a.phi_r - a.phi_i);
        let width = -p.get(SMOOTHNESS, 0) + 1.0;
        let beta_n = -p.get(RADIAL_SMOOTHNESS, 0) + 1.0;
        let eta = p.get(ETA, 0);
        let f0 = normal_reflectance(&eta);
        let sigmas = lobe_widths(&width);
        let shifts = lobe_shifts(&p.get(CUTICLE_ANGLE, 0));
        let logistic = Logistic::new(&beta_n);
        let x = azimuthal::inverse_modified_index(cos_theta_d);
        // M_p · N_p: what every channel shares.
        let shape = |lobe: usize| {
            gaussian(&(-shifts[lobe].clone() + theta_h), &sigmas[lobe])
                * azimuthal::lobe(lobe, phi, x, &logistic)
        };
        let cos_theta_r = a.theta_r.cos();
        let cos_theta_t = refracted_cosine(a.theta_r.sin(), &eta);
        let eta_prime = azimuthal::modified_index(cos_theta_d);
        let r = on
            .has(R)
            .then(|| shape(R) * attenuation_r(&f0, half_angle_cosine(a)));
        let tt = on.has(TT).then(|| shape(TT));
        let trt = on.has(TRT).then(|| shape(TRT));
        let cos_gamma_trt = refracted_offset_cosine(H_TRT, eta_prime);
        for (c, o) in out.iter_mut().enumerate() {
            if let Some(r) = &r {
                o[R] = r.clone();
            }
            if tt.is_none() && trt.is_none() {
                continue;
            }
            let sigma_a = absorption_from_base_color(&p.get(BASE_COLOR, c), &beta_n);
            if let Some(tt) = &tt {
                let t = chord_transmittance(&sigma_a, 1.0, &cos_theta_t);
                o[TT] = tt.clone() * attenuation_tt(&f0, cos_theta_r, &t);
            }
            if let Some(trt) = &trt {
                let t = chord_transmittance(&sigma_a, cos_gamma_trt, &cos_theta_t);
                o[TRT] = trt.clone() * attenuation_trt(&f0, cos_theta_r, &t);
            }
        }
    }
}
