//! The registry: the one list of model families ([`registry!`]), and [`ModelFamily`], the
//! `--model NAME` every command takes, made from it with its lookup of each family's facts.

use serde::{Deserialize, Serialize};

use super::{
    table, FamilyFacts, FamilyFile, OwnFamily, OwnRecord, OwnTypes, ScatteringModel, DEMO_CHANNELS,
};
use crate::error::{Error, Result};
use crate::families::table::{DynTable, TableModel, TableParamFile};

/// The registry: every family hairfit knows, one line each, in the order `compare --models all`
/// reports them (the first is the default `--model`). `Own(TYPE)`: a family with its own
/// parameter file, model and options, whose TYPE implements [`OwnFamily`] and [`OwnTypes`] in
/// its folder and `crate::fit::family::Family` in its `fit` folder; `Table(TYPE)`: a [`table`] family, whose
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

/// [`FamilyParams`] and [`FamilyModel`] from the [`registry`] list: one variant per `Own`
/// family (its [`OwnTypes`]) and one for every table family, with the lookups that need each
/// family's types.
macro_rules! family_types {
    (@own [$($variant:ident($ty:path))*]) => {
        /// A parameter file of any family. Written untagged, each as its family writes it
        /// (every table family's file carries its `"model"`); read as its `"model"` tag says.
        #[derive(Debug, Clone, PartialEq, Serialize)]
        #[serde(untagged)]
        pub enum FamilyParams {
            $($variant(<$ty as OwnTypes>::File),)*
            Table(TableParamFile),
        }

        /// A family's model with its parameters, ready to evaluate `S` per channel.
        #[derive(Debug, Clone)]
        pub enum FamilyModel {
            $($variant(<$ty as OwnTypes>::Model),)*
            Table(TableModel),
        }

        $(impl From<<$ty as OwnTypes>::File> for FamilyParams {
            fn from(p: <$ty as OwnTypes>::File) -> Self {
                FamilyParams::$variant(p)
            }
        })*

        impl From<TableParamFile> for FamilyParams {
            fn from(p: TableParamFile) -> Self {
                FamilyParams::Table(p)
            }
        }

        impl FamilyParams {
            /// Every `Own` family's [`OwnTypes::SIGNATURE_KEY`].
            pub(super) const SIGNATURES: &[(&str, ModelFamily)] =
                &[$((<$ty as OwnTypes>::SIGNATURE_KEY, ModelFamily::$variant)),*];

            /// Which family the file belongs to.
            pub fn family(&self) -> ModelFamily {
                match self {
                    $(FamilyParams::$variant(_) => ModelFamily::$variant,)*
                    FamilyParams::Table(p) => ModelFamily::parse(p.table.name())
                        .expect("every table family is a ModelFamily"),
                }
            }

            /// The file, as every command asks of it.
            pub fn file(&self) -> &dyn FamilyFile {
                match self {
                    $(FamilyParams::$variant(p) => p,)*
                    FamilyParams::Table(p) => p,
                }
            }

            pub(super) fn file_mut(&mut self) -> &mut dyn FamilyFile {
                match self {
                    $(FamilyParams::$variant(p) => p,)*
                    FamilyParams::Table(p) => p,
                }
            }

            /// `text` read as the `Own` family `family`'s file (`None`: a table family).
            pub(super) fn read_own(
                family: ModelFamily,
                text: &str,
                path: &std::path::Path,
                tagged: bool,
            ) -> Option<Result<FamilyParams>> {
                match family {
                    $(ModelFamily::$variant => Some(
                        super::read_own_file::<$ty>(text, path, tagged).map(FamilyParams::$variant),
                    ),)*
                    _ => None,
                }
            }

            /// An untagged file: the first `Own` family's (registry order) it reads as, else the
            /// first one's error.
            pub(super) fn deserialize_untagged(
                value: &serde_json::Value,
            ) -> std::result::Result<FamilyParams, serde_json::Error> {
                let mut first = None;
                $(match <<$ty as OwnTypes>::File as Deserialize>::deserialize(value) {
                    Ok(p) => return Ok(FamilyParams::$variant(p)),
                    Err(e) => {
                        first.get_or_insert(e);
                    }
                })*
                Err(first.expect("the registry lists an Own family"))
            }

            /// A file tagged as the `Own` family `family`, if its files carry a tag.
            pub(super) fn deserialize_tagged(
                family: ModelFamily,
                value: &serde_json::Value,
            ) -> Option<std::result::Result<FamilyParams, serde_json::Error>> {
                match family {
                    $(ModelFamily::$variant if <$ty as OwnTypes>::TAGGED => Some(
                        <<$ty as OwnTypes>::File as Deserialize>::deserialize(value)
                            .map(FamilyParams::$variant),
                    ),)*
                    _ => None,
                }
            }
        }

        /// What an `Own` family records of its configuration beside `model` (fit.json's and
        /// truth.json's `chiang`), written as the family writes it.
        #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
        #[serde(untagged)]
        pub enum FamilyRecord {
            $($variant(<$ty as OwnTypes>::Record),)*
        }

        impl FamilyRecord {
            /// [`OwnRecord::describe`].
            pub fn describe(&self) -> Vec<String> {
                match self {
                    $(FamilyRecord::$variant(r) => r.describe(),)*
                }
            }

            /// [`OwnRecord::configure`].
            pub fn configure(&self, setup: &mut super::ModelSetup) -> Result<()> {
                match self {
                    $(FamilyRecord::$variant(r) => r.configure(setup),)*
                }
            }
        }

        impl FamilyModel {
            /// The model, as every command evaluates it.
            pub fn scattering(&self) -> &dyn ScatteringModel {
                match self {
                    $(FamilyModel::$variant(m) => m,)*
                    FamilyModel::Table(m) => m,
                }
            }
        }
    };
    (@own [$($own:tt)*] $variant:ident => Own($ty:path), $($rest:tt)*) => {
        family_types!(@own [$($own)* $variant($ty)] $($rest)*);
    };
    (@own [$($own:tt)*] $variant:ident => Table($ty:path), $($rest:tt)*) => {
        family_types!(@own [$($own)*] $($rest)*);
    };
    ($($line:tt)*) => {
        family_types!(@own [] $($line)*);
    };
}
registry!(family_types);

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

    /// What fit.json and truth.json record of the family's configuration in `setup`: an `Own`
    /// family's [`OwnFamily::records`], a table family's terms and the lobes they draw.
    pub fn records(self, setup: &super::ModelSetup) -> super::ModelRecords {
        match self.entry() {
            Entry::Own(family) => family.records(setup),
            Entry::Table(table) => setup.table_records(table),
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

    /// The table family this is, or `None` for an `Own` family.
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

    /// The family's terms, when `--terms` switches them.
    pub fn terms(self) -> Option<&'static [table::Term]> {
        match self.entry() {
            Entry::Own(family) => family.terms(),
            Entry::Table(table) => Some(table.terms()),
        }
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
