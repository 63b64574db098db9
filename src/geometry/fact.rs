//! The one parameter-fact type every family's table is made of ([`ParamFact`]), and what a
//! family tells the commands about itself ([`FamilyFacts`]). A parameter fact holds a parameter's
//! file name, symbol, unit, domain (with the one domain check and its one wording of the error),
//! fit bounds, typical range, default and when a fit varies it. Numbers are in FILE units
//! (degrees for angles); the accessors that return model values convert.

use super::units::{Interval, Unit};

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

/// One line of a family's parameter table. Numbers are in file units (degrees for angles).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamFact {
    /// The parameter file's key (`eta`, `sigma_a`, `alpha_r_deg`, `roughness`).
    pub name: &'static str,
    /// The symbol in docs and reports (`σ_a`, `β_R`).
    pub symbol: &'static str,
    /// What it does, in a few words.
    pub meaning: &'static str,
    pub unit: Unit,
    /// One value per colour channel (written `name[c]` in fit.json and `--fix`).
    pub per_channel: bool,
    /// What the model accepts; every command checks it (see [`ParamFact::check`]).
    pub domain: Interval,
    /// Why the domain ends where it does (empty: the domain says it all).
    pub domain_why: &'static str,
    /// Fit bounds: `fit_lo` and `fit_hi` (`None`: bounded below only), inside the domain.
    pub fit_lo: f64,
    pub fit_hi: Option<f64>,
    /// The typical range: the box the fit's start design samples.
    pub typical: (f64, f64),
    /// The value a parameter file may omit it at.
    pub default: Option<f64>,
    /// The value held when not fitted (and probed with by `--effects auto`); `None`: the
    /// default, else the middle of the typical range.
    pub reference: Option<f64>,
    pub fitted: Fitted,
    /// The terms that read it (empty: every term, or the family says in its own words).
    pub terms: &'static [&'static str],
}

impl ParamFact {
    /// A line with only the fields every family fills left to fill: the base of a table's
    /// struct literals (`ParamFact { name: "eta", .., ..ParamFact::BASE }`).
    pub const BASE: ParamFact = ParamFact {
        name: "",
        symbol: "",
        meaning: "",
        unit: Unit::Dimensionless,
        per_channel: false,
        domain: Interval::open(f64::NEG_INFINITY, f64::INFINITY),
        domain_why: "",
        fit_lo: f64::NEG_INFINITY,
        fit_hi: None,
        typical: (0.0, 0.0),
        default: None,
        reference: None,
        fitted: Fitted::Yes,
        terms: &[],
    };

    /// Check a FILE-unit value against the domain; `Err` holds the message for
    /// [`crate::Error::Parameter`]: what the parameter is, the allowed range with its unit, and
    /// why the range ends there when the table says.
    pub fn check(&self, file_value: f64) -> std::result::Result<(), String> {
        if self.domain.contains(file_value) {
            return Ok(());
        }
        let unit = match self.unit.label() {
            "" => String::new(),
            label => format!(" {label}"),
        };
        let why = match self.domain_why {
            "" => String::new(),
            why => format!(": {why}"),
        };
        Err(format!(
            "{} must be finite and lie in {}{unit}{why}",
            self.meaning,
            self.domain.text()
        ))
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

    /// The value held when not fitted, in FILE units (see [`ParamFact::reference`]).
    pub fn held(&self) -> f64 {
        self.reference
            .or(self.default)
            .unwrap_or(0.5 * (self.typical.0 + self.typical.1))
    }

    /// The value held when not fitted, in model units.
    pub fn reference_value(&self) -> f64 {
        self.unit.to_model(self.held())
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

/// What a family tells every command about itself: its `--model` name, how sentences and
/// help name it, its parameter table and the options only it takes. Each family's folder
/// implements it once (every table family through `families::table::Table`);
/// `families::ModelFamily::entry` is the registry. Here, below the families, so that a family
/// implementing it and the registry naming the family do not import each other.
pub trait FamilyFacts: Sync {
    /// The `--model` / `"model"` spelling.
    fn name(&self) -> &'static str;
    /// The name in sentences and figure legends.
    fn title(&self) -> &'static str;
    /// The model with its source, for help and lists.
    fn citation(&self) -> &'static str;
    /// Every parameter's facts (name, unit, domain, bounds, typical range, default).
    fn parameters(&self) -> &'static [ParamFact];
    /// The flags of `cli::ModelArgs` only some families take that this one takes.
    fn own_options(&self) -> &'static [&'static str];
}
