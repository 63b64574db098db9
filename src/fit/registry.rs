//! The fit's registry: which type fits each model family (`--model NAME`), the one list every
//! command that fits (fit, demo, compare, batch, cost, Python) reads. It sits apart from
//! [`super::family`] (the trait) so that a family's fit adaptor, which implements the trait,
//! and the list that names it do not import each other.

use super::family::{FamilyFit, FitInput};
use super::{FitData, FitOptions, FitOutcome};
use crate::error::Result;
use crate::families::table::Table;
use crate::families::{chiang, marschner};
use crate::families::{deon::DEon, frostbite::Frostbite, kajiya_kay::KajiyaKay, karis::Karis};
use crate::families::{FamilyParams, ModelFamily};
use crate::files::LoadReport;

/// The fit of `family`.
pub fn family_fit(family: ModelFamily) -> &'static dyn FamilyFit {
    match family {
        ModelFamily::Marschner => &marschner::fit::Marschner,
        ModelFamily::Chiang => &chiang::fit::Chiang,
        ModelFamily::KajiyaKay => &Table::<KajiyaKay>::NEW,
        ModelFamily::DEon => &Table::<DEon>::NEW,
        ModelFamily::Karis => &Table::<Karis>::NEW,
        ModelFamily::Frostbite => &Table::<Frostbite>::NEW,
    }
}

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
