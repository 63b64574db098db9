//! The registry: the one list of model families ([`registry!`]), and [`ModelFamily`], the
//! `--model NAME` every command takes, made from it with its lookup of each family's facts.

use serde::{Deserialize, Serialize};

use super::{table, FamilyFacts, FamilyParams, OwnFamily, DEMO_CHANNELS};
use crate::error::{Error, Result};
use crate::families::table::DynTable;

/// The registry: every family hairfit knows, one line each, in the order `compare --models all`
/// reports them (the first is the default `--model`). `Own(TYPE)`: a family with its own
/// parameter file and options, whose TYPE implements [`FamilyFacts`] in its folder and
/// `crate::fit::family::Family` in its `fit` folder; `Table(TYPE)`: a [`table`] family, whose
/// TYPE implements [`table::TableFamily`]. [`ModelFamily`], its `ALL`, its facts and the fit's
/// `crate::fit::registry::family_fit` are all made from this list, so a new family is its folder
/// plus one line here.
macro_rules! registry {
    ($make:ident) => {
        $make! {
            Marschner => Own($crate::families::marschner::MarschnerFamily),
            Chiang => Own($crate::families::chiang::ChiangFamily),
            KajiyaKay => Table($crate::families::kajiya_kay::KajiyaKay),
            DEon => Table($crate::families::deon::DEon),
            Karis => Table($crate::families::karis::Karis),
            Frostbite => Table($crate::families::frostbite::Frostbite),
        }
    };
}
pub(crate) use registry;

/// [`ModelFamily`], its `ALL` and its registry entry, from the [`registry`] list.
macro_rules! model_family {
    ($($variant:ident => $kind:ident($ty:path)),* $(,)?) => {
        /// A model family (`--model NAME`, a parameter file's `"model"`): one per line of the
        /// registry; its name and everything else about it come from its facts
        /// ([`ModelFamily::facts`]).
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub enum ModelFamily {
            $($variant,)*
        }

        impl ModelFamily {
            /// Every family, in registry order (the order `compare --models all` reports them
            /// in).
            pub const ALL: [ModelFamily; [$(stringify!($variant)),*].len()] =
                [$(ModelFamily::$variant),*];

            /// The family's entry in the registry: the type that implements it.
            fn entry(self) -> Entry {
                match self {
                    $(ModelFamily::$variant => model_family!(@entry $kind($ty)),)*
                }
            }
        }
    };
    (@entry Own($ty:path)) => {
        Entry::Own(&$ty)
    };
    (@entry Table($ty:path)) => {
        Entry::Table(&table::Table::<$ty>::NEW)
    };
}
registry!(model_family);

impl Default for ModelFamily {
    /// The registry's first family.
    fn default() -> Self {
        ModelFamily::ALL[0]
    }
}

/// Written as its `--model` name.
impl Serialize for ModelFamily {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

/// Read from its `--model` name, exactly as written.
impl<'de> Deserialize<'de> for ModelFamily {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        Self::ALL
            .into_iter()
            .find(|f| f.as_str() == name)
            .ok_or_else(|| {
                serde::de::Error::custom(format!(
                    "unknown model family `{name}`: use one of {}",
                    Self::names()
                ))
            })
    }
}

/// `--model NAME`: the choices are the registry's names.
impl clap::ValueEnum for ModelFamily {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::ALL
    }
    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.as_str()))
    }
}

impl ModelFamily {
    /// The `--model` / `"model"` spelling.
    pub fn as_str(self) -> &'static str {
        self.facts().name()
    }

    /// What every command reads of the family: name, title, citation, parameter table and
    /// family-only options.
    pub fn facts(self) -> &'static dyn FamilyFacts {
        match self.entry() {
            Entry::Own(facts) => facts,
            Entry::Table(table) => table,
        }
    }

    /// The demo's true parameters of the family ([`DEMO_CHANNELS`] channels) as its parameter
    /// file: an `Own` family's [`OwnFamily::demo_truth`], a table family's
    /// [`table::demo_params`].
    pub fn demo_truth(self) -> FamilyParams {
        match self.entry() {
            Entry::Own(family) => family.demo_truth(),
            Entry::Table(t) => {
                let truth = table::demo_params(t.parameters(), DEMO_CHANNELS);
                table::TableParamFile::from_params(t, &truth).into()
            }
        }
    }

    /// The family's name in sentences and figure legends ("Marschner", "Chiang").
    pub fn title(self) -> &'static str {
        self.facts().title()
    }

    /// The family's model with its source, for help and lists ("Marschner 2003", "Karis 2016
    /// (Unreal Engine 5)").
    pub fn citation(self) -> &'static str {
        self.facts().citation()
    }

    /// The table family this is, or `None` for Marschner and Chiang.
    pub fn table(self) -> Option<&'static dyn DynTable> {
        match self.entry() {
            Entry::Own(_) => None,
            Entry::Table(table) => Some(table),
        }
    }

    /// The report's unit label of one of the family's parameters by its JSON name
    /// (`sigma_a[1]` included): `deg`, `per fiber radius`, or empty.
    pub fn unit_label(self, json_name: &str) -> &'static str {
        let base = json_name.split('[').next().unwrap_or(json_name);
        self.facts()
            .parameters()
            .iter()
            .find(|f| f.name == base)
            .map_or("", |f| f.unit.label())
    }

    /// True when the family takes `--terms` (Chiang and every table family).
    pub fn takes_terms(self) -> bool {
        self.own_options().contains(&"--terms")
    }

    /// A `--model` spelling (case-insensitive), or an error listing every family.
    pub fn parse(name: &str) -> Result<ModelFamily> {
        let name = name.trim();
        Self::ALL
            .into_iter()
            .find(|f| f.as_str().eq_ignore_ascii_case(name))
            .ok_or_else(|| {
                Error::Other(format!(
                    "unknown model family `{name}`: use one of {}",
                    Self::names()
                ))
            })
    }

    /// Every family's `--model` spelling, comma-separated.
    pub fn names() -> String {
        Self::ALL.map(ModelFamily::as_str).join(", ")
    }

    /// A comma-separated list of families (`marschner,chiang`), or `all`; at least one, none
    /// twice, in the order given.
    pub fn parse_list(list: &str) -> Result<Vec<ModelFamily>> {
        if list.trim().eq_ignore_ascii_case("all") {
            return Ok(Self::ALL.to_vec());
        }
        let mut out: Vec<ModelFamily> = Vec::new();
        for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let family = Self::parse(item)?;
            if out.contains(&family) {
                return Err(Error::Other(format!(
                    "`{item}` is named twice in the model list `{list}`"
                )));
            }
            out.push(family);
        }
        if out.is_empty() {
            return Err(Error::Other(format!(
                "the model list `{list}` is empty: name families from {} (or all)",
                Self::names()
            )));
        }
        Ok(out)
    }

    /// The family-only options this family takes (the flags of `cli::ModelArgs` that not every
    /// family takes; what `ModelArgs::check_family_options` accepts, which a unit test of
    /// `cli::compare` checks). A command that fits several families (`compare --models`) gives
    /// each one only these, and refuses such an option when no listed family takes it.
    pub fn own_options(self) -> &'static [&'static str] {
        self.facts().own_options()
    }
}

/// How a family is implemented: its own types (parameter file, model, fit), or a table family
/// whose file, model and fit [`table`] writes once.
enum Entry {
    Own(&'static dyn OwnFamily),
    Table(&'static dyn DynTable),
}

impl std::fmt::Display for ModelFamily {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}
