//! Writing finished profiles into fit.json: each parameter's intervals, points and method per
//! side, and the status and warnings of a profile that stays open inside the bounds.

use super::search::SEARCH_RANGES;
use super::{End, Label, Profile};
use crate::files::{FitJson, Interval, ParamStatus};

/// Write `profiles` into fit.json's parameter entries (reporting units): intervals, profile
/// points, and the status and warnings of a profile that stays open inside the bounds.
pub fn apply(json: &mut FitJson, profiles: &[Profile<Label>]) {
    for pr in profiles {
        let name = pr.name.json_name.clone();
        let f = pr.name.factor;
        let Some(entry) = json.parameters.iter_mut().find(|e| e.name == name) else {
            continue;
        };
        let interval = |ends: &[End; 2]| Interval {
            lower: ends[0].value().map(|v| v * f),
            upper: ends[1].value().map(|v| v * f),
        };
        entry.interval_68 = Some(interval(&pr.end_68));
        entry.interval_95 = Some(interval(&pr.end_95));
        entry.profile = pr.points.iter().map(|&(v, d)| [v * f, d]).collect();
        entry.profile_method = Some(pr.methods);
        // A side that starts at the bound the parameter sits on is one-sided by nature (its
        // at-bound warning says so); every other open side is news.
        let open = |ends: &[End; 2], level: &str| -> Vec<String> {
            ends.iter()
                .zip(["below", "above"])
                .filter_map(|(e, side)| match *e {
                    End::Open { at, dchi2, bound } => {
                        if entry.status == ParamStatus::AtBound && dchi2 == 0.0 {
                            return None;
                        }
                        let at_txt = crate::plot::fmt_num(at * f);
                        Some(format!(
                            "{name}: the {level} profile interval is open {side} (reaches {} with {})",
                            if bound {
                                format!("the bound {at_txt}")
                            } else {
                                format!("{at_txt}, {SEARCH_RANGES} typical ranges from the best fit")
                            },
                            dchi2_text(dchi2)
                        ))
                    }
                    End::Closed(_) => None,
                })
                .collect()
        };
        let open_68 = open(&pr.end_68, "68%");
        let open_95 = open(&pr.end_95, "95%");
        if !open_68.is_empty() {
            if entry.status == ParamStatus::Free {
                entry.status = ParamStatus::Undetermined;
                let se = entry.std_error.take();
                for w in open_68 {
                    json.warnings.push(match se {
                        Some(se) => format!(
                            "{w}: not determined by the data; the linearised standard error {} understates it",
                            crate::plot::fmt_num(se)
                        ),
                        None => format!("{w}: not determined by the data"),
                    });
                }
            } else {
                json.warnings.extend(open_68);
            }
        } else {
            json.warnings.extend(open_95);
        }
        let value = entry.value.unwrap_or(f64::NAN);
        if let (Some(se), Some(i)) = (entry.std_error, entry.interval_68) {
            json.warnings
                .extend(se_beside_profile(&name, value, se, &i));
        }
        if let Some(i) = entry.interval_68 {
            json.warnings
                .extend(outside_yet_inside(&name, &entry.profile, &i));
        }
        if let Some(&(v, d)) = pr.points.iter().min_by(|a, b| a.1.total_cmp(&b.1)) {
            if d < -0.1 {
                json.warnings.push(format!(
                    "{name}: its profile found a lower cost (Δχ² = {d:.2} at {}): the fit stopped short of the minimum; the intervals are relative to the reported point",
                    crate::plot::fmt_num(v * f)
                ));
            }
        }
    }
}

/// `Δχ² = 2.06`; a profile point below the fit's cost reads `Δχ² ≤ 0` with how far below (a
/// negative Δχ² is no χ² difference a reader can place: the parameter is flat there, and the
/// fit's point lies that far above the valley's floor).
fn dchi2_text(d: f64) -> String {
    if d < 0.0 {
        format!(
            "Δχ² ≤ 0: the cost there is {:.2} below the fit's, the profile is flat",
            -d
        )
    } else {
        format!("Δχ² = {d:.2}")
    }
}

/// The linearised SE and the 68% profile interval disagree by more than this factor: say why.
const SE_PROFILE_RATIO: f64 = 3.0;

/// A warning when the standard error and the 68% profile interval's half-width differ by more
/// than [`SE_PROFILE_RATIO`]. The SE extrapolates χ²'s curvature at the fit, unbounded, along
/// every direction, including those the data barely determine; the profile re-fits the other
/// parameters within their bounds and follows the cost's real shape (a robust loss's too).
fn se_beside_profile(name: &str, value: f64, se: f64, i: &Interval) -> Option<String> {
    let (lo, hi) = (i.lower?, i.upper?);
    let half = 0.5 * (hi - lo);
    if !(half > 0.0 && se > 0.0 && value.is_finite()) {
        return None;
    }
    let ratio = se / half;
    if (1.0 / SE_PROFILE_RATIO..=SE_PROFILE_RATIO).contains(&ratio) {
        return None;
    }
    let (wider, factor) = if ratio > 1.0 {
        ("wider", ratio)
    } else {
        ("narrower", 1.0 / ratio)
    };
    Some(format!(
        "{name}: its standard error {} is {factor:.0}× {wider} than half its 68% profile interval ({}): the standard error extrapolates the cost's curvature at the fit without bounds (and along the directions the data barely determine), the profile re-fits the other parameters within their bounds on the actual cost; read the profile interval",
        crate::plot::fmt_num(se),
        crate::plot::fmt_num(half)
    ))
}

/// A warning when profile points outside the 68% interval lie below Δχ² = 1: the profile is
/// not a single valley (the re-fits found other minima of the remaining parameters), so the
/// interval, read from the crossings nearest the fit, leaves out values as good.
fn outside_yet_inside(name: &str, profile: &[[f64; 2]], i: &Interval) -> Option<String> {
    let outside = |v: f64| i.lower.is_some_and(|l| v < l) || i.upper.is_some_and(|u| v > u);
    let low: Vec<f64> = profile
        .iter()
        .filter(|q| outside(q[0]) && q[1] < 1.0)
        .map(|q| q[0])
        .collect();
    let (a, b) = low
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    (!low.is_empty()).then(|| {
        format!(
            "{name}: {} profile point(s) outside the 68% interval, at {}…{}, have Δχ² < 1: the profile has more than one valley (other minima of the parameters it re-fits), so the interval leaves out values as good",
            low.len(),
            crate::plot::fmt_num(a),
            crate::plot::fmt_num(b)
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_negative_dchi2_is_never_printed() {
        assert_eq!(dchi2_text(2.0647), "Δχ² = 2.06");
        let t = dchi2_text(-0.0144);
        assert!(
            !t.contains("-0.01") && t.contains("≤ 0") && t.contains("0.01 below"),
            "{t}"
        );
    }

    #[test]
    fn an_se_far_from_the_profile_is_explained() {
        // The cauchy fit of data/azimuthal_1ch_noisy.csv: k_g 2.4106 ± 0.5535, 68% profile
        // [2.3923, 2.4363] (half-width 0.022, 25× narrower).
        let i = Interval {
            lower: Some(2.392262),
            upper: Some(2.436283),
        };
        let w = se_beside_profile("k_g", 2.41058, 0.5535, &i).unwrap();
        assert!(w.contains("25× wider"), "{w}");
        // Within a factor 3 (a mildly skewed profile) there is nothing to say.
        assert!(se_beside_profile("k_g", 2.41058, 0.03, &i).is_none());
        // An open side has no half-width to compare.
        let open = Interval {
            lower: None,
            upper: Some(2.4),
        };
        assert!(se_beside_profile("k_g", 2.41, 0.5, &open).is_none());
    }

    #[test]
    fn a_second_valley_outside_the_interval_is_flagged() {
        let i = Interval {
            lower: Some(2.392262),
            upper: Some(2.436283),
        };
        let profile = [
            [2.3695, 4.72],
            [2.3696, 0.066],
            [2.3737, 0.057],
            [2.41, 0.0],
            [2.46, 3.9],
        ];
        let w = outside_yet_inside("k_g", &profile, &i).unwrap();
        assert!(
            w.contains("2 profile point(s)") && w.contains("2.370…2.374"),
            "{w}"
        );
        assert!(outside_yet_inside("k_g", &profile[3..], &i).is_none());
    }
}
