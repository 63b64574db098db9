//! `hairfit fit --model marschner`: the Marschner family's part of a fit — the effects the data
//! call for, its free parameters and `--fix` names, the words for an undetermined parameter —
//! handed to the shared stages ([`crate::fit::fit_with`]) — and its model as the fit evaluates
//! it ([`forward`]).

pub mod auto;
pub mod diagnostics;
pub mod forward;
pub mod synthetic;

use crate::error::Result;
use crate::families::marschner::fit::forward::MarschnerForward;
use crate::families::marschner::parameters::all_parameters;
use crate::families::marschner::parameters::{fitted_parameters, reference_params};
use crate::families::marschner::params::ParamFile;
use crate::families::marschner::{Effects, MarschnerFamily, ParamName, Params};
use crate::families::FamilyParams;
use crate::files::LoadReport;
use crate::fit::family::{Family, FitInput};
use crate::fit::fixes::FreeSet;
use crate::fit::{fit_with, require_samples, stages, FitData, FitOptions, FitOutcome, FitRun};

/// A Marschner fit's outcome, its parameters as the model's own set.
pub type MarschnerOutcome = FitOutcome<Params<f64>>;

/// The Marschner family's fit: the registry hands this same type out as the family's facts and
/// as its fit.
impl Family for MarschnerFamily {
    type Param = ParamName;
    const PARAMETER_WORD: &'static str = "parameter";
    const FIX_EXAMPLE: &'static str = "eccentricity=1 or --fix alpha_r_deg=-7";

    fn parameters(nc: usize) -> Vec<ParamName> {
        all_parameters(nc)
    }

    fn fit(i: FitInput<'_>) -> Result<FitOutcome<FamilyParams>> {
        let out = fit(i.data, i.file, i.load_report, i.opts)?;
        Ok(out.map_params(|p| FamilyParams::Marschner(ParamFile::from_params(p))))
    }
}

/// Fit `data` (from file `file`, loader report `load_report`) with `opts`, the Marschner model
/// (`opts.family` is not consulted: [`crate::fit::registry::fit_family`] dispatches on it).
pub fn fit(
    data: &FitData,
    file: &str,
    load_report: LoadReport,
    opts: &FitOptions,
) -> Result<MarschnerOutcome> {
    let input = FitInput::new(data, file, load_report, opts);
    let nc = require_samples(data, file)?;
    let mut warnings = Vec::new();
    let auto = auto::choose_model(data, opts);
    let forward = MarschnerForward {
        config: auto.config,
        measurement: opts.measurement,
    };
    let set = free_set(&auto.config.effects, nc, opts, &mut warnings)?;
    let options = |sub: usize, explicit: bool, floored| {
        stages::options_record(opts, &auto.choice, &set, sub, explicit, floored)
    };
    let why = |p: ParamName, params: &Params<f64>, partners: &[String]| {
        diagnostics::why_undetermined(p, data, auto.config.mode, params, partners)
    };
    fit_with(
        FitRun {
            input,
            forward: &forward,
            screening: None,
            base: set.base.clone(),
            free: set.free.clone(),
            options: &options,
            records: crate::families::ModelRecords::of_config(auto.config),
            all: all_parameters(nc),
            why: &why,
            params_file: |p| FamilyParams::Marschner(ParamFile::from_params(p)),
        },
        warnings,
    )
}

/// Free parameters and the base (fixed) values; warns about parameters the effects ignore.
fn free_set(
    effects: &Effects,
    nc: usize,
    opts: &FitOptions,
    warnings: &mut Vec<String>,
) -> Result<FreeSet<ParamName>> {
    Ok(FreeSet::new(
        MarschnerFamily::parse_fixes(&opts.fix, nc)?,
        reference_params(nc),
        fitted_parameters(effects, nc, opts.free_eta),
        fitted_parameters(&Effects::default(), nc, opts.free_eta),
        "the effects in play do not depend on it; see options.effects_reasons",
        warnings,
    ))
}
