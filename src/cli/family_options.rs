//! The options of [`ModelArgs`] that only some families take (each family's
//! [`ModelFamily::own_options`]): whether each was given, how to reset it, and the refusal of
//! one given to a family that does not take it (it would silently do nothing).

use super::ModelArgs;
use crate::error::{Error, Result};
use crate::families::ModelFamily;

/// An option of [`ModelArgs`] that only some families take ([`ModelFamily::own_options`]):
/// whether it was given, and how to put it back to its default for a family without it.
pub struct FamilyOption {
    pub flag: &'static str,
    pub given: fn(&ModelArgs) -> bool,
    pub reset: fn(&mut ModelArgs),
}

/// Every family-only option, by the flag [`ModelFamily::own_options`] names it with.
pub const FAMILY_OPTIONS: [FamilyOption; 6] = [
    FamilyOption {
        flag: "--mode",
        given: |m| m.mode != Default::default(),
        reset: |m| m.mode = Default::default(),
    },
    FamilyOption {
        flag: "--lobes",
        given: |m| {
            crate::families::effects::Effects::parse_lobes(&m.lobes).ok()
                != Some(Default::default())
        },
        reset: |m| m.lobes = "R,TT,TRT".into(),
    },
    FamilyOption {
        flag: "--no-glints",
        given: |m| m.no_glints,
        reset: |m| m.no_glints = false,
    },
    FamilyOption {
        flag: "--no-eccentricity",
        given: |m| m.no_eccentricity,
        reset: |m| m.no_eccentricity = false,
    },
    FamilyOption {
        flag: "--terms",
        given: |m| m.terms.is_some(),
        reset: |m| m.terms = None,
    },
    FamilyOption {
        flag: "--width-nodes",
        given: |m| m.width_nodes.is_some(),
        reset: |m| m.width_nodes = None,
    },
];

pub fn takes(family: ModelFamily, flag: &str) -> bool {
    family.own_options().contains(&flag)
}

/// The families that take `flag`, as `--model` words joined by `|`.
pub fn owners(flag: &str) -> String {
    ModelFamily::ALL
        .into_iter()
        .filter(|&f| takes(f, flag))
        .map(ModelFamily::as_str)
        .collect::<Vec<_>>()
        .join("|")
}

impl ModelArgs {
    /// A family-only option given to a family that does not take it is an error naming the
    /// families that do and the options this one takes.
    pub(super) fn refuse_foreign_options(&self) -> Result<()> {
        let Some(o) = FAMILY_OPTIONS
            .iter()
            .find(|o| (o.given)(self) && !takes(self.family, o.flag))
        else {
            return Ok(());
        };
        let own = self.family.own_options();
        Err(Error::Other(format!(
            "{} applies to --model {} only, not --model {}; the {} model takes {}",
            o.flag,
            owners(o.flag),
            self.family,
            self.family.title(),
            match own {
                [] => "no family-only option".to_string(),
                [one] => one.to_string(),
                [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
            }
        )))
    }
}
