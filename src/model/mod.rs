//! The Marschner 2003 forward model of `MODEL.md`: configuration, parameters, angles and the
//! scattering function `S`, generic over the number type so forward-mode AD gives exact Jacobians.
//!
//! Number type: every model function takes `T: num_dual::DualNum<f64>` (which is `Clone`, not
//! `Copy`), so it works for `f64`, `Dual64`, `DualSVec64<N>` and `DualDVec64`. For `f64` the clones
//! are free and the code is monomorphised with no allocation per call.

use std::fmt;
use std::str::FromStr;

use num_dual::DualNum;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

pub mod angles;
pub mod azimuthal;
pub mod bravais;
pub mod eccentricity;
pub mod exit_angle;
pub mod fresnel;
pub mod instrument;
pub mod jacobian;
pub mod longitudinal;
pub mod roots;

use angles::half_angles;
use azimuthal::{add_r, add_root_sum, add_trt_with_glints, Sink};
use bravais::bravais_indices;
use eccentricity::eccentric_index;
use exit_angle::ExitMap;
use longitudinal::longitudinal;

pub use jacobian::{param_value, scattering_jacobian, StaticJacobian};

/// How the roots of the exit-angle map are found (MODEL.md "Root modes").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum RootMode {
    /// Marschner's cubic approximation of `γ_t` inside the exit-angle map.
    #[default]
    Cubic,
    /// Exact roots of `Φ(p, h)` to near machine precision.
    Exact,
}

impl FromStr for RootMode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "cubic" => Ok(RootMode::Cubic),
            "exact" => Ok(RootMode::Exact),
            other => Err(Error::Other(format!(
                "unknown root mode `{other}`: use `cubic` or `exact`"
            ))),
        }
    }
}

impl fmt::Display for RootMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RootMode::Cubic => "cubic",
            RootMode::Exact => "exact",
        })
    }
}

/// Which lobes contribute to `S`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct Lobes {
    pub r: bool,
    pub tt: bool,
    pub trt: bool,
}

impl Default for Lobes {
    fn default() -> Self {
        Lobes {
            r: true,
            tt: true,
            trt: true,
        }
    }
}

/// Lobes and effects switched on; disabled ones are not computed at all.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct Effects {
    pub lobes: Lobes,
    pub glints: bool,
    pub eccentricity: bool,
}

impl Default for Effects {
    fn default() -> Self {
        Effects {
            lobes: Lobes::default(),
            glints: true,
            eccentricity: true,
        }
    }
}

impl Effects {
    /// Parse a lobe list such as `"R,TT,TRT"` (case-insensitive); unknown names are an error.
    pub fn parse_lobes(list: &str) -> Result<Lobes> {
        let mut lobes = Lobes {
            r: false,
            tt: false,
            trt: false,
        };
        for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            match item.to_ascii_uppercase().as_str() {
                "R" => lobes.r = true,
                "TT" => lobes.tt = true,
                "TRT" => lobes.trt = true,
                other => {
                    return Err(Error::Other(format!(
                    "unknown lobe `{other}` in `{list}`: use a comma-separated list of R, TT, TRT"
                )))
                }
            }
        }
        if !(lobes.r || lobes.tt || lobes.trt) {
            return Err(Error::Other(format!(
                "lobe list `{list}` is empty: name at least one of R, TT, TRT"
            )));
        }
        Ok(lobes)
    }

    /// The parameters `S` depends on under these effects (`n_channels` absorption coefficients).
    pub fn parameters(&self, n_channels: usize) -> Vec<ParamName> {
        let l = self.lobes;
        let mut out = Vec::new();
        // η enters every lobe through Fresnel / the Bravais indices.
        out.push(ParamName::Eta);
        // σ_a only attenuates transmitted paths (TT, TRT).
        if l.tt || l.trt {
            out.extend((0..n_channels).map(ParamName::SigmaA));
        }
        // α_R, β_R set every lobe's longitudinal Gaussian.
        out.push(ParamName::AlphaR);
        out.push(ParamName::BetaR);
        if l.trt && self.glints {
            out.push(ParamName::KG);
            out.push(ParamName::WC);
        }
        if l.trt && self.eccentricity {
            out.push(ParamName::Eccentricity);
        }
        if l.trt && self.glints {
            out.push(ParamName::DeltaEtaPrime);
            out.push(ParamName::DeltaHM);
        }
        out
    }
}

/// Root mode and effect switches for one evaluation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct ModelConfig {
    pub mode: RootMode,
    pub effects: Effects,
}

/// A model parameter, by the JSON name of MODEL.md.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ParamName {
    Eta,
    SigmaA(usize),
    AlphaR,
    BetaR,
    KG,
    WC,
    Eccentricity,
    DeltaEtaPrime,
    DeltaHM,
}

impl ParamName {
    /// The JSON name (`"eta"`, `"sigma_a[1]"`, `"alpha_r_deg"`, ...).
    pub fn json_name(&self) -> String {
        match self {
            ParamName::Eta => "eta".into(),
            ParamName::SigmaA(c) => format!("sigma_a[{c}]"),
            ParamName::AlphaR => "alpha_r_deg".into(),
            ParamName::BetaR => "beta_r_deg".into(),
            ParamName::KG => "k_g".into(),
            ParamName::WC => "w_c_deg".into(),
            ParamName::Eccentricity => "eccentricity".into(),
            ParamName::DeltaEtaPrime => "delta_eta_prime".into(),
            ParamName::DeltaHM => "delta_h_m".into(),
        }
    }
}

impl fmt::Display for ParamName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.json_name())
    }
}

/// Parameters in RADIANS, generic over the number type (f64, or num-dual duals for Jacobians).
#[derive(Debug, Clone, PartialEq)]
pub struct Params<T> {
    pub eta: T,
    pub sigma_a: Vec<T>,
    pub alpha_r: T,
    pub beta_r: T,
    pub k_g: T,
    pub w_c: T,
    pub eccentricity: T,
    pub delta_eta_prime: T,
    pub delta_h_m: T,
}

impl Params<f64> {
    /// Check the domain of MODEL.md; the error names the parameter and its valid range.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, value: f64, message: &str| {
            Err(Error::Parameter {
                name: name.into(),
                value,
                message: message.into(),
            })
        };
        let deg = f64::to_degrees;
        if !(self.eta.is_finite() && self.eta > 1.0) {
            return bad("eta", self.eta, "must be finite and > 1");
        }
        if self.sigma_a.is_empty() {
            return bad("sigma_a", f64::NAN, "give at least one colour channel");
        }
        for (c, &s) in self.sigma_a.iter().enumerate() {
            if !(s.is_finite() && s >= 0.0) {
                return bad(&format!("sigma_a[{c}]"), s, "must be finite and >= 0");
            }
        }
        if !self.alpha_r.is_finite() {
            return bad("alpha_r_deg", deg(self.alpha_r), "must be finite");
        }
        if !(self.beta_r.is_finite() && self.beta_r > 0.0) {
            return bad("beta_r_deg", deg(self.beta_r), "must be finite and > 0");
        }
        if !(self.k_g.is_finite() && self.k_g >= 0.0) {
            return bad("k_g", self.k_g, "must be finite and >= 0");
        }
        if !(self.w_c.is_finite() && self.w_c > 0.0) {
            return bad("w_c_deg", deg(self.w_c), "must be finite and > 0");
        }
        let a = self.eccentricity;
        if !(a.is_finite() && a > std::f64::consts::FRAC_1_SQRT_2 && a <= 1.0) {
            return bad(
                "eccentricity",
                a,
                "must lie in (1/sqrt(2), 1] = (0.70711, 1]: below 1/sqrt(2) the TRT Bravais index can drop under 1",
            );
        }
        if !(self.delta_eta_prime.is_finite() && self.delta_eta_prime > 0.0) {
            return bad(
                "delta_eta_prime",
                self.delta_eta_prime,
                "must be finite and > 0",
            );
        }
        if !(self.delta_h_m.is_finite() && self.delta_h_m > 0.0) {
            return bad("delta_h_m", self.delta_h_m, "must be finite and > 0");
        }
        Ok(())
    }
}

/// Incident and reflected directions in the fiber frame, radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Angles {
    pub theta_i: f64,
    pub phi_i: f64,
    pub theta_r: f64,
    pub phi_r: f64,
}

impl Angles {
    /// Check `θ ∈ (−90°, 90°)` (|θ| = 90° puts the direction on the fiber axis) and all finite;
    /// the error names the angle and its value in degrees.
    pub fn validate(&self) -> Result<()> {
        let check = |name: &str, v: f64, limit: Option<f64>| {
            let ok = v.is_finite() && limit.is_none_or(|l| v.abs() < l);
            if ok {
                Ok(())
            } else {
                Err(Error::Parameter {
                    name: name.into(),
                    value: v.to_degrees(),
                    message: match limit {
                        Some(_) => {
                            "an inclination must be finite and strictly between -90 and 90 degrees"
                                .into()
                        }
                        None => "an azimuth must be finite".into(),
                    },
                })
            }
        };
        let half_pi = Some(std::f64::consts::FRAC_PI_2);
        check("theta_i", self.theta_i, half_pi)?;
        check("phi_i", self.phi_i, None)?;
        check("theta_r", self.theta_r, half_pi)?;
        check("phi_r", self.phi_r, None)
    }

    /// Angles from degrees.
    pub fn from_degrees(theta_i: f64, phi_i: f64, theta_r: f64, phi_r: f64) -> Angles {
        Angles {
            theta_i: theta_i.to_radians(),
            phi_i: phi_i.to_radians(),
            theta_r: theta_r.to_radians(),
            phi_r: phi_r.to_radians(),
        }
    }
}

/// S for every colour channel (`out.len() == params.sigma_a.len()`); roots computed once, shared
/// by channels.
///
/// `T` is `f64` or any num-dual number (`Dual64`, `DualSVec64<N>`, `DualDVec64`): the bound is just
/// `DualNum<f64>` (Clone, not Copy). Panics if `out.len() != params.sigma_a.len()` (a programming
/// error, not bad input). Parameters are assumed valid ([`Params::validate`]).
pub fn scattering<T: DualNum<f64>>(
    params: &Params<T>,
    config: &ModelConfig,
    angles: &Angles,
    out: &mut [T],
) {
    assert_eq!(out.len(), params.sigma_a.len(), "one output per channel");
    for o in out.iter_mut() {
        *o = T::from(0.0);
    }
    evaluate(params, config, angles, &mut Total(out));
}

/// Same, split per lobe: `out[c] = [R, TT, TRT]` contributions (each already divided by
/// cos²θ_d); disabled lobes 0.
pub fn scattering_by_lobe<T: DualNum<f64>>(
    params: &Params<T>,
    config: &ModelConfig,
    angles: &Angles,
    out: &mut [[T; 3]],
) {
    assert_eq!(out.len(), params.sigma_a.len(), "one output per channel");
    for o in out.iter_mut() {
        *o = [T::from(0.0), T::from(0.0), T::from(0.0)];
    }
    evaluate(params, config, angles, &mut ByLobe(out));
}

/// Sum of the lobes per channel.
struct Total<'a, T>(&'a mut [T]);
impl<T: DualNum<f64>> Sink<T> for Total<'_, T> {
    #[inline]
    fn add(&mut self, channel: usize, _lobe: usize, value: T) {
        self.0[channel] += value;
    }
}

/// Lobes kept apart per channel.
struct ByLobe<'a, T>(&'a mut [[T; 3]]);
impl<T: DualNum<f64>> Sink<T> for ByLobe<'_, T> {
    #[inline]
    fn add(&mut self, channel: usize, lobe: usize, value: T) {
        self.0[channel][lobe] += value;
    }
}

/// `S = Σ_p M_p(θ_h)·N_p(θ_d, φ, φ_h)/cos²θ_d` over the enabled lobes; disabled lobes and effects
/// are skipped before any of their work (roots, caustics, η*).
fn evaluate<T: DualNum<f64>, S: Sink<T>>(
    params: &Params<T>,
    config: &ModelConfig,
    angles: &Angles,
    sink: &mut S,
) {
    let ha = half_angles(angles.theta_i, angles.phi_i, angles.theta_r, angles.phi_r);
    let (sin_td, cos_td) = ha.theta_d.sin_cos();
    let inv_cos2 = 1.0 / (cos_td * cos_td);
    let lobes = config.effects.lobes;
    let n = params.sigma_a.len();

    if lobes.r || lobes.tt {
        let br = bravais_indices(&params.eta, sin_td, cos_td);
        if lobes.r {
            let m = longitudinal(0, ha.theta_h, &params.alpha_r, &params.beta_r) * inv_cos2;
            add_r(&br, ha.phi, n, &m, sink);
        }
        if lobes.tt {
            let m = longitudinal(1, ha.theta_h, &params.alpha_r, &params.beta_r) * inv_cos2;
            let map = ExitMap::new(config.mode, 1, br.eta_p.clone());
            add_root_sum(1, &map, &br, ha.phi, &params.sigma_a, &m, sink);
        }
    }
    if lobes.trt {
        let eta = if config.effects.eccentricity {
            eccentric_index(&params.eta, &params.eccentricity, ha.phi_h)
        } else {
            params.eta.clone()
        };
        let br = bravais_indices(&eta, sin_td, cos_td);
        let m = longitudinal(2, ha.theta_h, &params.alpha_r, &params.beta_r) * inv_cos2;
        let map = ExitMap::new(config.mode, 2, br.eta_p.clone());
        if config.effects.glints {
            add_trt_with_glints(
                &map,
                &br,
                ha.phi,
                &params.sigma_a,
                &params.k_g,
                &params.w_c,
                &params.delta_eta_prime,
                &params.delta_h_m,
                &m,
                sink,
            );
        } else {
            add_root_sum(2, &map, &br, ha.phi, &params.sigma_a, &m, sink);
        }
    }
}
