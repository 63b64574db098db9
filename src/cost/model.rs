//! The ledger's model section: every root mode × effect set on a seeded set of directions,
//! time per evaluation against the relative error of S to exact roots with every effect.

use super::{time_per_call, CostRow, COST_SEED};
use crate::families::effects::{Effects, Lobes, ModelConfig, RootMode};
use crate::families::marschner::demo::demo_truth;
use crate::families::marschner::{scattering, Params};
use crate::geometry::Angles;
use crate::rng::SplitMix64;

/// A fixed, seeded set of directions: θ uniform in (−80°, 80°) (away from the degenerate ±90°),
/// φ uniform over the circle — every lobe, the glints and grazing θ_d occur.
pub fn representative_angles(n: usize, seed: u64) -> Vec<Angles> {
    let mut rng = SplitMix64::new(seed);
    (0..n)
        .map(|_| {
            Angles::from_degrees(
                rng.uniform_in(-80.0, 80.0),
                rng.uniform_in(-180.0, 180.0),
                rng.uniform_in(-80.0, 80.0),
                rng.uniform_in(-180.0, 180.0),
            )
        })
        .collect()
}

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

/// Relative error of `s` against `reference` with the denominator floored at 1e-3 × the median
/// reference value, so values in the far tails (underflowing lobes) do not dominate:
/// (max, rms, index of the max).
pub fn relative_error(s: &[f64], reference: &[f64]) -> (f64, f64, usize) {
    let mut sorted: Vec<f64> = reference
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(1.0);
    let floor = (1e-3 * median).max(f64::MIN_POSITIVE);
    let (mut max, mut sum, mut at) = (0.0f64, 0.0, 0usize);
    for (k, (&a, &b)) in s.iter().zip(reference).enumerate() {
        let e = (a - b).abs() / b.abs().max(floor);
        let e = if e.is_finite() { e } else { f64::INFINITY };
        sum += e * e;
        if e > max {
            max = e;
            at = k;
        }
    }
    (max, (sum / s.len().max(1) as f64).sqrt(), at)
}

/// A ledger row of `(section, knob, setting)` costing `time_s`: values `s` (every channel per
/// direction of `angles`) against `reference`, with where the error is worst.
pub(super) fn accuracy_row(
    (section, knob, setting): (&str, &str, String),
    time_s: f64,
    s: &[f64],
    reference: &[f64],
    angles: &[Angles],
) -> CostRow {
    let nc = s.len() / angles.len().max(1);
    let (max, rms, at) = relative_error(s, reference);
    let a = &angles[at / nc.max(1)];
    CostRow {
        section: section.into(),
        knob: knob.into(),
        setting,
        time_s,
        error_max: max,
        error_rms: rms,
        worst_at: format!(
            "theta_i {:.1}, phi_i {:.1}, theta_r {:.1}, phi_r {:.1} deg, channel {}",
            a.theta_i.to_degrees(),
            a.phi_i.to_degrees(),
            a.theta_r.to_degrees(),
            a.phi_r.to_degrees(),
            at % nc.max(1)
        ),
        pareto: false,
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_error_floors_the_denominator_and_finds_the_worst() {
        let reference = [1.0, 1.0, 1.0, 1e-12];
        let s = [1.0, 1.1, 1.0, 2e-12];
        let (max, rms, at) = relative_error(&s, &reference);
        // The 1e-12 entry's denominator is floored at 1e-3 (× median 1), so its error is 1e-9.
        assert_eq!(at, 1);
        assert!((max - 0.1).abs() < 1e-12);
        assert!((rms - (0.01f64 / 4.0).sqrt()).abs() < 1e-9);
    }

    #[test]
    fn the_angle_set_is_seeded_and_avoids_the_axis() {
        let a = representative_angles(500, 7);
        assert_eq!(a, representative_angles(500, 7));
        assert!(a
            .iter()
            .all(|x| x.theta_i.abs() < 80f64.to_radians() && x.theta_r.abs() < 80f64.to_radians()));
    }
}
