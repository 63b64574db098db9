//! The ledger's Chiang section (`hairfit cost --model chiang`): time per evaluation of the Chiang
//! `S` against its accuracy, per width rule (the plain node counts and the default automatic
//! rule), with and without the cache per exit
//! direction, on random directions and on a rig ("evaluations per second per core" =
//! 1 / time_s). The ledger adds the default family's time as the yardstick
//! ([`crate::cost::yardstick_row`]).

use crate::cost::{
    accuracy_row, representative_angles, time_per_call, CostRow, FamilyCost, COST_SEED,
};
use crate::error::Result;
use crate::families::chiang::{
    scattering, scattering_batch, ChiangEffects, ChiangFamily, ChiangModel, ChiangParams,
};
use crate::geometry::Angles;

/// Node counts of the ledger (the reference uses [`REFERENCE_NODES`]).
pub const NODE_LADDER: [usize; 5] = [256, 512, 768, 1024, 2048];
/// The reference width rule: 4096 nodes (moves by 4e-9 at 8192, docs/chiang.md).
pub const REFERENCE_NODES: usize = 4096;

/// CHIANG.md's parameter set A as three channels, and the same with narrow lobes
/// (β_m = β_n = 0.05: the hardest case of the width integral).
fn parameter_sets() -> [(&'static str, ChiangParams<f64>); 2] {
    // The labels are the ledger's section names (one Pareto front and one panel each).
    let a = ChiangParams {
        eta: 1.55,
        sigma_a: vec![0.25, 0.45, 0.8],
        beta_m: 0.3,
        beta_n: 0.3,
        alpha: 2f64.to_radians(),
    };
    let narrow = ChiangParams {
        beta_m: 0.05,
        beta_n: 0.05,
        ..a.clone()
    };
    [("chiang-b0.3", a), ("chiang-b0.05", narrow)]
}

/// A rig: 5 θ_i × 13 θ_r × 36 φ_r (every θ_i sees each exit direction; 247 distinct (θ_r, |φ|)).
fn rig_angles() -> Vec<Angles> {
    let mut v = Vec::new();
    for tr in (-6..=6).map(|j| j as f64 * 10.0) {
        for pr in (-17..=18).map(|j| j as f64 * 10.0) {
            for ti in [-30.0, -15.0, 0.0, 15.0, 30.0] {
                v.push(Angles::from_degrees(ti, 0.0, tr, pr));
            }
        }
    }
    v
}

fn uncached(p: &ChiangParams<f64>, model: &ChiangModel, angles: &[Angles]) -> Vec<f64> {
    let nc = p.sigma_a.len();
    let mut out = vec![0.0; angles.len() * nc];
    for (a, o) in angles.iter().zip(out.chunks_mut(nc)) {
        scattering(p, model, a, o);
    }
    out
}

fn cached(p: &ChiangParams<f64>, model: &ChiangModel, angles: &[Angles]) -> Vec<f64> {
    let mut out = vec![0.0; angles.len() * p.sigma_a.len()];
    scattering_batch(p, model, angles, &mut out);
    out
}

/// The Chiang section's rows (one thread; time per sample, all channels).
impl FamilyCost for ChiangFamily {
    fn rows(&self, quick: bool) -> Result<Vec<CostRow>> {
        chiang_rows(quick)
    }

    fn metrics(&self) -> &'static [(&'static str, &'static str)] {
        &[("chiang-b0.3, chiang-b0.05", "relative error of the Chiang S per channel against 4096 width nodes, denominator floored at 1e-3 x the median reference S; time per sample (all channels, one thread); evaluations per second per core = 1/time_s")]
    }
}

fn chiang_rows(quick: bool) -> Result<Vec<CostRow>> {
    let min_s = if quick { 0.05 } else { 0.5 };
    let random = representative_angles(crate::cost::section_directions(quick), COST_SEED);
    let rig = rig_angles();
    let mut rows = Vec::new();
    for (label, p) in parameter_sets() {
        let reference_model = ChiangModel::new(ChiangEffects::default(), REFERENCE_NODES)?;
        for (dirs_label, angles) in [("random", &random), ("rig", &rig)] {
            let reference = cached(&p, &reference_model, angles);
            // The plain rules of the ladder, then the default automatic rule.
            let mut rules = Vec::new();
            for nodes in NODE_LADDER {
                let model = ChiangModel::new(ChiangEffects::default(), nodes)?;
                rules.push((format!("{nodes} nodes"), nodes == 1024, model));
            }
            rules.push(("auto".to_string(), true, ChiangModel::default()));
            for (rule, always, model) in rules {
                let variants: &[(&str, bool)] = if dirs_label == "rig" {
                    &[("cached", true), ("uncached", false)]
                } else {
                    &[("uncached", false)]
                };
                for &(how, use_cache) in variants {
                    if quick && !use_cache && dirs_label == "rig" && !always {
                        continue;
                    }
                    let mut s = Vec::new();
                    let t = time_per_call(min_s, || {
                        s = if use_cache {
                            cached(&p, &model, angles)
                        } else {
                            uncached(&p, &model, angles)
                        }
                    });
                    rows.push(accuracy_row(
                        (label, "width nodes", format!("{rule}, {dirs_label}, {how}")),
                        t / angles.len() as f64,
                        &s,
                        &reference,
                        angles,
                    ));
                }
            }
        }
    }
    Ok(rows)
}
