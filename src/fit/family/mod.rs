//! The model families as the fit sees them: one type per family implementing [`FamilyFit`] —
//! its free parameters, `--fix` names, forward model and the records it writes, handed to the
//! shared stages ([`super::fit_with`]) — and [`family_fit`], the one place where a `--model`
//! name meets its type. The shared stages, verdicts, intervals and reports never name a family.

pub mod chiang;
pub mod marschner;

use crate::error::Result;
use crate::family::{FamilyParams, ModelFamily};
use crate::files::LoadReport;
use crate::fit::{FitData, FitOptions, FitOutcome};

/// A model family's part of a fit.
pub trait FamilyFit: Sync {
    /// Fit `data` (read from `file`, with the loader's report `load_report`) under `opts`;
    /// the parameters come back as this family's parameter file.
    fn fit(
        &self,
        data: &FitData,
        file: &str,
        load_report: LoadReport,
        opts: &FitOptions,
    ) -> Result<FitOutcome<FamilyParams>>;

    /// The file names of every parameter for `nc` channels, in output order.
    fn parameter_names(&self, nc: usize) -> Vec<String>;

    /// Check `--fix NAME=VALUE` items against this family's parameters for `nc` channels
    /// (names, values, channel indices), with the message the fit would give.
    fn check_fixes(&self, fix: &[String], nc: usize) -> Result<()>;
}

/// The fit of `family`.
pub fn family_fit(family: ModelFamily) -> &'static dyn FamilyFit {
    match family {
        ModelFamily::Marschner => &marschner::Marschner,
        ModelFamily::Chiang => &chiang::Chiang,
    }
}
