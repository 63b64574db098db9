//! The fit's side of the registry: which type fits each model family (`--model NAME`), what
//! every command that fits (fit, demo, compare, batch, cost, Python) reads. Made from the one
//! family list (`crate::families::registry`); it sits apart from [`super::family`] (the trait)
//! so that a family's fit adaptor, which implements the trait, and this lookup do not import
//! each other.

use super::family::{FamilyFit, FitInput};
use super::{FitData, FitOptions, FitOutcome};
use crate::error::Result;
use crate::families::table::Table;
use crate::families::{FamilyParams, ModelFamily};
use crate::files::LoadReport;

/// [`family_fit`] from the registry's list (`crate::families::registry`): an `Own` family's type
/// is its own fit; a table family's fit is its [`Table`], as its facts are.
macro_rules! family_fit {
    ($($variant:ident => $kind:ident($ty:path)),* $(,)?) => {
        /// The fit of `family`.
        pub fn family_fit(family: ModelFamily) -> &'static dyn FamilyFit {
            match family {
                $(ModelFamily::$variant => family_fit!(@fit $kind($ty)),)*
            }
        }
    };
    (@fit Own($ty:path)) => {
        &$ty
    };
    (@fit Table($ty:path)) => {
        &Table::<$ty>::NEW
    };
}
crate::families::registry!(family_fit);

/// Fit `data` with the model family `opts.family` (through its [`FamilyFit`]); the
/// outcome's parameters as a parameter file of that family.
pub fn fit_family(
    data: &FitData,
    file: &str,
    load_report: LoadReport,
    opts: &FitOptions,
) -> Result<FitOutcome<FamilyParams>> {
    family_fit(opts.family).fit(FitInput::new(data, file, load_report, opts))
}
