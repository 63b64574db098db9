//! The ledger's model section: every root mode × effect set on a seeded set of directions,
//! time per evaluation against the relative error of S to exact roots with every effect.

use crate::cost::{accuracy_row, representative_angles, time_per_call, CostRow, COST_SEED};
use crate::families::effects::{Effects, Lobes, ModelConfig, RootMode};
use crate::families::marschner::demo::demo_truth;
use crate::families::marschner::{scattering, Params};
use crate::geometry::Angles;

/// The effect sets of the ledger, cheapest first: R; R+TT; +TRT; +glints; +eccentricity.
pub fn effect_ladder() -> Vec<(&'static str, Effects)> {
    let lobes = |r, tt, trt| Lobes { r, tt, trt };
    let e = |l, glints, eccentricity| Effects {
        lobes: l,
        glints,
        eccentricity,
    };
    vec![
        ("R", e(lobes(true, false, false), false, false)),
        ("R+TT", e(lobes(true, true, false), false, false)),
        ("R+TT+TRT", e(lobes(true, true, true), false, false)),
        ("+glints", e(lobes(true, true, true), true, false)),
        ("+eccentricity", e(lobes(true, true, true), true, true)),
    ]
}

/// S for every angle (row-major angle × channel).
fn evaluate_all(p: &Params<f64>, config: &ModelConfig, angles: &[Angles]) -> Vec<f64> {
    let nc = p.sigma_a.len();
    let mut out = vec![0.0; angles.len() * nc];
    for (a, o) in angles.iter().zip(out.chunks_mut(nc)) {
        scattering(p, config, a, o);
    }
    out
}

/// Model section: every root mode × effect set against exact all-effects.
pub(super) fn model_rows(quick: bool) -> Vec<CostRow> {
    let n = if quick { 2000 } else { 20_000 };
    let min_s = if quick { 0.05 } else { 0.5 };
    let angles = representative_angles(n, COST_SEED);
    let p = demo_truth();
    let reference = evaluate_all(
        &p,
        &ModelConfig {
            mode: RootMode::Exact,
            effects: Effects::default(),
        },
        &angles,
    );
    let mut rows = Vec::new();
    for mode in [RootMode::Cubic, RootMode::Exact] {
        for (name, effects) in effect_ladder() {
            let config = ModelConfig { mode, effects };
            let mut s = Vec::new();
            let per_set = time_per_call(min_s, || s = evaluate_all(&p, &config, &angles));
            rows.push(accuracy_row(
                ("model", "roots+effects", format!("{mode} {name}")),
                per_set / n as f64,
                &s,
                &reference,
                &angles,
            ));
        }
    }
    rows
}
