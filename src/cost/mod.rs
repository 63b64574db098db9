//! `hairfit cost`: the accuracy-vs-time ledger. Measures on this machine what each accuracy knob
//! costs — model root mode and effect set (time per evaluation vs error of S against the exact
//! all-effects model), Jacobian by AD vs central differences, and the fit's stages, start count
//! and sample count (wall time vs parameter-recovery error on seeded synthetic data) — and writes
//! cost.csv, cost.json and cost.svg/png (error against time, log axes, Pareto front marked).

//!
//! Files: [`model`], [`jacobian`] and [`fits`] measure one section each, [`ledger`] marks the
//! Pareto front and writes the files, [`figure`] draws cost.svg/png with the plotting kit.

mod chiang;
mod families;
mod figure;
mod fits;
mod jacobian;
mod ledger;
mod model;

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use crate::error::Result;

pub use ledger::{mark_pareto, summary_text};
pub use model::{effect_ladder, relative_error, representative_angles};

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
    /// `chiang`: the Chiang section instead (width nodes × cache against accuracy, with the
    /// Marschner model's time as the yardstick).
    pub family: crate::families::ModelFamily,
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

/// Seconds per call of `f`: the fastest of five batches, each repeating `f` until `min_s / 5`
/// has elapsed. The minimum is the least disturbed by other work on a shared machine.
fn time_per_call(min_s: f64, mut f: impl FnMut()) -> f64 {
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
    match options.family {
        crate::families::ModelFamily::Marschner => {
            rows.extend(model::model_rows(quick));
            let data = fits::synthetic_data();
            rows.extend(jacobian::jacobian_rows(&data, quick)?);
            rows.extend(fits::fit_rows(&data, quick)?);
        }
        crate::families::ModelFamily::Chiang => rows.extend(chiang::chiang_rows(quick)?),
        // A table family's one knob is its terms: each family's cost below is the ledger.
        _ => {}
    }
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
        metrics: serde_json::json!({
            "model": "relative error of S per channel against exact roots with every effect, denominator floored at 1e-3 x the median reference S; time per evaluation (one direction pair, all channels, one thread)",
            "jacobian": "per parameter column: ||J_fd - J_ad|| / ||J_ad|| (max and RMS over columns); time per full Jacobian of the synthetic data",
            "fit": "|estimate - truth| / width of the parameter's typical range (docs/model.md), over the free shape parameters (max and RMS); wall time of the whole fit",
            "families": "every model family's S: time per direction pair (3 channels, its demo truth, every term, its default accuracy, one thread) and, in the full ledger, the wall time of fitting its own demo data (linearised intervals); the families are different models, so no error is comparable (hairfit compare ranks what each loses on the same data)",
            "chiang-b0.3, chiang-b0.05": "relative error of the Chiang S per channel against 4096 width nodes, denominator floored at 1e-3 x the median reference S; time per sample (all channels, one thread); evaluations per second per core = 1/time_s; section baseline: the Marschner model's time on the same random directions (its error is not comparable)",
        }),
        rows,
        wall_time_s: t0.elapsed().as_secs_f64(),
    };
    ledger::write_ledger(set.staging(), &ledger)?;
    set.publish()?;
    Ok(ledger)
}
