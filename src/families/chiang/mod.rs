//! The Chiang et al. 2016 hair model as pbrt-v4 evaluates it, turned into a whole-fibre `S` in the
//! project's conventions (CHIANG.md): parameters, effect switches, the width-quadrature knob, and
//! `S = [Σ_{p<3} M_p Ñ_p + M₃ Ā₃/(2π)] / cosθ_i`, generic over the number type for exact
//! AD Jacobians. One pure function per equation lives in the submodules:
//! - [`longitudinal`]: `v₀`, the tilt on θ_r, `M_p`;
//! - [`azimuthal`]: `N_p`, the logistics' kinks, the width integral;
//! - [`width`]: which rule a model uses (`auto` or N) and its nodes for one exit direction;
//! - [`evaluator`]: batches grouped by exit direction so the width integral is paid once each;
//! - [`fixed_eta`]: the fit's f64 values and Jacobian with η fixed (hand-written chain rule);
//! - [`file`]: the Chiang parameter file (JSON names of CHIANG.md);
//! - [`jacobian`]: seeding dual numbers, Jacobians of a batch;
//!
//! The fit's side of the family (its `Forward`, free parameters, `--fix` names) is
//! `crate::families::chiang::fit`.
//!
//! What d'Eon and Frostbite share with it (the lobe `M` and its `I₀`, the cylinder's Fresnel, `T`,
//! `A_p`, `Φ_p`, the trimmed logistic, the Gauss–Legendre width rules) is
//! [`crate::families::shared`]'s.
//!
//! Angles reuse [`crate::geometry::Angles`]: the frame and sign conventions are MODEL.md's.

use std::fmt;
use std::sync::{Arc, OnceLock};

use num_dual::DualNum;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::families::effects::{Effects, Lobes, ModelConfig};
use crate::families::table::{LobeColumn, Term, TermSet};
use crate::geometry::Angles;
pub use crate::geometry::ParamFact;
use crate::geometry::{Fitted, Interval, Unit};

pub mod azimuthal;
pub mod cost;
pub mod demo;
pub mod evaluator;
pub mod export;
pub mod family;
pub mod file;
pub mod fit;
pub mod fixed_eta;
pub mod jacobian;
mod logistics;
pub mod longitudinal;
pub mod variant;
pub mod width;

pub use crate::families::shared::quadrature::{WidthNode, WidthRule, DEFAULT_WIDTH_NODES};
pub use azimuthal::{AzimuthalTable, WidthSet};
pub use evaluator::{scattering, scattering_batch, scattering_from_table};
pub use file::ChiangParamFile;
pub use jacobian::{batch_jacobian, batch_jacobian_static, seeded};
pub use width::WidthNodes;

/// Chiang's terms as `--terms` names them ([`ChiangEffects`] holds which are on).
pub const TERMS: [Term; 4] = [
    Term {
        name: "R",
        meaning: "p = 0, reflection",
        column: LobeColumn::R,
    },
    Term {
        name: "TT",
        meaning: "p = 1, transmission",
        column: LobeColumn::TT,
    },
    Term {
        name: "TRT",
        meaning: "p = 2, one internal reflection",
        column: LobeColumn::TRT,
    },
    Term {
        name: "residual",
        meaning: "p >= 3 summed, azimuthally uniform",
        column: LobeColumn::TRT,
    },
];

/// Which terms of `S` are on; what is off is not computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct ChiangEffects {
    /// p = 0, reflection.
    pub r: bool,
    /// p = 1, transmission.
    pub tt: bool,
    /// p = 2, one internal reflection.
    pub trt: bool,
    /// p ≥ 3 summed: `M₃ Ā₃/(2π)`, azimuthally uniform.
    pub residual: bool,
}

impl Default for ChiangEffects {
    fn default() -> Self {
        ChiangEffects {
            r: true,
            tt: true,
            trt: true,
            residual: true,
        }
    }
}

impl ChiangEffects {
    /// Parse a list such as `"R,TT,TRT,residual"` (case-insensitive), as `--terms` takes it.
    pub fn parse(list: &str) -> Result<ChiangEffects> {
        TermSet::parse(list, &TERMS, "chiang").map(ChiangEffects::from_terms)
    }

    /// The terms of `on` (bits over [`TERMS`]).
    pub fn from_terms(on: TermSet) -> ChiangEffects {
        ChiangEffects {
            r: on.has(0),
            tt: on.has(1),
            trt: on.has(2),
            residual: on.has(3),
        }
    }

    /// These terms as bits over [`TERMS`].
    pub fn terms(self) -> TermSet {
        let bits = [self.r, self.tt, self.trt, self.residual];
        TermSet(
            bits.iter()
                .enumerate()
                .map(|(k, &on)| (on as u32) << k)
                .sum(),
        )
    }

    /// `(these effects without the residual, the residual alone if on)`.
    pub fn split_residual(&self) -> (ChiangEffects, ChiangEffects) {
        let off = ChiangEffects {
            r: false,
            tt: false,
            trt: false,
            residual: false,
        };
        (
            ChiangEffects {
                residual: false,
                ..*self
            },
            ChiangEffects {
                residual: self.residual,
                ..off
            },
        )
    }

    /// The parameters `S` depends on under these effects, for `n_channels` absorption values.
    pub fn parameters(&self, n_channels: usize) -> Vec<ChiangParamName> {
        let lobes = self.r || self.tt || self.trt;
        let mut out = vec![ChiangParamName::Eta]; // Fresnel enters every term
        if self.tt || self.trt || self.residual {
            out.extend((0..n_channels).map(ChiangParamName::SigmaA));
        }
        out.push(ChiangParamName::BetaM); // every term has an M_p
        if lobes {
            // the residual is azimuthally uniform and untilted
            out.push(ChiangParamName::BetaN);
            out.push(ChiangParamName::Alpha);
        }
        out
    }
}

/// A Chiang parameter, by its JSON name of CHIANG.md.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ChiangParamName {
    Eta,
    SigmaA(usize),
    BetaM,
    BetaN,
    /// Stored in radians in [`ChiangParams`], degrees in files.
    Alpha,
}

impl ChiangParamName {
    /// `"eta"`, `"sigma_a[1]"`, `"beta_m"`, `"beta_n"`, `"alpha_deg"`.
    pub fn json_name(&self) -> String {
        match self {
            ChiangParamName::SigmaA(c) => format!("sigma_a[{c}]"),
            other => PARAMETERS[other.fact_index()].name.into(),
        }
    }

    fn fact_index(&self) -> usize {
        match self {
            ChiangParamName::Eta => 0,
            ChiangParamName::SigmaA(_) => 1,
            ChiangParamName::BetaM => 2,
            ChiangParamName::BetaN => 3,
            ChiangParamName::Alpha => 4,
        }
    }

    /// The row of [`PARAMETERS`] for this parameter.
    pub fn fact(&self) -> &'static ParamFact {
        &PARAMETERS[self.fact_index()]
    }
}

impl fmt::Display for ChiangParamName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.json_name())
    }
}

/// The one table of Chiang parameter facts (CHIANG.md "Parameters"); pbrt-v4 defaults where the
/// project uses one.
pub const PARAMETERS: [ParamFact; 5] = [
    ParamFact {
        name: "eta",
        symbol: "η",
        meaning: "cortex index of refraction",
        unit: Unit::Dimensionless,
        // CHIANG.md says > 1. Capped at 10 as in the Marschner table: no fibre comes near it
        // (diamond is 2.42), and η² overflows for η near 1e154, turning S into NaN.
        domain: Interval::open_closed(1.0, 10.0),
        default: Some(1.55),
        fit_lo: 1.000001,
        fit_hi: Some(2.5),
        typical: (1.5, 1.6),
        reference: Some(1.55),
        fitted: Fitted::OnRequest,
        ..ParamFact::BASE
    },
    ParamFact {
        name: "sigma_a",
        symbol: "σ_a",
        per_channel: true,
        meaning: "absorption per unit fibre radius, one value per colour channel",
        unit: Unit::PerFiberRadius,
        domain: Interval::closed_open(0.0, f64::INFINITY),
        default: None,
        // σ_a = 50 per radius already removes all transmitted light.
        fit_lo: 0.0,
        fit_hi: Some(50.0),
        typical: (0.05, 2.0),
        reference: Some(0.4),
        fitted: Fitted::Yes,
        ..ParamFact::BASE
    },
    ParamFact {
        name: "beta_m",
        symbol: "β_m",
        meaning: "longitudinal roughness",
        unit: Unit::Dimensionless,
        domain: Interval::open_closed(0.0, 1.0),
        default: None,
        // pbrt-v4 clamps β to [0.01, 1].
        fit_lo: 0.01,
        fit_hi: Some(1.0),
        typical: (0.1, 0.5),
        reference: Some(0.3),
        fitted: Fitted::Yes,
        ..ParamFact::BASE
    },
    ParamFact {
        name: "beta_n",
        symbol: "β_n",
        meaning: "azimuthal roughness",
        unit: Unit::Dimensionless,
        domain: Interval::open_closed(0.0, 1.0),
        default: None,
        // Below 0.05 the logistic peaks get too narrow for the default 1024 width nodes.
        fit_lo: 0.05,
        fit_hi: Some(1.0),
        typical: (0.1, 0.5),
        reference: Some(0.3),
        fitted: Fitted::Yes,
        ..ParamFact::BASE
    },
    ParamFact {
        name: "alpha_deg",
        symbol: "α",
        meaning: "cuticle-scale tilt; the R peak sits at theta_h = +alpha_deg",
        unit: Unit::Degrees,
        domain: Interval::open(-90.0, 90.0),
        default: None,
        // As the Marschner α_R: a tilt beyond ±30° is not hair (|α| ≤ 5° in practice).
        fit_lo: -30.0,
        fit_hi: Some(30.0),
        typical: (-5.0, 5.0),
        reference: Some(2.0),
        fitted: Fitted::Yes,
        ..ParamFact::BASE
    },
];

/// The Chiang family: its facts here, its fit in [`fit`]; listed in `crate::families::registry`.
pub struct ChiangFamily;

impl crate::geometry::FamilyFacts for ChiangFamily {
    fn name(&self) -> &'static str {
        "chiang"
    }
    fn title(&self) -> &'static str {
        "Chiang"
    }
    fn citation(&self) -> &'static str {
        "Chiang 2016 (pbrt-v4's hair)"
    }
    fn parameters(&self) -> &'static [ParamFact] {
        &PARAMETERS
    }
    fn own_options(&self) -> &'static [&'static str] {
        &["--terms", "--width-nodes"]
    }
}

/// Chiang parameters, α in RADIANS, generic over the number type.
#[derive(Debug, Clone, PartialEq)]
pub struct ChiangParams<T> {
    pub eta: T,
    pub sigma_a: Vec<T>,
    pub beta_m: T,
    pub beta_n: T,
    pub alpha: T,
}

impl<T: Clone> ChiangParams<T> {
    /// The value of `name` (radians for α). Panics on a channel that does not exist.
    pub fn get(&self, name: ChiangParamName) -> T {
        match name {
            ChiangParamName::Eta => self.eta.clone(),
            ChiangParamName::SigmaA(c) => self.sigma_a[c].clone(),
            ChiangParamName::BetaM => self.beta_m.clone(),
            ChiangParamName::BetaN => self.beta_n.clone(),
            ChiangParamName::Alpha => self.alpha.clone(),
        }
    }

    /// Set `name` to `value` (radians for α).
    pub fn set(&mut self, name: ChiangParamName, value: T) {
        match name {
            ChiangParamName::Eta => self.eta = value,
            ChiangParamName::SigmaA(c) => self.sigma_a[c] = value,
            ChiangParamName::BetaM => self.beta_m = value,
            ChiangParamName::BetaN => self.beta_n = value,
            ChiangParamName::Alpha => self.alpha = value,
        }
    }

    /// Map `f` over every parameter (e.g. lift f64 to duals).
    pub fn map<U>(&self, f: impl Fn(&T) -> U) -> ChiangParams<U> {
        ChiangParams {
            eta: f(&self.eta),
            sigma_a: self.sigma_a.iter().map(&f).collect(),
            beta_m: f(&self.beta_m),
            beta_n: f(&self.beta_n),
            alpha: f(&self.alpha),
        }
    }
}

impl ChiangParams<f64> {
    /// Check CHIANG.md's domains; the error names the parameter (file name and units) and range.
    pub fn validate(&self) -> Result<()> {
        crate::geometry::sigma_a::require_channels(&self.sigma_a)?;
        let mut checks = vec![
            (ChiangParamName::Eta, self.eta),
            (ChiangParamName::BetaM, self.beta_m),
            (ChiangParamName::BetaN, self.beta_n),
            (ChiangParamName::Alpha, self.alpha.to_degrees()),
        ];
        checks.extend(
            self.sigma_a
                .iter()
                .enumerate()
                .map(|(c, &s)| (ChiangParamName::SigmaA(c), s)),
        );
        for (name, value) in checks {
            if let Err(message) = name.fact().check(value) {
                return Err(Error::Parameter {
                    name: name.json_name(),
                    value,
                    message,
                });
            }
        }
        Ok(())
    }
}

/// What one evaluation computes: the effect switches and the width rule. A plain rule is built
/// on first use: every command carries a `ChiangModel`, and a Marschner run should not pay for
/// 1024 Gauss–Legendre nodes it never reads (~18 ms, 3% of a 1M-row `eval`).
#[derive(Debug, Clone)]
pub struct ChiangModel {
    pub effects: ChiangEffects,
    width: WidthNodes,
    rule: OnceLock<Arc<WidthRule>>,
}

impl ChiangModel {
    /// The plain rule with `width_nodes` Gauss–Legendre nodes in γ (error if out of range).
    pub fn new(effects: ChiangEffects, width_nodes: usize) -> Result<ChiangModel> {
        ChiangModel::with_width(effects, WidthNodes::Fixed(width_nodes))
    }

    /// `effects` with the width rule `width` (error if a count is out of range).
    pub fn with_width(effects: ChiangEffects, width: WidthNodes) -> Result<ChiangModel> {
        Ok(ChiangModel {
            effects,
            width: width.check()?,
            rule: OnceLock::new(),
        })
    }

    /// The width rule.
    pub fn width(&self) -> WidthNodes {
        self.width
    }

    /// The width nodes of exit direction (`theta_r`, `phi`) at `eta`, `beta_n`: the plain
    /// rule's for both parts, or the composite rule's for the lobes (written into `scratch`)
    /// with [`width::RESIDUAL_NODES`] plain nodes for the residual.
    pub fn width_nodes_for<'a>(
        &'a self,
        eta: f64,
        beta_n: f64,
        theta_r: f64,
        phi: f64,
        scratch: &'a mut WidthScratch,
    ) -> WidthSet<'a> {
        // The one plain rule a model uses: its own count, or the residual's under auto.
        let plain = self.rule.get_or_init(|| {
            let n = match self.width {
                WidthNodes::Fixed(n) => n,
                _ => width::RESIDUAL_NODES,
            };
            WidthRule::cached(n).expect("the node count was checked in with_width")
        });
        if let WidthNodes::Fixed(_) = self.width {
            return WidthSet {
                lobes: &plain.nodes,
                residual: &plain.nodes,
            };
        }
        let density = self.width.density(beta_n);
        let (breaks, nodes) = (&mut scratch.breaks, &mut scratch.nodes);
        width::split_nodes(&self.effects, density, eta, theta_r, phi, breaks, nodes);
        WidthSet {
            lobes: nodes,
            residual: &plain.nodes,
        }
    }
}

/// Buffers the composite rule is written into, reused across exit directions.
#[derive(Debug, Default)]
pub struct WidthScratch {
    breaks: Vec<f64>,
    nodes: Vec<WidthNode>,
}

impl ChiangModel {
    /// The model `setup` configures: its terms (`--terms`, over [`TERMS`]; default all) and
    /// width rule (`--width-nodes`, checked when it was read).
    pub fn of_setup(setup: &crate::families::ModelSetup) -> ChiangModel {
        let effects = setup
            .terms
            .map_or_else(ChiangEffects::default, ChiangEffects::from_terms);
        ChiangModel::with_width(effects, setup.width_nodes).expect("a checked width rule")
    }
}

impl Default for ChiangModel {
    fn default() -> Self {
        ChiangModel::with_width(ChiangEffects::default(), WidthNodes::Auto)
            .expect("auto needs no count")
    }
}

/// Validate angles for this model (same domain as MODEL.md: |θ| < 90°, finite).
pub fn validate_angles(angles: &Angles) -> Result<()> {
    angles.validate()
}

/// Evaluate `S` from its parts: `[Σ_{p<3} M_p Ñ_p + M₃ Ā₃/(2π)] / cosθ_i` for one channel.
#[inline]
pub fn combine<T: DualNum<f64>>(m: &[T; 4], lobes: &[T; 3], residual: &T, cos_theta_i: f64) -> T {
    let sum = m[0].clone() * lobes[0].clone()
        + m[1].clone() * lobes[1].clone()
        + m[2].clone() * lobes[2].clone()
        + m[3].clone() * residual.clone() * std::f64::consts::FRAC_1_PI * 0.5;
    sum / cos_theta_i
}

/// Every Chiang parameter for `nc` channels, in output order (the table's order).
pub fn all_parameters(nc: usize) -> Vec<ChiangParamName> {
    let mut v = vec![ChiangParamName::Eta];
    v.extend((0..nc).map(ChiangParamName::SigmaA));
    v.extend([
        ChiangParamName::BetaM,
        ChiangParamName::BetaN,
        ChiangParamName::Alpha,
    ]);
    v
}

/// The table's reference values: what a fit holds a parameter it does not vary at.
pub fn reference_params(nc: usize) -> ChiangParams<f64> {
    let r = |i: usize| PARAMETERS[i].held();
    ChiangParams {
        eta: r(0),
        sigma_a: vec![r(1); nc],
        beta_m: r(2),
        beta_n: r(3),
        alpha: r(4).to_radians(),
    }
}

/// The Marschner-shaped record of a Chiang fit's lobes (fit.json `model`): its lobes on, no
/// glints, no eccentricity (the report draws those lobes).
pub fn lobes_config(effects: &ChiangEffects) -> ModelConfig {
    ModelConfig {
        mode: Default::default(),
        effects: Effects {
            lobes: Lobes {
                r: effects.r,
                tt: effects.tt,
                trt: effects.trt || effects.residual,
            },
            glints: false,
            eccentricity: false,
        },
    }
}
