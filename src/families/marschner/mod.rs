//! The Marschner 2003 forward model of `MODEL.md`: configuration, parameters, angles and the
//! scattering function `S`, generic over the number type so forward-mode AD gives exact Jacobians.
//!
//! Number type: [`scattering`] takes `T: ModelNum` (`f64`, `DualSVec64<N>`, `DualDVec64`;
//! `Clone`, not `Copy`); the per-equation functions take any `num_dual::DualNum<f64>`, and the
//! index-only geometry runs in `T::Scalar` ([`chain`]). For `f64` the clones are free and the
//! code is monomorphised with no allocation per call.

use std::fmt;

use crate::error::{Error, Result};
pub use crate::families::effects::{Effects, Lobes, ModelConfig, RootMode};
use crate::geometry::sigma_a::require_channels;

pub mod azimuthal;
pub mod bravais;
pub mod chain;
pub mod cost;
pub mod demo;
pub mod eccentricity;
pub mod exit_angle;
pub mod family;
pub mod fit;
pub mod fresnel;
pub mod instrument;
pub mod jacobian;
pub mod lanes;
pub mod longitudinal;
pub mod parameters;
pub mod params;
pub mod roots;

use crate::geometry::{angles, Angles};
use angles::half_angles;
use azimuthal::{add_r, add_root_sum, add_trt_with_glints, GlintParams, Sink};
use bravais::bravais_indices;
use eccentricity::{eccentric_index_at, eccentric_terms};
use exit_angle::ExitMap;
use longitudinal::{gaussian_inv, lobe_shape};

pub use chain::ModelNum;
pub use jacobian::{scattering_jacobian, StaticJacobian};
pub use lanes::{scattering_by_lobe_lanes, scattering_lanes};
#[doc(hidden)]
pub use lanes::{scattering_lanes_on, LaneKernel};

/// The Marschner family: its facts here, its fit in [`fit`]; listed in `crate::families::registry`.
pub struct MarschnerFamily;

impl crate::geometry::FamilyFacts for MarschnerFamily {
    fn name(&self) -> &'static str {
        "marschner"
    }
    fn title(&self) -> &'static str {
        "Marschner"
    }
    fn citation(&self) -> &'static str {
        "Marschner 2003"
    }
    fn parameters(&self) -> &'static [crate::geometry::ParamFact] {
        &parameters::TABLE
    }
    fn own_options(&self) -> &'static [&'static str] {
        &["--mode", "--lobes", "--no-glints", "--no-eccentricity"]
    }
}

impl Effects {
    /// The Marschner parameters `S` depends on under these effects (`n_channels` absorption coefficients),
    /// in output order; read from the parameter table's "used by" column.
    pub fn parameters(&self, n_channels: usize) -> Vec<ParamName> {
        parameters::used_parameters(self, n_channels)
    }
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
    /// The JSON name (`"eta"`, `"sigma_a[1]"`, `"alpha_r_deg"`, ...), from the parameter table.
    pub fn json_name(&self) -> String {
        match self {
            ParamName::SigmaA(c) => format!("{}[{c}]", self.fact().name),
            _ => self.fact().name.into(),
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

impl<T: Clone> Params<T> {
    /// The value of parameter `name` (radians for angles).
    pub fn get(&self, name: ParamName) -> T {
        match name {
            ParamName::Eta => self.eta.clone(),
            ParamName::SigmaA(c) => self.sigma_a[c].clone(),
            ParamName::AlphaR => self.alpha_r.clone(),
            ParamName::BetaR => self.beta_r.clone(),
            ParamName::KG => self.k_g.clone(),
            ParamName::WC => self.w_c.clone(),
            ParamName::Eccentricity => self.eccentricity.clone(),
            ParamName::DeltaEtaPrime => self.delta_eta_prime.clone(),
            ParamName::DeltaHM => self.delta_h_m.clone(),
        }
    }
}

impl<T> Params<T> {
    /// Parameters with `n_channels` absorption coefficients, each value `f(name)`.
    pub fn from_fn(n_channels: usize, mut f: impl FnMut(ParamName) -> T) -> Params<T> {
        Params {
            eta: f(ParamName::Eta),
            sigma_a: (0..n_channels).map(|c| f(ParamName::SigmaA(c))).collect(),
            alpha_r: f(ParamName::AlphaR),
            beta_r: f(ParamName::BetaR),
            k_g: f(ParamName::KG),
            w_c: f(ParamName::WC),
            eccentricity: f(ParamName::Eccentricity),
            delta_eta_prime: f(ParamName::DeltaEtaPrime),
            delta_h_m: f(ParamName::DeltaHM),
        }
    }

    /// Set parameter `name` to `value` (radians for angles).
    pub fn set(&mut self, name: ParamName, value: T) {
        match name {
            ParamName::Eta => self.eta = value,
            ParamName::SigmaA(c) => self.sigma_a[c] = value,
            ParamName::AlphaR => self.alpha_r = value,
            ParamName::BetaR => self.beta_r = value,
            ParamName::KG => self.k_g = value,
            ParamName::WC => self.w_c = value,
            ParamName::Eccentricity => self.eccentricity = value,
            ParamName::DeltaEtaPrime => self.delta_eta_prime = value,
            ParamName::DeltaHM => self.delta_h_m = value,
        }
    }

    /// Map `f` over every parameter (e.g. lift f64 to a dual number type).
    pub fn map<U>(&self, f: impl Fn(&T) -> U) -> Params<U> {
        Params {
            eta: f(&self.eta),
            sigma_a: self.sigma_a.iter().map(&f).collect(),
            alpha_r: f(&self.alpha_r),
            beta_r: f(&self.beta_r),
            k_g: f(&self.k_g),
            w_c: f(&self.w_c),
            eccentricity: f(&self.eccentricity),
            delta_eta_prime: f(&self.delta_eta_prime),
            delta_h_m: f(&self.delta_h_m),
        }
    }
}

impl Params<f64> {
    /// Check every parameter against its domain in the parameter table; the error names the
    /// parameter, its value in file units (degrees for angles) and the allowed range.
    pub fn validate(&self) -> Result<()> {
        require_channels(&self.sigma_a)?;
        for name in parameters::all_parameters(self.sigma_a.len()) {
            let spec = name.fact();
            let value = self.get(name) * spec.unit.file_factor();
            spec.check(value).map_err(|message| Error::Parameter {
                name: name.json_name(),
                value,
                message,
            })?;
        }
        Ok(())
    }
}

/// S for every colour channel (`out.len() == params.sigma_a.len()`); roots computed once, shared
/// by channels.
///
/// `T` is `f64` or a first-order num-dual vector (`DualSVec64<N>`, `DualDVec64`): [`ModelNum`]
/// (Clone, not Copy). Panics if `out.len() != params.sigma_a.len()` (a programming
/// error, not bad input). Parameters are assumed valid ([`Params::validate`]).
pub fn scattering<T: ModelNum>(
    params: &Params<T>,
    config: &ModelConfig,
    angles: &Angles,
    out: &mut [T],
) {
    scattering_batch(params, config, std::slice::from_ref(angles), out);
}

/// [`scattering`] of every direction in `angles`: `out[k * nc + c]` for sample `k`, channel `c`
/// (panics unless `out.len() == angles.len() * nc`). The parameter-only factors are computed
/// once for the batch.
pub fn scattering_batch<T: ModelNum>(
    params: &Params<T>,
    config: &ModelConfig,
    angles: &[Angles],
    out: &mut [T],
) {
    let nc = params.sigma_a.len();
    assert_eq!(
        out.len(),
        angles.len() * nc,
        "one output per sample and channel"
    );
    let prepared = Prepared::new(params);
    for (a, o) in angles.iter().zip(out.chunks_mut(nc.max(1))) {
        evaluate_into(params, &prepared, config, a, o);
    }
}

/// `S` of one sample, one value per channel, into `out` (overwritten).
fn evaluate_into<T: ModelNum>(
    params: &Params<T>,
    prepared: &Prepared<T>,
    config: &ModelConfig,
    angles: &Angles,
    out: &mut [T],
) {
    for v in out.iter_mut() {
        *v = T::from(0.0);
    }
    evaluate(params, prepared, config, angles, &mut Total(out));
}

/// Same, split per lobe: `out[c] = [R, TT, TRT]` contributions (each already divided by
/// cos²θ_d); disabled lobes 0.
pub fn scattering_by_lobe<T: ModelNum>(
    params: &Params<T>,
    config: &ModelConfig,
    angles: &Angles,
    out: &mut [[T; 3]],
) {
    assert_eq!(out.len(), params.sigma_a.len(), "one output per channel");
    for o in out.iter_mut() {
        *o = [T::from(0.0), T::from(0.0), T::from(0.0)];
    }
    evaluate(
        params,
        &Prepared::new(params),
        config,
        angles,
        &mut ByLobe(out),
    );
}

/// Sum of the lobes per channel.
struct Total<'a, T>(&'a mut [T]);
impl<T: ModelNum> Sink<T> for Total<'_, T> {
    #[inline]
    fn add(&mut self, channel: usize, _lobe: usize, value: T) {
        self.0[channel] += value;
    }
}

/// Lobes kept apart per channel.
struct ByLobe<'a, T>(&'a mut [[T; 3]]);
impl<T: ModelNum> Sink<T> for ByLobe<'_, T> {
    #[inline]
    fn add(&mut self, channel: usize, lobe: usize, value: T) {
        self.0[channel][lobe] += value;
    }
}

/// The parameter-only factors of `S`, shared by every sample of a batch (reciprocals too, so
/// the per-sample path divides less).
struct Prepared<T> {
    /// `(α_p, 1/β_p)` of R, TT, TRT.
    shapes: [(T, T); 3],
    /// The eccentric index's `(η*_1 + η*_2, η*_1 − η*_2)`.
    eccentric: (T, T),
    glint: GlintParams<T>,
}

impl<T: ModelNum> Prepared<T> {
    fn new(params: &Params<T>) -> Self {
        let shape = |p| {
            let (alpha, beta) = lobe_shape(p, &params.alpha_r, &params.beta_r);
            (alpha, beta.recip())
        };
        Prepared {
            shapes: [shape(0), shape(1), shape(2)],
            eccentric: eccentric_terms(&params.eta, &params.eccentricity),
            glint: GlintParams::new(
                &params.k_g,
                &params.w_c,
                &params.delta_eta_prime,
                &params.delta_h_m,
            ),
        }
    }

    /// `M_p(θ_h)`, as [`longitudinal::longitudinal`].
    #[inline]
    fn longitudinal(&self, p: usize, theta_h: f64) -> T {
        let (alpha, inv_beta) = &self.shapes[p];
        gaussian_inv(-alpha.clone() + theta_h, inv_beta)
    }
}

/// `S = Σ_p M_p(θ_h)·N_p(θ_d, φ, φ_h)/cos²θ_d` over the enabled lobes; disabled lobes and effects
/// are skipped before any of their work (roots, caustics, η*).
fn evaluate<T: ModelNum, S: Sink<T>>(
    params: &Params<T>,
    prepared: &Prepared<T>,
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
        let br = bravais_indices(&params.eta.seed(), sin_td, cos_td);
        if lobes.r {
            let m = prepared.longitudinal(0, ha.theta_h) * inv_cos2;
            add_r(&br, &params.eta, ha.phi, n, &m, sink);
        }
        if lobes.tt {
            let m = prepared.longitudinal(1, ha.theta_h) * inv_cos2;
            let map = ExitMap::new(config.mode, 1, br.eta_p.clone());
            add_root_sum(1, &map, &br, &params.eta, ha.phi, &params.sigma_a, &m, sink);
        }
    }
    if lobes.trt {
        let eta = if config.effects.eccentricity {
            eccentric_index_at(&prepared.eccentric, ha.phi_h)
        } else {
            params.eta.clone()
        };
        let br = bravais_indices(&eta.seed(), sin_td, cos_td);
        let m = prepared.longitudinal(2, ha.theta_h) * inv_cos2;
        let map = ExitMap::new(config.mode, 2, br.eta_p.clone());
        if config.effects.glints {
            add_trt_with_glints(
                &map,
                &br,
                &eta,
                ha.phi,
                &params.sigma_a,
                &prepared.glint,
                &m,
                sink,
            );
        } else {
            add_root_sum(2, &map, &br, &eta, ha.phi, &params.sigma_a, &m, sink);
        }
    }
}
