//! The parameter table: every model parameter's facts (JSON name, symbol, unit, domain, fit bound,
//! typical range, default, the effects that use it) in one line each. The parameter file, the
//! domain check, the fit's bounds and parameter lists, `--effects auto` and the report read it here.
//!
//! Values in the table are in FILE units (degrees for angles); the accessors that return model
//! values convert to the model's units (radians) with `f64::to_radians`.
//!
//! Over 500 lines because rustfmt lays each table line out as a ~25-line struct literal; splitting
//! the file would split the table.

use std::f64::consts::FRAC_1_SQRT_2;

use super::{Effects, ParamName};
use crate::geometry::fact::{Fitted, ParamFact};
use crate::geometry::units::{Interval, Unit};

/// Lowest eccentricity: `η*_1 = 2(η − 1)a² − η + 2 > 1` exactly when `a > 1/√2`.
pub const MIN_ECCENTRICITY: f64 = FRAC_1_SQRT_2;
/// Margin that keeps a fit strictly inside an open end of the domain (η > 1, a > 1/√2, Δ > 0).
const OPEN_MARGIN: f64 = 1e-6;

/// The part of the model that needs a parameter: when it is off, `S` does not depend on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UsedBy {
    /// Every lobe (Fresnel, Bravais indices, longitudinal Gaussians).
    EveryLobe,
    /// The transmitted lobes TT and TRT.
    Transmission,
    /// TRT with glints.
    Glints,
    /// TRT with eccentricity.
    Eccentricity,
}

impl UsedBy {
    /// True when `effects` switch on a part that uses the parameter.
    pub fn active(self, effects: &Effects) -> bool {
        let l = effects.lobes;
        match self {
            UsedBy::EveryLobe => true,
            UsedBy::Transmission => l.tt || l.trt,
            UsedBy::Glints => l.trt && effects.glints,
            UsedBy::Eccentricity => l.trt && effects.eccentricity,
        }
    }

    /// Words for documentation.
    pub fn describe(self) -> &'static str {
        match self {
            UsedBy::EveryLobe => "R, TT, TRT",
            UsedBy::Transmission => "TT, TRT",
            UsedBy::Glints => "TRT glints",
            UsedBy::Eccentricity => "TRT eccentricity",
        }
    }
}

/// The table, in output order (fit.json, the report, `--fix` names).
pub const TABLE: [ParamFact; 9] = [
    ParamFact {
        name: "eta",
        symbol: "η",
        meaning: "index of refraction of the cortex",
        unit: Unit::Dimensionless,
        domain: Interval { lo: 1.0, lo_open: true, hi: 10.0, hi_open: false },
        domain_why: "refraction needs eta > 1, and no fiber comes near 10 (diamond is 2.42; far larger values overflow the model)",
        fit_lo: 1.0 + OPEN_MARGIN,
        fit_hi: Some(2.5),
        typical: (1.5, 1.6),
        default: Some(1.55),
        reference: Some(1.55),
        fitted: Fitted::OnRequest,
        ..ParamFact::BASE
    },
    ParamFact {
        name: "sigma_a",
        per_channel: true,
        symbol: "σ_a",
        meaning: "absorption coefficient, one per colour channel",
        unit: Unit::PerFiberRadius,
        domain: Interval::open_above(0.0, false),
        domain_why: "absorption cannot be negative",
        // Far beyond the typical range (σ_a = 50 already removes all transmitted light): only
        // stops a direction the data leave flat from running away.
        fit_lo: 0.0,
        fit_hi: Some(50.0),
        typical: (0.05, 2.0),
        default: None,
        reference: Some(0.4),
        fitted: Fitted::Yes,
        ..ParamFact::BASE
    },
    ParamFact {
        name: "alpha_r_deg",
        symbol: "α_R",
        meaning: "longitudinal shift of the R lobe (negative: toward the root)",
        unit: Unit::Degrees,
        domain: Interval {
            lo: f64::NEG_INFINITY,
            lo_open: true,
            hi: f64::INFINITY,
            hi_open: true,
        },
        domain_why: "any finite shift",
        // A cuticle tilt beyond ±30° is not hair; unbounded, a flat direction let α_R wander to
        // −1434° on a scan that does not span θ_h.
        fit_lo: -30.0,
        fit_hi: Some(30.0),
        typical: (-10.0, -5.0),
        default: None,
        reference: None,
        fitted: Fitted::Yes,
        ..ParamFact::BASE
    },
    ParamFact {
        name: "beta_r_deg",
        symbol: "β_R",
        meaning: "longitudinal width (standard deviation) of the R lobe",
        unit: Unit::Degrees,
        domain: Interval::open_above(0.0, true),
        domain_why: "a Gaussian needs a positive width",
        fit_lo: 0.01,
        fit_hi: Some(30.0),
        typical: (5.0, 10.0),
        default: None,
        reference: None,
        fitted: Fitted::Yes,
        ..ParamFact::BASE
    },
    ParamFact {
        name: "k_g",
        symbol: "k_G",
        meaning: "glint scale factor",
        unit: Unit::Dimensionless,
        domain: Interval::open_above(0.0, false),
        domain_why: "a glint cannot be negative",
        fit_lo: 0.0,
        fit_hi: Some(100.0),
        typical: (0.5, 5.0),
        default: None,
        reference: Some(1.0),
        fitted: Fitted::Yes,
        ..ParamFact::BASE
    },
    ParamFact {
        name: "w_c_deg",
        symbol: "w_c",
        meaning: "azimuthal width of the glint lobes",
        unit: Unit::Degrees,
        domain: Interval::open_above(0.0, true),
        domain_why: "a Gaussian needs a positive width",
        fit_lo: 0.01,
        fit_hi: Some(60.0),
        typical: (10.0, 25.0),
        default: None,
        reference: None,
        fitted: Fitted::Yes,
        ..ParamFact::BASE
    },
    ParamFact {
        name: "eccentricity",
        symbol: "a",
        meaning: "cross-section eccentricity (ratio of the axes)",
        unit: Unit::Dimensionless,
        domain: Interval { lo: MIN_ECCENTRICITY, lo_open: true, hi: 1.0, hi_open: false },
        domain_why: "a ratio of axes is at most 1; at or below 1/sqrt(2) the TRT Bravais index can drop under 1",
        fit_lo: MIN_ECCENTRICITY + OPEN_MARGIN,
        fit_hi: Some(1.0),
        typical: (0.85, 1.0),
        default: Some(1.0),
        reference: Some(1.0),
        fitted: Fitted::Yes,
        ..ParamFact::BASE
    },
    ParamFact {
        name: "delta_eta_prime",
        symbol: "Δη′",
        meaning: "range of η′ over which the glint fades after the caustics merge",
        unit: Unit::Dimensionless,
        domain: Interval::open_above(0.0, true),
        domain_why: "a fade needs a positive range",
        fit_lo: OPEN_MARGIN,
        fit_hi: None,
        typical: (0.2, 0.4),
        default: Some(0.3),
        reference: Some(0.3),
        fitted: Fitted::No,
        ..ParamFact::BASE
    },
    ParamFact {
        name: "delta_h_m",
        symbol: "Δh_M",
        meaning: "limit of the caustic's width in h",
        unit: Unit::Dimensionless,
        domain: Interval::open_above(0.0, true),
        domain_why: "a width limit must be positive",
        fit_lo: OPEN_MARGIN,
        fit_hi: None,
        typical: (0.4, 0.6),
        default: Some(0.5),
        reference: Some(0.5),
        fitted: Fitted::No,
        ..ParamFact::BASE
    },
];

/// The table's parameters in its order: line `k` of [`TABLE`] is `NAMES[k]` (`SigmaA(0)` stands
/// for every channel's σ_a), read by the parts of the model in `USED_BY[k]`.
pub const NAMES: [ParamName; 9] = [
    ParamName::Eta,
    ParamName::SigmaA(0),
    ParamName::AlphaR,
    ParamName::BetaR,
    ParamName::KG,
    ParamName::WC,
    ParamName::Eccentricity,
    ParamName::DeltaEtaPrime,
    ParamName::DeltaHM,
];
const USED_BY: [UsedBy; 9] = [
    UsedBy::EveryLobe,
    UsedBy::Transmission,
    UsedBy::EveryLobe,
    UsedBy::EveryLobe,
    UsedBy::Glints,
    UsedBy::Glints,
    UsedBy::Eccentricity,
    UsedBy::Glints,
    UsedBy::Glints,
];

impl ParamName {
    /// This parameter's line of [`TABLE`] (every `SigmaA(c)` shares one).
    pub fn fact(self) -> &'static ParamFact {
        &TABLE[self.line()]
    }

    /// The part of the model that reads it.
    pub fn used_by(self) -> UsedBy {
        USED_BY[self.line()]
    }

    fn line(self) -> usize {
        let key = match self {
            ParamName::SigmaA(_) => ParamName::SigmaA(0),
            other => other,
        };
        NAMES
            .iter()
            .position(|&n| n == key)
            .expect("every ParamName has a line in the parameter table")
    }

    /// The parameter named `name` (`"eta"`, `"sigma_a[1]"`, `"w_c_deg"`), if any.
    pub fn from_json_name(name: &str) -> Option<ParamName> {
        let sigma = ParamName::SigmaA(0).fact().name;
        if let Some(c) = name
            .strip_prefix(sigma)
            .and_then(|r| r.strip_prefix('['))
            .and_then(|r| r.strip_suffix(']'))
        {
            return c.parse().ok().map(ParamName::SigmaA);
        }
        TABLE
            .iter()
            .zip(NAMES)
            .find(|(s, n)| s.name == name && !matches!(n, ParamName::SigmaA(_)))
            .map(|(_, n)| n)
    }
}

/// Every parameter in output order, σ_a expanded to `n_channels` entries.
pub fn all_parameters(n_channels: usize) -> Vec<ParamName> {
    expand(NAMES.into_iter(), n_channels)
}

/// The parameters `S` depends on under `effects`, in output order.
pub fn used_parameters(effects: &Effects, n_channels: usize) -> Vec<ParamName> {
    expand(
        NAMES.into_iter().filter(|n| n.used_by().active(effects)),
        n_channels,
    )
}

/// The parameters a fit under `effects` varies before `--fix` (η only with `free_eta`).
pub fn fitted_parameters(effects: &Effects, n_channels: usize, free_eta: bool) -> Vec<ParamName> {
    expand(
        NAMES.into_iter().filter(|n| {
            n.used_by().active(effects)
                && match n.fact().fitted {
                    Fitted::Yes => true,
                    Fitted::OnRequest => free_eta,
                    Fitted::No => false,
                }
        }),
        n_channels,
    )
}

fn expand(names: impl Iterator<Item = ParamName>, n_channels: usize) -> Vec<ParamName> {
    let mut out = Vec::new();
    for name in names {
        match name {
            ParamName::SigmaA(_) => out.extend((0..n_channels).map(ParamName::SigmaA)),
            name => out.push(name),
        }
    }
    out
}

/// MODEL.md's typical range of `name` in natural units (radians for angles): the start design box.
pub fn typical_range(name: ParamName) -> (f64, f64) {
    name.fact().typical_range()
}

/// True for parameters stored in radians and reported in degrees.
pub fn is_angle(name: ParamName) -> bool {
    name.fact().unit == Unit::Degrees
}

/// Factor from natural units to reporting units (degrees for angles).
pub fn report_factor(name: ParamName) -> f64 {
    name.fact().unit.file_factor()
}

/// The table's reference values (defaults, else mid typical range): a neutral parameter set with
/// `n_channels` channels, the value of every parameter a fit does not vary.
pub fn reference_params(n_channels: usize) -> super::Params<f64> {
    super::Params::from_fn(n_channels, |name| name.fact().reference_value())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The whole typical range written in radians is caught; the typical range in degrees and
    /// zero are not.
    #[test]
    fn radians_in_a_degrees_key_look_like_radians() {
        for s in TABLE.iter().filter(|s| s.unit == Unit::Degrees) {
            let (a, b) = s.typical;
            for deg in [a, b, 0.5 * (a + b)] {
                assert!(s.looks_like_radians(deg.to_radians()), "{} {deg}", s.name);
                assert!(!s.looks_like_radians(deg), "{} {deg}", s.name);
            }
            assert!(!s.looks_like_radians(0.0), "{}", s.name);
        }
        assert!(!ParamName::KG.fact().looks_like_radians(0.01));
    }

    #[test]
    fn every_fit_bound_and_typical_range_lies_inside_the_domain() {
        for s in &TABLE {
            let hi = s.fit_hi.unwrap_or(f64::MAX);
            assert!(
                s.domain.contains(s.fit_lo) && s.domain.contains(hi),
                "{}",
                s.name
            );
            assert!(s.fit_lo <= s.typical.0 && s.typical.1 <= hi, "{}", s.name);
            for v in [s.default, s.reference].into_iter().flatten() {
                assert!(s.domain.contains(v), "{}", s.name);
            }
        }
    }

    #[test]
    fn json_names_round_trip() {
        for name in all_parameters(3) {
            assert_eq!(ParamName::from_json_name(&name.json_name()), Some(name));
        }
        assert_eq!(ParamName::from_json_name("sigma_a"), None);
        assert_eq!(ParamName::from_json_name("sigma_a[x]"), None);
    }

    #[test]
    fn interval_text_and_membership() {
        let eta = ParamName::Eta.fact().domain;
        assert_eq!(eta.text(), "(1, 10]");
        assert!(!eta.contains(1.0) && eta.contains(10.0) && !eta.contains(1e155));
        let a = ParamName::Eccentricity.fact().domain;
        assert_eq!(a.text(), "(0.70711, 1]");
        assert!(!a.contains(f64::NAN) && !a.contains(FRAC_1_SQRT_2) && a.contains(1.0));
    }
}
