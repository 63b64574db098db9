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

/// Lowest eccentricity: `η*_1 = 2(η − 1)a² − η + 2 > 1` exactly when `a > 1/√2`.
pub const MIN_ECCENTRICITY: f64 = FRAC_1_SQRT_2;
/// Margin that keeps a fit strictly inside an open end of the domain (η > 1, a > 1/√2, Δ > 0).
const OPEN_MARGIN: f64 = 1e-6;

/// The unit a parameter is written in (files, reports) and held in (the model).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// A pure number.
    Dimensionless,
    /// Degrees in files and reports, radians inside the model.
    Degrees,
    /// Absorption coefficient per unit fiber RADIUS (the fiber's radius is the length unit).
    PerFiberRadius,
}

impl Unit {
    /// Short label for report tables: `"deg"`, `"per fiber radius"`, or `""`.
    pub fn label(self) -> &'static str {
        match self {
            Unit::Dimensionless => "",
            Unit::Degrees => "deg",
            Unit::PerFiberRadius => "per fiber radius",
        }
    }

    /// Words for documentation.
    pub fn describe(self) -> &'static str {
        match self {
            Unit::Dimensionless => "dimensionless",
            Unit::Degrees => "degrees (radians inside the model)",
            Unit::PerFiberRadius => "per fiber radius",
        }
    }

    /// Factor from the model's value to the file's value (180/π for angles).
    pub fn file_factor(self) -> f64 {
        match self {
            Unit::Degrees => 180.0 / std::f64::consts::PI,
            _ => 1.0,
        }
    }

    /// A file value in model units.
    pub fn to_model(self, file_value: f64) -> f64 {
        match self {
            Unit::Degrees => file_value.to_radians(),
            _ => file_value,
        }
    }
}

/// An interval of allowed values, file units; an infinite end is open.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub lo_open: bool,
    pub hi: f64,
    pub hi_open: bool,
}

impl Interval {
    const fn open_above(lo: f64, lo_open: bool) -> Interval {
        Interval {
            lo,
            lo_open,
            hi: f64::INFINITY,
            hi_open: true,
        }
    }

    /// `(lo, hi]`.
    pub const fn open_closed(lo: f64, hi: f64) -> Interval {
        Interval {
            lo,
            lo_open: true,
            hi,
            hi_open: false,
        }
    }

    /// `[lo, hi)`.
    pub const fn closed_open(lo: f64, hi: f64) -> Interval {
        Interval {
            lo,
            lo_open: false,
            hi,
            hi_open: true,
        }
    }

    /// `(lo, hi)`.
    pub const fn open(lo: f64, hi: f64) -> Interval {
        Interval {
            lo,
            lo_open: true,
            hi,
            hi_open: true,
        }
    }

    /// True for a finite `x` inside the interval.
    pub fn contains(&self, x: f64) -> bool {
        x.is_finite()
            && (if self.lo_open {
                x > self.lo
            } else {
                x >= self.lo
            })
            && (if self.hi_open {
                x < self.hi
            } else {
                x <= self.hi
            })
    }

    /// `(1, 10]`, `[0, inf)`: five significant digits, enough to tell the ends apart.
    pub fn text(&self) -> String {
        let num = |x: f64| {
            if x.is_infinite() {
                if x > 0.0 { "inf" } else { "-inf" }.to_string()
            } else if x == x.round() {
                format!("{x}")
            } else {
                format!("{x:.5}")
                    .trim_end_matches('0')
                    .trim_end_matches('.')
                    .to_string()
            }
        };
        format!(
            "{}{}, {}{}",
            if self.lo_open { '(' } else { '[' },
            num(self.lo),
            num(self.hi),
            if self.hi_open { ')' } else { ']' }
        )
    }
}

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

/// Whether a fit varies a parameter whose effect is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fitted {
    /// Always.
    Yes,
    /// Only when asked (`--free eta`); otherwise held at its default.
    OnRequest,
    /// Never: held at its default (free it with `--fix` only to another fixed value).
    No,
}

/// One line of the table. Numbers are in file units (degrees for angles).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// The key; `SigmaA(0)` stands for every channel's σ_a.
    pub name: ParamName,
    /// The params.json field.
    pub json: &'static str,
    /// The symbol in docs and reports.
    pub symbol: &'static str,
    /// What it does, in a few words.
    pub meaning: &'static str,
    pub unit: Unit,
    /// What the model accepts; every command checks it (see [`ParamSpec::check`]).
    pub domain: Interval,
    /// Why the domain ends where it does.
    pub domain_why: &'static str,
    /// Fit bounds `(lo, hi)`; `hi = None`: bounded below only. Inside the domain.
    pub fit_lo: f64,
    pub fit_hi: Option<f64>,
    /// MODEL.md's typical range: the box the start design samples.
    pub typical: (f64, f64),
    /// The value a parameter file may omit it at.
    pub default: Option<f64>,
    /// The value held when not fitted and probed with by `--effects auto`; `None`: the middle of
    /// the typical range (in model units).
    pub reference: Option<f64>,
    pub used_by: UsedBy,
    pub fitted: Fitted,
}

/// The table, in output order (fit.json, the report, `--fix` names).
pub const TABLE: [ParamSpec; 9] = [
    ParamSpec {
        name: ParamName::Eta,
        json: "eta",
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
        used_by: UsedBy::EveryLobe,
        fitted: Fitted::OnRequest,
    },
    ParamSpec {
        name: ParamName::SigmaA(0),
        json: "sigma_a",
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
        used_by: UsedBy::Transmission,
        fitted: Fitted::Yes,
    },
    ParamSpec {
        name: ParamName::AlphaR,
        json: "alpha_r_deg",
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
        used_by: UsedBy::EveryLobe,
        fitted: Fitted::Yes,
    },
    ParamSpec {
        name: ParamName::BetaR,
        json: "beta_r_deg",
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
        used_by: UsedBy::EveryLobe,
        fitted: Fitted::Yes,
    },
    ParamSpec {
        name: ParamName::KG,
        json: "k_g",
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
        used_by: UsedBy::Glints,
        fitted: Fitted::Yes,
    },
    ParamSpec {
        name: ParamName::WC,
        json: "w_c_deg",
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
        used_by: UsedBy::Glints,
        fitted: Fitted::Yes,
    },
    ParamSpec {
        name: ParamName::Eccentricity,
        json: "eccentricity",
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
        used_by: UsedBy::Eccentricity,
        fitted: Fitted::Yes,
    },
    ParamSpec {
        name: ParamName::DeltaEtaPrime,
        json: "delta_eta_prime",
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
        used_by: UsedBy::Glints,
        fitted: Fitted::No,
    },
    ParamSpec {
        name: ParamName::DeltaHM,
        json: "delta_h_m",
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
        used_by: UsedBy::Glints,
        fitted: Fitted::No,
    },
];

impl ParamName {
    /// This parameter's line of [`TABLE`] (every `SigmaA(c)` shares one).
    pub fn spec(self) -> &'static ParamSpec {
        let key = match self {
            ParamName::SigmaA(_) => ParamName::SigmaA(0),
            other => other,
        };
        TABLE
            .iter()
            .find(|s| s.name == key)
            .expect("every ParamName has a line in the parameter table")
    }

    /// The parameter named `name` (`"eta"`, `"sigma_a[1]"`, `"w_c_deg"`), if any.
    pub fn from_json_name(name: &str) -> Option<ParamName> {
        let sigma = ParamName::SigmaA(0).spec().json;
        if let Some(c) = name
            .strip_prefix(sigma)
            .and_then(|r| r.strip_prefix('['))
            .and_then(|r| r.strip_suffix(']'))
        {
            return c.parse().ok().map(ParamName::SigmaA);
        }
        TABLE
            .iter()
            .find(|s| s.json == name && !matches!(s.name, ParamName::SigmaA(_)))
            .map(|s| s.name)
    }
}

impl ParamSpec {
    /// Check a FILE-unit value against the domain; `Err` holds the message for
    /// [`crate::Error::Parameter`] (names the allowed range and why).
    pub fn check(&self, file_value: f64) -> std::result::Result<(), String> {
        if self.domain.contains(file_value) {
            Ok(())
        } else {
            Err(format!(
                "must be finite and lie in {}{}: {}",
                self.domain.text(),
                match self.unit {
                    Unit::Dimensionless => String::new(),
                    u => format!(" {}", u.label()),
                },
                self.domain_why
            ))
        }
    }

    /// Fit bounds in model units (radians for angles): `(lo, Some(hi))` or `(lo, None)`.
    pub fn fit_bounds(&self) -> (f64, Option<f64>) {
        let to = |x| self.unit.to_model(x);
        (to(self.fit_lo), self.fit_hi.map(to))
    }

    /// Typical range in model units (radians for angles).
    pub fn typical_range(&self) -> (f64, f64) {
        (
            self.unit.to_model(self.typical.0),
            self.unit.to_model(self.typical.1),
        )
    }

    /// The value held when not fitted, in model units (see [`ParamSpec::reference`]).
    pub fn reference_value(&self) -> f64 {
        match self.reference {
            Some(v) => self.unit.to_model(v),
            None => {
                let (a, b) = self.typical_range();
                0.5 * (a + b)
            }
        }
    }

    /// True when `file_value` of a degrees parameter is more likely radians written by mistake
    /// (`beta_r_deg: 0.14`, i.e. 8°): nonzero and under a tenth of the typical range's end
    /// nearest zero. Every typical value written in radians falls under it (the largest,
    /// w_c's 25° = 0.44, against 1.0), while a tenth of the typical smallest is already an
    /// implausible value in degrees. A typical range that holds zero never warns.
    pub fn looks_like_radians(&self, file_value: f64) -> bool {
        let (a, b) = self.typical;
        let spans_zero = a <= 0.0 && b >= 0.0;
        let nearest = a.abs().min(b.abs());
        self.unit == Unit::Degrees
            && !spans_zero
            && file_value != 0.0
            && file_value.abs() < 0.1 * nearest
    }

    /// The default in model units, if the file may omit the parameter.
    pub fn default_value(&self) -> Option<f64> {
        self.default.map(|v| self.unit.to_model(v))
    }
}

/// Every parameter in output order, σ_a expanded to `n_channels` entries.
pub fn all_parameters(n_channels: usize) -> Vec<ParamName> {
    expand(TABLE.iter(), n_channels)
}

/// The parameters `S` depends on under `effects`, in output order.
pub fn used_parameters(effects: &Effects, n_channels: usize) -> Vec<ParamName> {
    expand(
        TABLE.iter().filter(|s| s.used_by.active(effects)),
        n_channels,
    )
}

/// The parameters a fit under `effects` varies before `--fix` (η only with `free_eta`).
pub fn fitted_parameters(effects: &Effects, n_channels: usize, free_eta: bool) -> Vec<ParamName> {
    expand(
        TABLE.iter().filter(|s| {
            s.used_by.active(effects)
                && match s.fitted {
                    Fitted::Yes => true,
                    Fitted::OnRequest => free_eta,
                    Fitted::No => false,
                }
        }),
        n_channels,
    )
}

fn expand<'a>(specs: impl Iterator<Item = &'a ParamSpec>, n_channels: usize) -> Vec<ParamName> {
    let mut out = Vec::new();
    for s in specs {
        match s.name {
            ParamName::SigmaA(_) => out.extend((0..n_channels).map(ParamName::SigmaA)),
            name => out.push(name),
        }
    }
    out
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
                assert!(s.looks_like_radians(deg.to_radians()), "{} {deg}", s.json);
                assert!(!s.looks_like_radians(deg), "{} {deg}", s.json);
            }
            assert!(!s.looks_like_radians(0.0), "{}", s.json);
        }
        assert!(!ParamName::KG.spec().looks_like_radians(0.01));
    }

    #[test]
    fn every_fit_bound_and_typical_range_lies_inside_the_domain() {
        for s in &TABLE {
            let hi = s.fit_hi.unwrap_or(f64::MAX);
            assert!(
                s.domain.contains(s.fit_lo) && s.domain.contains(hi),
                "{}",
                s.json
            );
            assert!(s.fit_lo <= s.typical.0 && s.typical.1 <= hi, "{}", s.json);
            for v in [s.default, s.reference].into_iter().flatten() {
                assert!(s.domain.contains(v), "{}", s.json);
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
        let eta = ParamName::Eta.spec().domain;
        assert_eq!(eta.text(), "(1, 10]");
        assert!(!eta.contains(1.0) && eta.contains(10.0) && !eta.contains(1e155));
        let a = ParamName::Eccentricity.spec().domain;
        assert_eq!(a.text(), "(0.70711, 1]");
        assert!(!a.contains(f64::NAN) && !a.contains(FRAC_1_SQRT_2) && a.contains(1.0));
    }
}
