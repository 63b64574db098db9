//! `hairfit cost`: the accuracy-vs-time ledger. Measures on this machine what each accuracy knob
//! costs — model root mode and effect set (time per evaluation vs error of S against the exact
//! all-effects model), Jacobian by AD vs central differences, and the fit's stages, start count
//! and sample count (wall time vs parameter-recovery error on seeded synthetic data) — and writes
//! cost.csv, cost.json and cost.svg/png (error against time, log axes, Pareto front marked).

//!
//! A family's own section lives in its folder (`families/<name>/cost`, implementing
//! [`FamilyCost`]) and is found through the registry; [`families`] measures every family side
//! by side, [`accuracy`] is what every section measures error with, [`ledger`] marks the Pareto
//! front and writes the files, [`figure`] draws cost.svg/png with the plotting kit.

mod accuracy;
mod families;
mod figure;
mod ledger;

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use crate::error::Result;
use crate::families::{FamilyModel, ModelFamily, ModelSetup};

pub use accuracy::{accuracy_row, relative_error, representative_angles};
pub use ledger::{mark_pareto, summary_text};

/// Error values below this are drawn at it on the log axes (the reference itself has error 0).
pub const ERROR_FLOOR: f64 = 1e-16;

/// Seed of every random choice in the ledger (angles, synthetic noise, fit starts).
pub const COST_SEED: u64 = 20_03;

/// Options of `hairfit cost`.
#[derive(Debug, Clone, Copy, Default)]
pub struct CostOptions {
    /// Fewer angles, shorter timings, fewer fit variants: under a minute on 2 cores.
    pub quick: bool,
    /// Write into a directory hairfit did not mark that holds other files (they are kept).
    pub force: bool,
    /// `--model NAME`: whose own section the ledger measures ([`FamilyCost`], beside the
    /// default family's time as the yardstick); a table family has none.
    pub family: ModelFamily,
}

/// One measured setting of one knob.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CostRow {
    /// `model`, `jacobian` or `fit`.
    pub section: String,
    /// What was varied (e.g. `roots+effects`, `starts`).
    pub knob: String,
    /// The setting (e.g. `cubic R+TT`).
    pub setting: String,
    /// Seconds: per model evaluation (one direction pair, all channels), per Jacobian, per fit.
    pub time_s: f64,
    /// What the error measures (see [`CostLedger::metrics`]).
    pub error_max: f64,
    pub error_rms: f64,
    /// Where the largest error sits (angles and channel, or parameter name).
    pub worst_at: String,
    /// On the section's Pareto front of (time_s, error_rms).
    pub pareto: bool,
}

/// The ledger: rows plus what was measured and how.
#[derive(Debug, Clone, Serialize)]
pub struct CostLedger {
    pub hairfit_version: String,
    pub quick: bool,
    pub seed: u64,
    /// Rayon worker threads (the machine's cores unless limited).
    pub threads: usize,
    /// Error definition per section.
    pub metrics: serde_json::Value,
    pub rows: Vec<CostRow>,
    pub wall_time_s: f64,
}

/// A family's own section of the ledger (`hairfit cost --model NAME`): what its accuracy knobs
/// cost. Implemented in the family's folder by each `Own` family of the registry; a table
/// family's one knob is its terms, so its cost is its row in the families section.
pub trait FamilyCost: Sync {
    /// The section's rows (`quick`: fewer directions, shorter timings, fewer variants).
    fn rows(&self, quick: bool) -> Result<Vec<CostRow>>;

    /// What each of the section's row sections measures (cost.json's `metrics`): (the row
    /// sections it describes, the description).
    fn metrics(&self) -> &'static [(&'static str, &'static str)];
}

/// [`family_section`] from the registry's list (`crate::families::registry`).
macro_rules! family_section {
    ($($variant:ident => $kind:ident($ty:path)),* $(,)?) => {
        /// The own section of `family`; none for a table family.
        fn family_section(family: ModelFamily) -> Option<&'static dyn FamilyCost> {
            match family {
                $(ModelFamily::$variant => family_section!(@section $kind($ty)),)*
            }
        }
    };
    (@section Own($ty:path)) => {
        Some(&$ty)
    };
    (@section Table($ty:path)) => {
        None
    };
}
crate::families::registry!(family_section);

/// How many random directions a family section times its evaluations on.
pub fn section_directions(quick: bool) -> usize {
    if quick {
        64
    } else {
        256
    }
}

/// The yardstick of a family's section: the default family's time per sample (its demo truth,
/// default options, one thread) on the section's random directions, so "N times the default
/// model" can be read off the ledger. Its error is not comparable (another model).
fn yardstick_row(quick: bool) -> CostRow {
    let family = ModelFamily::default();
    let min_s = if quick { 0.05 } else { 0.5 };
    let random = representative_angles(section_directions(quick), COST_SEED);
    let model = FamilyModel::new(&family.demo_truth(), &ModelSetup::default());
    let mut out = vec![0.0; random.len() * model.n_channels()];
    let t = time_per_call(min_s, || model.eval_batch(&random, &mut out));
    CostRow {
        section: "baseline".into(),
        knob: format!("{family} (yardstick)"),
        setting: format!("{family}, default options, every term"),
        time_s: t / random.len() as f64,
        error_max: f64::NAN,
        error_rms: f64::NAN,
        worst_at: "not comparable (another model)".into(),
        pareto: false,
    }
}

/// cost.json's description of the yardstick row.
const YARDSTICK_METRIC: &str = "the default family's time per sample on the section's random directions (its demo truth, default options, every term, one thread); its error is not comparable (another model)";

/// cost.json's description of the families section.
const FAMILIES_METRIC: &str = "every model family's S: time per direction pair (3 channels, its demo truth, every term, its default accuracy, one thread) and, in the full ledger, the wall time of fitting its own demo data (linearised intervals); the families are different models, so no error is comparable (hairfit compare ranks what each loses on the same data)";

/// Seconds per call of `f`: the fastest of five batches, each repeating `f` until `min_s / 5`
/// has elapsed. The minimum is the least disturbed by other work on a shared machine.
pub fn time_per_call(min_s: f64, mut f: impl FnMut()) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t0 = Instant::now();
        let mut calls = 0u64;
        loop {
            f();
            calls += 1;
            let t = t0.elapsed().as_secs_f64();
            if t >= min_s / 5.0 {
                best = best.min(t / calls as f64);
                break;
            }
        }
    }
    best
}

/// Measure everything and write cost.csv, cost.json, cost.svg and cost.png into `out`.
pub fn run_cost(out: &Path, options: &CostOptions) -> Result<CostLedger> {
    // Locked before measuring, so a second run fails fast; the files are published as one set.
    let set = crate::outdir::OutputSet::begin(out, "hairfit cost", options.force, &[])?;
    let t0 = Instant::now();
    let quick = options.quick;
    let mut rows = Vec::new();
    let mut metrics = serde_json::Map::new();
    let mut describe = |sections: &str, what: &str| {
        metrics.insert(sections.into(), what.into());
    };
    if let Some(section) = family_section(options.family) {
        if options.family != ModelFamily::default() {
            rows.push(yardstick_row(quick));
            describe("baseline", YARDSTICK_METRIC);
        }
        rows.extend(section.rows(quick)?);
        for (sections, what) in section.metrics() {
            describe(sections, what);
        }
    }
    describe("families", FAMILIES_METRIC);
    // Every family's cost beside the others' (what each approximation saves).
    let random = representative_angles(if quick { 256 } else { 1024 }, COST_SEED);
    rows.extend(families::eval_rows(&random, quick));
    if !quick {
        rows.extend(families::fit_rows()?);
    }
    mark_pareto(&mut rows);
    let ledger = CostLedger {
        hairfit_version: env!("CARGO_PKG_VERSION").into(),
        quick,
        seed: COST_SEED,
        threads: rayon::current_num_threads(),
        metrics: metrics.into(),
        rows,
        wall_time_s: t0.elapsed().as_secs_f64(),
    };
    ledger::write_ledger(set.staging(), &ledger)?;
    set.publish()?;
    Ok(ledger)
}
