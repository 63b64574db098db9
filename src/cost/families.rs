//! The ledger's families section: what each model family costs on this machine, beside
//! Marschner's — evaluations per second per core of its `S` (3 channels, its demo truth, every
//! term, its default accuracy) on the ledger's random directions and, in the full ledger, the
//! wall time of fitting its own demo data. The families are different models, so no error is
//! comparable here: `hairfit compare` ranks what each one loses on the same data.

use super::{time_per_call, CostRow};
use crate::error::Result;
use crate::families::{FamilyModel, ModelFamily, ModelSetup};
use crate::fit::registry::fit_family;
use crate::fit::FitOptions;
use crate::geometry::Angles;

/// What the error columns would compare: nothing across models.
const NOT_COMPARABLE: &str = "another model (hairfit compare ranks the families' losses)";

/// Time per direction pair (3 channels, one thread) of each family's `S`, and the samples per
/// second per core that is.
pub(super) fn eval_rows(random: &[Angles], quick: bool) -> Vec<CostRow> {
    let min_s = if quick { 0.05 } else { 0.5 };
    let setup = ModelSetup::default();
    ModelFamily::ALL
        .into_iter()
        .map(|family| {
            let file = family.demo_truth();
            let model = FamilyModel::new(&file, &setup);
            let mut out = vec![0.0; random.len() * model.n_channels()];
            let t =
                time_per_call(min_s, || model.eval_batch(random, &mut out)) / random.len() as f64;
            row(
                family,
                "evaluation (3 channels)",
                t,
                format!("{:.3e} samples/s/core", 1.0 / t),
            )
        })
        .collect()
}

/// Wall time of each family's fit of its own demo data (2340 samples × 3 channels, 2% noise,
/// the default options with linearised intervals, so the fits differ only in their model).
pub(super) fn fit_rows() -> Result<Vec<CostRow>> {
    let mut rows = Vec::new();
    for family in ModelFamily::ALL {
        let opts = FitOptions {
            family,
            intervals: crate::fit::Intervals::Linear,
            ..FitOptions::default()
        };
        let data = crate::demo::demo_data(&opts)?;
        let t0 = std::time::Instant::now();
        let out = fit_family(&data, "demo", Default::default(), &opts)?;
        let t = t0.elapsed().as_secs_f64();
        rows.push(row(
            family,
            "demo fit (7020 values)",
            t,
            format!("verdict {}", out.json.verdict),
        ));
    }
    Ok(rows)
}

fn row(family: ModelFamily, knob: &str, time_s: f64, what: String) -> CostRow {
    CostRow {
        section: "families".into(),
        knob: knob.into(),
        setting: format!("{family}: {what}"),
        time_s,
        error_max: f64::NAN,
        error_rms: f64::NAN,
        worst_at: NOT_COMPARABLE.into(),
        pareto: false,
    }
}
