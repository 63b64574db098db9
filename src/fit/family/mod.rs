//! The model families as the fit sees them: one type per family implementing [`Family`] —
//! its free parameters, `--fix` names, forward model and the records it writes, handed to the
//! shared stages ([`super::fit_with`]). `crate::fit::registry` is where a `--model` name meets
//! its type; the shared stages, verdicts, intervals and reports never name a family.

use crate::error::Result;
use crate::families::FamilyParams;
use crate::files::LoadReport;
use crate::fit::{FitData, FitOptions, FitOutcome, FitParam};

/// What a fit is given: the samples, the file they came from (for messages and fit.json), the
/// loader's report of that file, the options, and when the fit started (timing.json).
pub struct FitInput<'a> {
    pub data: &'a FitData,
    pub file: &'a str,
    pub load_report: LoadReport,
    pub opts: &'a FitOptions,
    pub started: std::time::Instant,
}

impl<'a> FitInput<'a> {
    /// The input of a fit starting now.
    pub fn new(
        data: &'a FitData,
        file: &'a str,
        load_report: LoadReport,
        opts: &'a FitOptions,
    ) -> FitInput<'a> {
        FitInput {
            data,
            file,
            load_report,
            opts,
            started: std::time::Instant::now(),
        }
    }
}

/// A model family's part of a fit: its parameters, how `--fix` names them, and its fit. A new
/// family is one type implementing this; [`FamilyFit`] follows.
pub trait Family: Sync + 'static {
    /// The family's parameter names.
    type Param: FitParam;

    /// How `--fix` messages name one of its parameters ("parameter", "Chiang parameter").
    const PARAMETER_WORD: &'static str;

    /// A `--fix` value for messages to show (`eccentricity=1 or --fix alpha_r_deg=-7`).
    const FIX_EXAMPLE: &'static str;

    /// Every parameter for `nc` channels, in output order.
    fn parameters(nc: usize) -> Vec<Self::Param>;

    /// `--fix NAME=VALUE` items as natural-unit values (`sigma_a=v` fixes every channel), with
    /// the message the fit gives for a wrong name, value or channel index.
    fn parse_fixes(items: &[String], nc: usize) -> Result<Vec<(Self::Param, f64)>> {
        super::fixes::parse_fixes(
            items,
            &Self::parameters(nc),
            Self::PARAMETER_WORD,
            Self::FIX_EXAMPLE,
        )
    }

    /// Fit `input`; the parameters come back as this family's parameter file.
    fn fit(input: FitInput<'_>) -> Result<FitOutcome<FamilyParams>>;
}

/// A family as the commands hold it (`--model NAME` picks one at run time: `crate::fit::registry::family_fit`).
pub trait FamilyFit: Sync {
    /// Fit `input`; the parameters come back as this family's parameter file.
    fn fit(&self, input: FitInput<'_>) -> Result<FitOutcome<FamilyParams>>;

    /// The file names of every parameter for `nc` channels, in output order.
    fn parameter_names(&self, nc: usize) -> Vec<String>;

    /// Check `--fix NAME=VALUE` items against this family's parameters for `nc` channels
    /// (names, values, channel indices), with the message the fit would give.
    fn check_fixes(&self, fix: &[String], nc: usize) -> Result<()>;
}

impl<F: Family> FamilyFit for F {
    fn fit(&self, input: FitInput<'_>) -> Result<FitOutcome<FamilyParams>> {
        <F as Family>::fit(input)
    }

    fn parameter_names(&self, nc: usize) -> Vec<String> {
        F::parameters(nc)
            .into_iter()
            .map(|p| p.json_name())
            .collect()
    }

    fn check_fixes(&self, fix: &[String], nc: usize) -> Result<()> {
        F::parse_fixes(fix, nc).map(drop)
    }
}
