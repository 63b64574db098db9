//! Writing finished profiles into fit.json: each parameter's intervals, points and method per
//! side, and the status and warnings of a profile that stays open inside the bounds.

use super::{End, Profile, SEARCH_RANGES};
use crate::files::{FitJson, Interval, ParamStatus};
use crate::fit::problem::FitParam;

/// Write `profiles` into fit.json's parameter entries (reporting units): intervals, profile
/// points, and the status and warnings of a profile that stays open inside the bounds.
pub fn apply<P: FitParam>(json: &mut FitJson, profiles: &[Profile<P>]) {
    for pr in profiles {
        let name = pr.name.json_name();
        let f = pr.name.report_factor();
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
                            "{name}: the {level} profile interval is open {side} (reaches {} with Δχ² = {dchi2:.2})",
                            if bound {
                                format!("the bound {at_txt}")
                            } else {
                                format!("{at_txt}, {SEARCH_RANGES} typical ranges from the best fit")
                            }
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
