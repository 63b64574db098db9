//! `--fix` of `hairfit compare`: every listed family is fitted with the same options, so a
//! fixed name must be a parameter of every listed family. Checked before any fit (and, for
//! channel indices, once the data load), naming the listed families that lack the parameter.

use crate::error::{Error, Result};
use crate::families::ModelFamily;
use crate::fit::registry::family_fit;

use super::findings::and_list;

/// `name[k]` → `(name, k)`: a per-channel parameter's name and channel.
fn split_channel(name: &str) -> Option<(&str, usize)> {
    let (base, rest) = name.split_once('[')?;
    let digits = rest.strip_suffix(']')?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some((base, digits.parse().ok()?))
}

/// A family's `--fix` names: those acting on every channel, and the per-channel ones'
/// base names (`sigma_a` for `sigma_a[c]`).
struct Names {
    family: ModelFamily,
    shared: Vec<String>,
    per_channel: Vec<String>,
}

impl Names {
    fn of(family: ModelFamily) -> Names {
        let (mut shared, mut per_channel) = (Vec::new(), Vec::new());
        for name in family_fit(family).parameter_names(1) {
            match split_channel(&name) {
                Some((base, _)) => per_channel.push(base.to_string()),
                None => shared.push(name),
            }
        }
        Names {
            family,
            shared,
            per_channel,
        }
    }

    /// `--fix NAME=…` names one of this family's parameters (any channel index: the data's
    /// channel count is checked by the family's own parser).
    fn has(&self, name: &str) -> bool {
        let base = split_channel(name).map_or(name, |(b, _)| b);
        self.per_channel.iter().any(|b| b == base)
            || (base == name && self.shared.iter().any(|s| s == name))
    }
}

/// `sigma_a (every channel), sigma_a[c] (one channel), eta`: what every family in `all` has.
fn common(all: &[Names]) -> String {
    let in_all = |pick: fn(&Names) -> &Vec<String>| -> Vec<String> {
        pick(&all[0])
            .iter()
            .filter(|n| all.iter().all(|f| pick(f).contains(n)))
            .cloned()
            .collect()
    };
    let mut out: Vec<String> = in_all(|n| &n.per_channel)
        .iter()
        .map(|b| format!("{b} (every channel), {b}[c] (one channel)"))
        .collect();
    out.extend(in_all(|n| &n.shared));
    if out.is_empty() {
        "nothing (the listed families share no parameter)".into()
    } else {
        out.join(", ")
    }
}

/// The titles of `families`, `A and B`.
fn titles(families: &[ModelFamily]) -> String {
    and_list(&families.iter().map(|f| f.title()).collect::<Vec<_>>())
}

/// Check compare's `--fix` items for the listed `families`: each name must belong to every
/// one (the error names the families that lack it, what they all have, and how to fix it in a
/// fit of its own), then each value as each family's fit would check it. `nc`: the data's
/// channel count, or `None` before the data load (each `sigma_a[k]` then names a channel).
pub fn check_fixes(families: &[ModelFamily], fix: &[String], nc: Option<usize>) -> Result<()> {
    let names: Vec<Names> = families.iter().map(|&f| Names::of(f)).collect();
    if names.is_empty() {
        return Ok(());
    }
    for item in fix {
        let Some((name, _)) = item.split_once('=') else {
            continue; // the families' own parser says how to write it
        };
        let name = name.trim();
        let (having, lacking): (Vec<&Names>, Vec<&Names>) = names.iter().partition(|n| n.has(name));
        if lacking.is_empty() {
            continue;
        }
        let lacking: Vec<ModelFamily> = lacking.iter().map(|n| n.family).collect();
        let fixable = common(&names);
        return Err(Error::Other(match having.first() {
            Some(owner) => {
                let having: Vec<ModelFamily> = having.iter().map(|n| n.family).collect();
                format!(
                    "--fix `{item}`: compare fits every listed model family with the same \
                     options, but `{name}` is a {} parameter the {} model{} not have; compare \
                     fixes only what every listed family has: {fixable}. To fix {name}, fit the \
                     {} model alone: hairfit fit DATA --model {} --fix {item}",
                    titles(&having),
                    titles(&lacking),
                    if lacking.len() == 1 { " does" } else { "s do" },
                    owner.family.title(),
                    owner.family,
                )
            }
            None => {
                let own: Vec<String> = names
                    .iter()
                    .map(|n| {
                        let mut all = n.per_channel.clone();
                        all.extend(n.shared.iter().cloned());
                        format!("{} has {}", n.family.title(), all.join(", "))
                    })
                    .collect();
                format!(
                    "--fix `{item}`: {}; compare fixes only what every listed family has: \
                     {fixable} ({})",
                    match families.len() {
                        1 => format!(
                            "the {} model has no parameter `{name}`",
                            families[0].title()
                        ),
                        2 => format!("neither model family has a parameter `{name}`"),
                        _ => format!("no listed model family has a parameter `{name}`"),
                    },
                    own.join("; ")
                )
            }
        }));
    }
    let nc = match nc {
        Some(nc) => nc,
        None => crate::fit::fixes::channels_named(fix)?,
    };
    for &family in families {
        family_fit(family).check_fixes(fix, nc)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fails(families: &[ModelFamily], fix: &str) -> String {
        check_fixes(families, &[fix.to_string()], None)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn a_name_must_belong_to_every_listed_family() {
        let all = ModelFamily::ALL;
        for family in all {
            // Whatever each family has on its own is refused once another family lacks it.
            let own = Names::of(family);
            for name in &own.shared {
                let lacking: Vec<ModelFamily> = all
                    .into_iter()
                    .filter(|&f| !Names::of(f).has(name))
                    .collect();
                let item = format!("{name}=1");
                if lacking.is_empty() {
                    continue;
                }
                let e = fails(&all, &item);
                assert!(
                    e.contains(&format!("the {} model", titles(&lacking))),
                    "{e}"
                );
                assert!(e.contains("hairfit fit DATA --model"), "{e}");
            }
        }
        let e = fails(&all, "bogus=1");
        assert!(e.contains("has a parameter `bogus`"), "{e}");
        let e = fails(&all[..1], "bogus=1");
        assert!(e.contains("model has no parameter `bogus`"), "{e}");
    }

    #[test]
    fn channels_and_shared_names_are_told_apart() {
        assert_eq!(split_channel("sigma_a[12]"), Some(("sigma_a", 12)));
        assert_eq!(split_channel("sigma_a[]"), None);
        assert_eq!(split_channel("eta"), None);
        let m = Names::of(ModelFamily::Marschner);
        assert!(m.has("sigma_a") && m.has("sigma_a[3]") && m.has("eta"));
        assert!(!m.has("eta[0]") && !m.has("beta_m"));
    }
}
