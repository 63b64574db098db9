//! `hairfit fit --model chiang`: the Chiang family's part of a fit — its free parameters (what
//! the terms in play depend on, minus `--fix`, η only on `--free eta`), its `--fix` names, the
//! words for an undetermined parameter — handed to the shared stages ([`crate::fit::fit_with`]);
//! its model as the fit evaluates it is [`forward`].

pub mod forward;

use std::time::Instant;

use crate::error::Result;
use crate::families::chiang::{
    all_parameters, reference_params, ChiangEffects, ChiangFamily, ChiangModel, ChiangParamFile,
    ChiangParamName, ChiangParams, WidthNodes,
};
use crate::families::{FamilyParams, OwnFamily};
use crate::files::{Floored, LoadReport};
use crate::fit::family::{Family, FitInput};
use crate::fit::fixes::FreeSet;
use crate::fit::problem::FitData;
use crate::fit::{fit_with, require_samples, FitOptions, FitOutcome, FitRun};
use crate::geometry::angles::wrap;
use crate::geometry::Fitted;
pub use forward::ChiangForward;

/// The Chiang family's fit: the registry hands this same type out as the family's facts and as
/// its fit.
impl Family for ChiangFamily {
    type Param = ChiangParamName;
    const PARAMETER_WORD: &'static str = "Chiang parameter";
    const FIX_EXAMPLE: &'static str = "beta_n=0.3 or --fix alpha_deg=-2";

    fn parameters(nc: usize) -> Vec<ChiangParamName> {
        all_parameters(nc)
    }

    fn fit(i: FitInput<'_>) -> Result<FitOutcome<FamilyParams>> {
        let out = fit_chiang(i.data, i.file, i.load_report, i.opts)?;
        Ok(out.map_params(|p| FamilyParams::Chiang(ChiangParamFile::from_params(p))))
    }
}

/// Width nodes of the multi-start stage (when the fit asks for more): the plain rule's S within
/// 3.5e-2 relative at the narrowest azimuthal lobes (β_n = 0.05) and to rounding at β_n ≥ 0.3
/// (docs/chiang.md), enough to find the basin; under the automatic rule the multi-start uses it
/// at half density, capped at this many per π (`WidthNodes::Coarse`).
pub const SCREENING_WIDTH_NODES: usize = 256;

/// The coarser model the multi-start screens with, if the fit's rule can be coarser.
fn screening_model(model: &ChiangModel) -> Result<Option<ChiangModel>> {
    let coarser = match model.width() {
        WidthNodes::Fixed(n) if n > SCREENING_WIDTH_NODES => {
            WidthNodes::Fixed(SCREENING_WIDTH_NODES)
        }
        WidthNodes::Auto => WidthNodes::Coarse(SCREENING_WIDTH_NODES),
        _ => return Ok(None),
    };
    ChiangModel::with_width(model.effects, coarser).map(Some)
}

/// Why the data cannot determine `p`: the geometry that shows it, then its partners.
fn why_undetermined(
    p: ChiangParamName,
    data: &FitData,
    _params: &ChiangParams<f64>,
    partners: &[String],
) -> String {
    let tail = crate::fit::diagnostics::correlated_tail(partners);
    match p {
        ChiangParamName::SigmaA(_) => {
            let n = crate::fit::diagnostics::tt_region_samples(data);
            format!(
                "absorption shows in TT/TRT; {n} sample(s) have |phi| > 135 deg (TT region){tail}"
            )
        }
        ChiangParamName::BetaM | ChiangParamName::Alpha => {
            let spread = crate::fit::diagnostics::theta_h_span(data);
            format!(
                "the samples span theta_h by {:.1} deg only: the longitudinal lobes need a scan across it{tail}",
                spread.to_degrees()
            )
        }
        _ => format!("the data do not constrain it{tail}"),
    }
}

/// Fit the Chiang model (`opts.model.chiang`: terms and width nodes) to `data`.
pub fn fit_chiang(
    data: &FitData,
    file: &str,
    load_report: LoadReport,
    opts: &FitOptions,
) -> Result<FitOutcome<ChiangParams<f64>>> {
    let started = Instant::now();
    let nc = require_samples(data, file)?;
    // The fit evaluates fixed chunks of consecutive samples, and a chunk pays the width
    // integral once per exit direction (θ_r, |φ|): fit the samples grouped by that key, then
    // put curves.csv back in the data's order.
    let order = exit_direction_order(data);
    let grouped = data.subset(&order);
    let data = &grouped;
    let mut warnings = Vec::new();
    let model = ChiangModel::of_setup(&opts.model);
    let effects = model.effects;
    let forward = ChiangForward {
        model: model.clone(),
        measurement: opts.measurement,
    };
    // The multi-start only looks for basins: a coarser width rule there, the polish at the
    // requested one (so the result is the requested model's optimum).
    let screening = screening_model(&model)?.map(|model| ChiangForward {
        model,
        measurement: opts.measurement,
    });
    let wanted = |p: &ChiangParamName| p.fact().fitted != Fitted::OnRequest || opts.free_eta;
    let wanted_of = |e: &ChiangEffects| e.parameters(nc).into_iter().filter(wanted).collect();
    let set = FreeSet::new(
        ChiangFamily::parse_fixes(&opts.fix, nc)?,
        reference_params(nc),
        wanted_of(&effects),
        wanted_of(&ChiangEffects::default()),
        "the terms in play do not depend on it",
        &mut warnings,
    );
    let screened = match &screening {
        Some(s) => format!("; the multi-start screens with {}", s.model.width()),
        None => String::new(),
    };
    let reasons = vec![format!(
        "Chiang 2016 model, terms {} (--terms), width nodes {} (--width-nodes{screened})",
        effects
            .terms()
            .names(&crate::families::chiang::TERMS)
            .join("+"),
        model.width()
    )];
    let options = |sub: usize, explicit: bool, floored: Floored| {
        let choice = crate::fit::stages::ModelChoice {
            effects_choice: crate::files::EffectsSource::Explicit,
            reasons: reasons.clone(),
        };
        crate::fit::stages::options_record(opts, &choice, &set, sub, explicit, floored)
    };
    let why = |p: ChiangParamName, params: &ChiangParams<f64>, partners: &[String]| {
        why_undetermined(p, data, params, partners)
    };
    let mut outcome = fit_with(
        FitRun {
            // The grouping above counts in the fit's time.
            input: FitInput {
                started,
                ..FitInput::new(data, file, load_report, opts)
            },
            forward: &forward,
            screening: screening.as_ref(),
            base: set.base.clone(),
            free: set.free.clone(),
            options: &options,
            records: ChiangFamily.records(&opts.model),
            all: all_parameters(nc),
            why: &why,
            params_file: |p| FamilyParams::Chiang(ChiangParamFile::from_params(p)),
        },
        warnings,
    )?;
    outcome.curves.restore_sample_order(&order);
    Ok(outcome)
}

/// Sample indices sorted by exit direction (θ_r, |φ|), ties in data order.
fn exit_direction_order(data: &FitData) -> Vec<usize> {
    let key = |i: usize| {
        let a = &data.angles[i];
        (a.theta_r, wrap(a.phi_r - a.phi_i).abs())
    };
    let mut order: Vec<usize> = (0..data.len()).collect();
    order.sort_by(|&i, &j| {
        let (a, b) = (key(i), key(j));
        a.0.total_cmp(&b.0)
            .then(a.1.total_cmp(&b.1))
            .then(i.cmp(&j))
    });
    order
}
