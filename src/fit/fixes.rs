//! `--fix NAME=VALUE` and the free set for any model family: names, reporting units and
//! bounds come from the family's parameter table through [`FitParam`], so every family parses,
//! checks and reports fixes one way.

use crate::error::{Error, Result};
use crate::fit::problem::FitParam;

/// Parse `--fix NAME=VALUE` items (reporting units; `sigma_a=v` fixes every channel) into
/// natural-unit values inside the model's domain (a fixed parameter need not lie within the
/// fit bounds, which only limit where a fit moves the free ones). `all` is the family's parameters, `what` names
/// them in errors (`parameter`, `Chiang parameter`), `example` is a valid item for the hint.
pub fn parse_fixes<P: FitParam>(
    items: &[String],
    all: &[P],
    what: &str,
    example: &str,
) -> Result<Vec<(P, f64)>> {
    let mut out: Vec<(P, f64)> = Vec::new();
    for item in items {
        let (name, value) = item.split_once('=').ok_or_else(|| {
            Error::Other(format!(
                "--fix `{item}`: write NAME=VALUE, e.g. --fix {example}"
            ))
        })?;
        let name = name.trim();
        let v: f64 = value.trim().parse().map_err(|_| {
            Error::Other(format!(
                "--fix `{item}`: `{}` is not a number",
                value.trim()
            ))
        })?;
        // `NAME=v` of a per-channel parameter fixes every channel (`sigma_a=0.4`).
        let channels: Vec<P> = all
            .iter()
            .copied()
            .filter(|p| p.channel().is_some() && split_channel(&p.json_name()).0 == name)
            .collect();
        let names: Vec<P> = if !channels.is_empty() {
            channels
        } else {
            let base = split_channel(name).0;
            let nc = all
                .iter()
                .filter(|p| p.channel().is_some() && split_channel(&p.json_name()).0 == base)
                .count();
            match all.iter().find(|p| p.json_name() == name) {
                Some(&p) => vec![p],
                None if channel_of(name).is_some() && nc > 0 => {
                    return Err(Error::Other(format!(
                        "--fix `{item}`: `{name}` names a channel the data do not have: they have \
                         {nc} channel{} ({base}[0]{}); {base}=VALUE fixes every channel",
                        if nc == 1 { "" } else { "s" },
                        if nc > 1 {
                            format!(" … {base}[{}]", nc - 1)
                        } else {
                            String::new()
                        }
                    )));
                }
                None => {
                    let mut known: Vec<String> = Vec::new();
                    for p in all {
                        let n = p.json_name();
                        let shown = split_channel(&n).0.to_string();
                        if !known.contains(&shown) {
                            known.push(shown);
                        }
                    }
                    return Err(Error::Other(format!(
                        "--fix `{item}`: unknown {what} `{name}`; use one of {} (NAME[c] for one \
                         channel of a per-channel parameter)",
                        known.join(", ")
                    )));
                }
            }
        };
        for p in names {
            let x = v / p.report_factor();
            // A fixed parameter does not move, so the model's domain applies, not the fit bound.
            if let Err(why) = p.check_domain(v) {
                return Err(Error::Parameter {
                    name: p.json_name(),
                    value: v,
                    message: format!("--fix value outside the model's domain: {why}"),
                });
            }
            if let Some((_, earlier)) = out.iter().find(|(q, _)| *q == p) {
                return Err(Error::Other(format!(
                    "--fix `{item}`: {} is already fixed (to {}) by an earlier --fix; give each parameter once",
                    p.json_name(),
                    earlier * p.report_factor()
                )));
            }
            out.push((p, x));
        }
    }
    Ok(out)
}

/// The channel `k` of a `sigma_a[k]` name (digits only), if it is one.
pub fn channel_index(name: &str) -> Option<usize> {
    channel_of(name).filter(|_| split_channel(name).0 == "sigma_a")
}

/// The channel `k` of any per-channel name `base[k]` (digits only), if it is one.
pub fn channel_of(name: &str) -> Option<usize> {
    let digits = name.strip_suffix(']')?.split_once('[')?.1;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// `("base", Some("k"))` of `base[k]`; `(name, None)` for any other name.
pub fn split_channel(name: &str) -> (&str, Option<&str>) {
    match name.strip_suffix(']').and_then(|n| n.split_once('[')) {
        Some((base, k)) => (base, Some(k)),
        None => (name, None),
    }
}

/// The fewest channels under which every `sigma_a[k]` of these `--fix` items names a channel
/// (at least one): what options are checked against before the data's own count is known.
/// An error when an index is so large (over a million) that no dataset has that many channels.
pub fn channels_named(items: &[String]) -> Result<usize> {
    const MAX_CHANNELS: usize = 1 << 20;
    let most = items
        .iter()
        .filter_map(|i| channel_of(i.split_once('=')?.0.trim()))
        .max()
        .map_or(1, |k| k.saturating_add(1));
    if most > MAX_CHANNELS {
        return Err(Error::Other(format!(
            "--fix {}: a channel index that large names no channel of any dataset",
            items.join(" --fix ")
        )));
    }
    Ok(most)
}

/// The parameters a fit varies and the values of the others.
pub struct FreeSet<P: FitParam> {
    /// `--fix` values in natural units.
    pub fixes: Vec<(P, f64)>,
    /// Reference values with the fixes applied.
    pub base: P::Set,
    pub free: Vec<P>,
}

impl<P: FitParam> FreeSet<P> {
    /// `reference` with `fixes` applied; free: the `candidates` (what the effects in play use)
    /// not fixed. Each parameter of `every` (what all effects would use) that is neither a
    /// candidate nor fixed gets a warning `NAME: not fitted (why)`.
    pub fn new(
        fixes: Vec<(P, f64)>,
        mut reference: P::Set,
        candidates: Vec<P>,
        every: Vec<P>,
        why: &str,
        warnings: &mut Vec<String>,
    ) -> Self {
        for &(p, x) in &fixes {
            p.set(&mut reference, x);
        }
        let is_fixed = |p: &P| fixes.iter().any(|(f, _)| f == p);
        for p in &every {
            if !candidates.contains(p) && !is_fixed(p) {
                warnings.push(format!("{}: not fitted ({why})", p.json_name()));
            }
        }
        let free = candidates.into_iter().filter(|p| !is_fixed(p)).collect();
        FreeSet {
            fixes,
            base: reference,
            free,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::families::chiang::ChiangParamName;
    use crate::families::marschner::ParamName;

    fn items(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn a_channel_beyond_the_data_is_named_as_such() {
        let all = crate::families::marschner::parameters::all_parameters(3);
        let e = parse_fixes(&items(&["sigma_a[5]=0.3"]), &all, "parameter", "")
            .unwrap_err()
            .to_string();
        assert!(e.contains("3 channels (sigma_a[0] … sigma_a[2])"), "{e}");
        assert_eq!(
            channels_named(&items(&["sigma_a[5]=0.3", "eta=1.5"])).unwrap(),
            6
        );
        assert_eq!(channels_named(&items(&["k_g=2"])).unwrap(), 1);
        assert!(channels_named(&items(&["sigma_a[99999999999]=1"]))
            .unwrap_err()
            .to_string()
            .contains("names no channel of any dataset"));
        assert_eq!(channel_index("sigma_a[+1]"), None);
    }

    #[test]
    fn sigma_a_fixes_every_channel_and_degrees_convert() {
        let all = crate::families::marschner::parameters::all_parameters(3);
        let fixes = parse_fixes(
            &items(&["sigma_a=0.5", "alpha_r_deg=-7"]),
            &all,
            "parameter",
            "",
        )
        .unwrap();
        let names: Vec<String> = fixes.iter().map(|(p, _)| p.json_name()).collect();
        assert_eq!(
            names,
            ["sigma_a[0]", "sigma_a[1]", "sigma_a[2]", "alpha_r_deg"]
        );
        assert_eq!(fixes[3].0, ParamName::AlphaR);
        assert!((fixes[3].1 - (-7f64).to_radians()).abs() < 1e-15);
    }

    #[test]
    fn errors_name_the_item_and_the_family() {
        let all = crate::families::chiang::all_parameters(1);
        let e = |v: &[&str]| {
            parse_fixes::<ChiangParamName>(&items(v), &all, "Chiang parameter", "beta_n=0.3")
                .unwrap_err()
                .to_string()
        };
        assert!(e(&["beta_n"]).contains("e.g. --fix beta_n=0.3"));
        assert!(e(&["k_g=2"]).contains("unknown Chiang parameter `k_g`"));
        assert!(e(&["beta_n=x"]).contains("`x` is not a number"));
        assert!(e(&["beta_n=0.3", "beta_n=0.4"]).contains("already fixed (to 0.3)"));
        assert!(e(&["beta_n=1e9"]).contains("outside the model's domain"));
    }

    /// A fixed parameter does not move: any value the model accepts is a valid fix, even one
    /// outside the fit bound (η = 3 > 2.5), and the message for one it does not accept names
    /// the domain rather than the fit bound.
    #[test]
    fn a_fix_may_lie_anywhere_in_the_domain() {
        let all = crate::families::marschner::parameters::all_parameters(1);
        let fixes = parse_fixes(&items(&["eta=3", "sigma_a=60"]), &all, "parameter", "").unwrap();
        assert_eq!(fixes[0], (ParamName::Eta, 3.0));
        assert_eq!(fixes[1], (ParamName::SigmaA(0), 60.0));
        let e = parse_fixes(&items(&["eta=11"]), &all, "parameter", "")
            .unwrap_err()
            .to_string();
        assert!(e.contains("(1, 10]"), "{e}");
        assert!(!e.contains("2.5"), "{e}");
    }

    #[test]
    fn the_free_set_drops_fixed_and_warns_about_unused_parameters() {
        let all = crate::families::marschner::parameters::all_parameters(1);
        let fixes = parse_fixes(&items(&["k_g=2"]), &all, "parameter", "").unwrap();
        let mut warnings = Vec::new();
        let set = FreeSet::new(
            fixes,
            crate::families::marschner::parameters::reference_params(1),
            vec![ParamName::SigmaA(0), ParamName::KG],
            vec![ParamName::SigmaA(0), ParamName::KG, ParamName::WC],
            "why",
            &mut warnings,
        );
        assert_eq!(set.free, [ParamName::SigmaA(0)]);
        assert_eq!(set.base.k_g, 2.0);
        assert_eq!(warnings, ["w_c_deg: not fitted (why)"]);
    }
}
