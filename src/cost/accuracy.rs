//! What every section of the ledger measures accuracy with: its seeded directions, the relative
//! error of S against a reference, and the row that reports both with where the error is worst.

use super::CostRow;
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
pub fn accuracy_row(
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
