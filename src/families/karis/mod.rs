//! Karis 2016 ("Physically Based Hair Shading in Unreal", SIGGRAPH 2016 PBS course) as Unreal
//! Engine 5.0–5.3 evaluates it for a punctual light on its Hair shading model: R, TT and TRT
//! lobes with Gaussian longitudinal terms in `sin θ_i + sin θ_r`, fitted closed forms for the
//! azimuthal terms, Base Color as absorption (the legacy transmittance both the card and the
//! strand paths use by default) and the "Scatter" multiple-scattering approximation. The
//! parameters are the material inputs an Unreal artist sets (Base Color, Roughness, Specular,
//! Backlit, Scatter) plus the two constants the engine hard-codes (η, the cuticle shift), so a
//! fit reads out as engine inputs. docs/karis.md has every equation, its source, and what the
//! course notes say against what the engine computes.
//!
//! The engine's value is `f` (the lighting multiplies it by the light's irradiance with no
//! `N·L`), so `S = f / cos θ_i` (docs/model.md's S). The engine's tangent runs root → tip for
//! strands (docs/karis.md, "Which way the tangent points"), so its `sin θ_L`, `sin θ_V` are
//! `sin θ_i`, `sin θ_r` here and its shift signs are kept: R sits toward the root.

pub mod export;

use std::f64::consts::PI;

use num_dual::DualNum;

use crate::families::shared::half_angle::{half_angle_cosine, half_phi_cosine};
use crate::families::table::{
    LobeColumn, ParamFact, TableFamily, TableParams, Term, TermSet, Terms,
};
use crate::geometry::Angles;
use crate::geometry::{Fitted, Interval, Unit};

/// The Karis / Unreal family.
pub struct Karis;

/// Table lines (indices into [`Karis::PARAMETERS`]).
pub const BASE_COLOR: usize = 0;
pub const ROUGHNESS: usize = 1;
pub const SPECULAR: usize = 2;
pub const BACKLIT: usize = 3;
pub const SCATTER: usize = 4;
pub const ETA: usize = 5;
pub const SHIFT: usize = 6;

/// Term indices (into [`Karis::TERMS`]).
pub const R: usize = 0;
pub const TT: usize = 1;
pub const TRT: usize = 2;
pub const SCATTER_TERM: usize = 3;

/// The engine's cuticle shift unit, radians (`Shift` in UE's HairShading).
pub const ENGINE_SHIFT: f64 = 0.035;

/// The engine's refractive index (Schlick's `F₀` from it).
pub const ENGINE_ETA: f64 = 1.55;

/// The smallest roughness: the engine clamps to [1/255, 1]; the bound is 1/255 rounded down to
/// the digits the docs and messages print (0.00392), so the value they name is accepted (the
/// engine raises it by 0.04%).
pub const MIN_ROUGHNESS: f64 = 0.00392;

/// `[lo, hi]`.
const fn closed(lo: f64, hi: f64) -> Interval {
    Interval {
        lo,
        lo_open: false,
        hi,
        hi_open: false,
    }
}

/// The angle-only quantities every term reads at one direction pair (UE's `HairShading`
/// preamble, from hairfit's angles instead of vectors).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// `sin θ_i + sin θ_r`, the longitudinal variable of every lobe.
    pub sin_sum: f64,
    pub sin_theta_i: f64,
    pub cos_theta_i: f64,
    pub sin_theta_r: f64,
    pub cos_theta_r: f64,
    /// `cos θ_d`, `θ_d = (θ_r − θ_i)/2`.
    pub cos_theta_d: f64,
    pub cos_phi: f64,
    /// `cos(φ/2)` of φ wrapped to [−π, π] (≥ 0: the model is even in φ), from the half angle
    /// itself: `√(½ + ½ cos φ)` cancels to nothing as φ → π.
    pub cos_half_phi: f64,
    /// `ω_i·ω_r = cos θ_i cos θ_r cos φ + sin θ_i sin θ_r`.
    pub v_dot_l: f64,
    /// `cos(∠(ω_i, ω_r)/2) = √(½ + ½ ω_i·ω_r)`, as `√(sin²θ_h + cos θ_i cos θ_r cos²(φ/2))`
    /// (`|ω_i + ω_r|/2` by half-angle identities): no cancellation as the directions oppose.
    pub half_angle_cos: f64,
}

impl Geometry {
    pub fn new(a: &Angles) -> Geometry {
        let (sin_theta_i, cos_theta_i) = a.theta_i.sin_cos();
        let (sin_theta_r, cos_theta_r) = a.theta_r.sin_cos();
        let phi = a.phi_r - a.phi_i;
        let cos_phi = phi.cos();
        let cos_half_phi = half_phi_cosine(phi);
        Geometry {
            sin_sum: sin_theta_i + sin_theta_r,
            sin_theta_i,
            cos_theta_i,
            sin_theta_r,
            cos_theta_r,
            cos_theta_d: (0.5 * (a.theta_r - a.theta_i)).cos(),
            cos_phi,
            cos_half_phi,
            v_dot_l: cos_theta_i * cos_theta_r * cos_phi + sin_theta_i * sin_theta_r,
            half_angle_cos: half_angle_cosine(a.theta_i, a.theta_r, cos_half_phi),
        }
    }
}

/// `G(y; B) = exp(−y²/2B²)/(√(2π) B)`: the normal density every longitudinal term uses, in
/// the variable `sin θ_i + sin θ_r` (Karis 2016, "Longitudinal scattering"). Divisions are
/// products with reciprocals here and below: that is how dual numbers divide, so values and
/// derivatives passes agree to the bit.
pub fn gaussian<T: DualNum<f64>>(y: &T, width: &T) -> T {
    let z = y.clone() * width.recip();
    (z.clone() * z * -0.5).exp() * (width.clone() * (2.0 * PI).sqrt()).recip()
}

/// The lobe widths `(B_R, B_TT, B_TRT) = (r², r²/2, 2r²)` from Roughness `r` (UE's `B[]`, with
/// its area-light widening 0 for a punctual light).
pub fn lobe_widths<T: DualNum<f64>>(roughness: &T) -> [T; 3] {
    let b = roughness.powi(2);
    [b.clone(), b.clone() * 0.5, b * 2.0]
}

/// `F₀ = ((1 − η)/(1 + η))²`, Schlick's normal-incidence reflectance.
pub fn normal_reflectance<T: DualNum<f64>>(eta: &T) -> T {
    ((-eta.clone() + 1.0) * (eta.clone() + 1.0).recip()).powi(2)
}

/// Schlick's Fresnel `F₀ + (1 − F₀)(1 − c)⁵` at incidence cosine `c` (the engine's `Hair_F`).
pub fn schlick<T: DualNum<f64>>(f0: &T, cos: f64) -> T {
    f0.clone() * (1.0 - (1.0 - cos).powi(5)) + (1.0 - cos).powi(5)
}

/// The lobe centres in `sin θ_i + sin θ_r` for the shift unit `s₀`: `(α_R, α_TT, α_TRT) =
/// (−2s₀, s₀, 4s₀)` (Karis 2016 notes p. 44's shifts; UE's `Alpha[]`).
pub fn lobe_shifts<T: DualNum<f64>>(shift: &T) -> [T; 3] {
    [shift.clone() * -2.0, shift.clone(), shift.clone() * 4.0]
}

/// R's centre, the cone rotated by `α_R` and projected: `2 sin α (cos α cos(φ/2) cos θ_r +
/// sin α sin θ_r)` (UE; at φ = 0 it is `sin(θ_r) − sin(θ_r − 2α)`, the notes' `α_R` doubled).
pub fn r_centre<T: DualNum<f64>>(alpha_r: &T, g: &Geometry) -> T {
    let (sa, ca) = (alpha_r.sin(), alpha_r.cos());
    sa.clone() * 2.0 * (ca * (g.cos_half_phi * g.cos_theta_r) + sa * g.sin_theta_r)
}

/// `M_R · N_R` with the separable-R width `B_R √2 cos(φ/2)` and `N_R = ¼ cos(φ/2)`, written as
/// one product `exp(−y²/(4B²cos²(φ/2)))/(8√π B)` so it stays finite at φ = π (0 there).
pub fn r_lobe<T: DualNum<f64>>(y: &T, b_r: &T, cos_half_phi: f64) -> T {
    if cos_half_phi <= 0.0 {
        return T::zero();
    }
    let z = y.clone() * (b_r.clone() * cos_half_phi).recip();
    (z.clone() * z * -0.25).exp() * (b_r.clone() * (8.0 * PI.sqrt())).recip()
}

/// R's attenuation `F(cos(∠(ω_i, ω_r)/2))`: Fresnel at the half angle between the directions
/// ([`Geometry::half_angle_cos`]).
pub fn r_attenuation<T: DualNum<f64>>(f0: &T, half_angle_cos: f64) -> T {
    schlick(f0, half_angle_cos)
}

/// Backlit's fade of R: `1 + (b − 1)·clamp(−ω_i·ω_r, 0, 1)` (lerp(1, b, sat(−V·L))).
pub fn backlit_fade<T: DualNum<f64>>(backlit: &T, v_dot_l: f64) -> T {
    (backlit.clone() - 1.0) * (-v_dot_l).clamp(0.0, 1.0) + 1.0
}

/// `f_R = M_R N_R · F · 2·Specular · fade`.
pub fn f_r<T: DualNum<f64>>(p: &KarisShared<T>, g: &Geometry) -> T {
    let y = -r_centre(&p.shifts[0], g) + g.sin_sum;
    r_lobe(&y, &p.widths[0], g.cos_half_phi)
        * r_attenuation(&p.f0, g.half_angle_cos)
        * p.specular.clone()
        * 2.0
        * backlit_fade(&p.backlit, g.v_dot_l)
}

/// Karis's fit of the Bravais index for η = 1.55: `η′ ≈ 1.19/cos θ_d + 0.36 cos θ_d`.
pub fn eta_prime_fit(cos_theta_d: f64) -> f64 {
    1.19 / cos_theta_d + 0.36 * cos_theta_d
}

/// Karis's fit of TT's exit offset: `h_TT ≈ cos(φ/2)(1 + a(0.6 − 0.8 cos φ))`, `a = 1/η′`.
pub fn tt_offset(cos_half_phi: f64, cos_phi: f64, a: f64) -> f64 {
    cos_half_phi * (1.0 + a * (0.6 - 0.8 * cos_phi))
}

/// TT's azimuthal term `exp(−3.65 cos φ − 3.98)` (a fit of a logistic of scale 0.35 about π).
pub fn tt_azimuthal(cos_phi: f64) -> f64 {
    (-3.65 * cos_phi - 3.98).exp()
}

/// TRT's azimuthal term `exp(17 cos φ − 16.78)` (0.75 × a logistic of scale 0.15 about 0).
pub fn trt_azimuthal(cos_phi: f64) -> f64 {
    (17.0 * cos_phi - 16.78).exp()
}

/// `C^e` as `exp(e ln C)`: the Base Color raised to a path-length exponent.
pub fn colour_power<T: DualNum<f64>>(base_color: &T, exponent: f64) -> T {
    (base_color.ln() * exponent).exp()
}

/// TT's legacy transmittance exponent `√(1 − h²a²)/(2 cos θ_d)`, so `T_TT = C^e`: the
/// transmittance `e^{−2σ_a cos γ_t / cos θ_d}` of σ_a = −¼ ln C per radius.
pub fn tt_exponent(h: f64, a: f64, cos_theta_d: f64) -> f64 {
    0.5 * (1.0 - (h * a).powi(2)).sqrt() / cos_theta_d
}

/// TRT's transmittance exponent `0.8/cos θ_d` (`T_TRT = C^e`; 0.8 ≈ cos γ_t at h = √3/2).
pub fn trt_exponent(cos_theta_d: f64) -> f64 {
    0.8 / cos_theta_d
}

/// The colourless factors of TT at one direction pair, and its transmittance exponent:
/// `(M_TT · D_TT · (1 − f)² · Backlit, e)` with `f = F(cos θ_d √(1 − h²))`.
pub fn tt_factors<T: DualNum<f64>>(p: &KarisShared<T>, g: &Geometry) -> (T, f64) {
    let a = eta_prime_fit(g.cos_theta_d).recip();
    let h = tt_offset(g.cos_half_phi, g.cos_phi, a);
    let f = schlick(&p.f0, g.cos_theta_d * (1.0 - h * h).max(0.0).sqrt());
    let m = gaussian(&(-p.shifts[1].clone() + g.sin_sum), &p.widths[1]);
    let fresnel = (-f + 1.0).powi(2);
    let shape = m * fresnel * tt_azimuthal(g.cos_phi) * p.backlit.clone();
    (shape, tt_exponent(h, a, g.cos_theta_d))
}

/// The colourless factors of TRT and its exponent: `(M_TRT · D_TRT · (1 − f)² f, e)` with
/// `f = F(½ cos θ_d)` (h fixed at √3/2).
pub fn trt_factors<T: DualNum<f64>>(p: &KarisShared<T>, g: &Geometry) -> (T, f64) {
    let f = schlick(&p.f0, 0.5 * g.cos_theta_d);
    let m = gaussian(&(-p.shifts[2].clone() + g.sin_sum), &p.widths[2]);
    let fresnel = (-f.clone() + 1.0).powi(2) * f;
    let shape = m * fresnel * trt_azimuthal(g.cos_phi);
    (shape, trt_exponent(g.cos_theta_d))
}

/// The Scatter term's shape `(1/π)(0.67 W + 0.33 K)`: a wrapped Lambert `W = clamp((cos θ_i
/// cos φ + 1)/4, 0, 1)` about the view projected on the normal plane and Kajiya–Kay's
/// `K = 1 − |sin θ_i|` (UE's KajiyaKayDiffuseAttenuation; an unshadowed fibre has tint 1).
pub fn scatter_shape(g: &Geometry) -> f64 {
    let wrap = ((g.cos_theta_i * g.cos_phi + 1.0) / 4.0).clamp(0.0, 1.0);
    let k = 1.0 - g.sin_theta_i.abs();
    (0.67 * wrap + 0.33 * k) / PI
}

/// `f_MS = √C · Scatter · shape`.
pub fn f_scatter<T: DualNum<f64>>(base_color: &T, scatter: &T, shape: f64) -> T {
    base_color.sqrt() * scatter.clone() * shape
}

/// The parameter-only quantities shared by every direction and channel.
pub struct KarisShared<T> {
    pub widths: [T; 3],
    pub shifts: [T; 3],
    pub f0: T,
    pub specular: T,
    pub backlit: T,
    pub scatter: T,
}

impl<T: DualNum<f64>> KarisShared<T> {
    pub fn new(p: &TableParams<T>) -> KarisShared<T> {
        KarisShared {
            widths: lobe_widths(&p.get(ROUGHNESS, 0)),
            shifts: lobe_shifts(&p.get(SHIFT, 0)),
            f0: normal_reflectance(&p.get(ETA, 0)),
            specular: p.get(SPECULAR, 0),
            backlit: p.get(BACKLIT, 0),
            scatter: p.get(SCATTER, 0),
        }
    }
}

impl TableFamily for Karis {
    const NAME: &'static str = "karis";
    const TITLE: &'static str = "Karis 2016 (Unreal Engine 5)";
    const FIX_EXAMPLE: &'static str = "specular=0.5 or --fix base_color[0]=0.3";
    const TERMS: &'static [Term] = &[
        Term {
            name: "R",
            meaning: "reflection off the cuticle, scaled by Specular",
            column: LobeColumn::R,
        },
        Term {
            name: "TT",
            meaning: "transmission through the fibre, coloured by Base Color, scaled by Backlit",
            column: LobeColumn::TT,
        },
        Term {
            name: "TRT",
            meaning: "one internal reflection, coloured by Base Color",
            column: LobeColumn::TRT,
        },
        Term {
            name: "scatter",
            meaning:
                "Unreal's multiple-scattering approximation, weighted by Scatter (off by default)",
            column: LobeColumn::TRT,
        },
    ];
    const PARAMETERS: &'static [ParamFact] = &[
        ParamFact {
            name: "base_color",
            symbol: "C",
            meaning: "Base Color (linear), one per colour channel: the colour TT and TRT carry",
            unit: Unit::Dimensionless,
            per_channel: true,
            domain: Interval::open_closed(0.0, 1.0),
            fit_lo: 1e-3,
            fit_hi: Some(1.0),
            typical: (0.1, 0.7),
            reference: Some(0.5),
            fitted: Fitted::Yes,
            terms: &["TT", "TRT", "scatter"],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "roughness",
            symbol: "r",
            meaning: "Roughness: the lobe widths r², r²/2, 2r² in sin θ_i + sin θ_r",
            unit: Unit::Dimensionless,
            per_channel: false,
            domain: closed(MIN_ROUGHNESS, 1.0),
            fit_lo: 0.05,
            fit_hi: Some(1.0),
            typical: (0.25, 0.75),
            reference: Some(0.5),
            fitted: Fitted::Yes,
            terms: &["R", "TT", "TRT"],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "specular",
            symbol: "s",
            meaning: "Specular: R is scaled by 2s (0.5 leaves it as is)",
            unit: Unit::Dimensionless,
            per_channel: false,
            domain: closed(0.0, 1.0),
            fit_lo: 0.0,
            fit_hi: Some(1.0),
            typical: (0.2, 0.8),
            reference: Some(0.5),
            fitted: Fitted::Yes,
            terms: &["R"],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "backlit",
            symbol: "b",
            meaning: "Backlit: TT is scaled by b and R faded toward b for light from behind",
            unit: Unit::Dimensionless,
            per_channel: false,
            domain: closed(0.0, 1.0),
            fit_lo: 0.0,
            fit_hi: Some(1.0),
            typical: (0.5, 1.0),
            reference: Some(1.0),
            fitted: Fitted::No,
            terms: &["R", "TT"],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "scatter",
            symbol: "σ_ms",
            meaning: "Scatter: the weight of the multiple-scattering approximation",
            unit: Unit::Dimensionless,
            per_channel: false,
            domain: closed(0.0, 1.0),
            fit_lo: 0.0,
            fit_hi: Some(1.0),
            typical: (0.05, 0.5),
            reference: Some(0.0),
            fitted: Fitted::Yes,
            terms: &["scatter"],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "eta",
            symbol: "η",
            meaning: "refractive index in Schlick's F0 (the engine's 1.55; --free eta)",
            unit: Unit::Dimensionless,
            per_channel: false,
            domain: Interval::open_closed(1.0, 10.0),
            fit_lo: 1.2,
            fit_hi: Some(2.5),
            typical: (1.45, 1.65),
            reference: Some(ENGINE_ETA),
            fitted: Fitted::OnRequest,
            terms: &["R", "TT", "TRT"],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "shift_deg",
            symbol: "s₀",
            meaning: "cuticle shift unit: lobes at -2s0, s0, 4s0 in sin θ_i + sin θ_r, R toward \
                      the root for s0 > 0 (the engine's 0.035 rad)",
            unit: Unit::Degrees,
            per_channel: false,
            domain: closed(-10.0, 10.0),
            fit_lo: -10.0,
            fit_hi: Some(10.0),
            typical: (1.0, 3.0),
            reference: Some(ENGINE_SHIFT * (180.0 / PI)),
            fitted: Fitted::No,
            terms: &["R", "TT", "TRT"],
            ..ParamFact::BASE
        },
    ];

    fn default_terms() -> TermSet {
        TermSet((1 << R) | (1 << TT) | (1 << TRT))
    }

    fn scatter<T: DualNum<f64>>(p: &TableParams<T>, a: &Angles, on: TermSet, out: &mut [Terms<T>]) {
        let g = Geometry::new(a);
        let shared = KarisShared::new(p);
        let to_s = g.cos_theta_i.recip();
        let r = on.has(R).then(|| f_r(&shared, &g) * to_s);
        let tt = on.has(TT).then(|| tt_factors(&shared, &g));
        let trt = on.has(TRT).then(|| trt_factors(&shared, &g));
        let ms = on.has(SCATTER_TERM).then(|| scatter_shape(&g) * to_s);
        for (c, o) in out.iter_mut().enumerate() {
            let colour = p.get(BASE_COLOR, c);
            if let Some(v) = &r {
                o[R] = v.clone();
            }
            if let Some((shape, e)) = &tt {
                o[TT] = shape.clone() * colour_power(&colour, *e) * to_s;
            }
            if let Some((shape, e)) = &trt {
                o[TRT] = shape.clone() * colour_power(&colour, *e) * to_s;
            }
            if let Some(shape) = ms {
                o[SCATTER_TERM] = f_scatter(&colour, &shared.scatter, shape);
            }
        }
    }
}
