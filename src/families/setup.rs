//! What the command line configures of each family ([`ModelSetup`]) and what fit.json and
//! truth.json record of it ([`ModelRecords`]: `model`, an `Own` family's record, `terms`), so
//! commands carry one value from their options to their files and back without matching on
//! families.

use super::{FamilyRecord, ModelFamily};
use crate::error::Result;
use crate::families::effects::ModelConfig;
use crate::families::shared::quadrature::WidthNodes;
use crate::families::table::{self, DynTable, TermSet};

/// What the command line configures of the chosen family's model: the root mode and effects
/// (`--mode`, `--lobes`, `--no-glints`, `--no-eccentricity`), its terms (`--terms`, over the
/// family's [`ModelFamily::terms`]) and width rule (`--width-nodes`). A command builds it once
/// and the family reads what it takes ([`crate::families::FamilyFacts::own_options`]).
#[derive(Debug, Clone, Default)]
pub struct ModelSetup {
    pub config: ModelConfig,
    /// The terms that are on (`None`: the family's default).
    pub terms: Option<TermSet>,
    /// The width rule of a family that integrates over the fibre's width.
    pub width_nodes: WidthNodes,
}

impl ModelSetup {
    /// What fit.json and truth.json record of `family`'s configuration ([`ModelFamily::records`]).
    pub fn records(&self, family: ModelFamily) -> ModelRecords {
        family.records(self)
    }

    /// What result files record of the table family `table`'s configuration: the lobes its
    /// terms draw and the terms that are on.
    pub fn table_records(&self, table: &dyn DynTable) -> ModelRecords {
        let on = self.table_terms(table);
        ModelRecords {
            terms: Some(on.names(table.terms())),
            ..ModelRecords::of_config(table::lobes_config(table.terms(), on))
        }
    }

    /// The terms of `table` that are on.
    pub fn table_terms(&self, table: &dyn DynTable) -> TermSet {
        self.terms.unwrap_or(table.default_terms())
    }

    /// The setup a result file records: `model`, an `Own` family's record, a table family's
    /// term names (read against `family`'s terms; an unknown name is an error naming the file's
    /// family).
    pub fn from_records(
        family: ModelFamily,
        config: ModelConfig,
        record: Option<&FamilyRecord>,
        terms: Option<&[String]>,
    ) -> Result<ModelSetup> {
        let mut setup = ModelSetup {
            config,
            ..ModelSetup::default()
        };
        if let Some(record) = record {
            record.configure(&mut setup)?;
        }
        if let (Some(table), Some(names)) = (family.table(), terms) {
            setup.terms = Some(TermSet::parse(
                &names.join(","),
                table.terms(),
                family.as_str(),
            )?);
        }
        Ok(setup)
    }
}

/// A family's configuration as result files record it ([`ModelSetup::records`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelRecords {
    pub config: ModelConfig,
    /// What an `Own` family records beside `model` ([`crate::families::OwnTypes::Record`]).
    pub family_record: Option<FamilyRecord>,
    pub terms: Option<Vec<String>>,
}

impl ModelRecords {
    /// The records of a family whose configuration is `model` alone.
    pub fn of_config(config: ModelConfig) -> ModelRecords {
        ModelRecords {
            config,
            family_record: None,
            terms: None,
        }
    }

    /// The configuration in words, one item each, as the fit's summary and report show it:
    /// an `Own` family's record; a table family's terms; the root mode and effects.
    pub fn describe(&self) -> Vec<String> {
        let on_off = |b: bool| if b { "on" } else { "off" };
        if let Some(record) = &self.family_record {
            return record.describe();
        }
        if let Some(terms) = &self.terms {
            return vec![format!("terms {}", terms.join("+"))];
        }
        let e = &self.config.effects;
        let lobes: Vec<&str> = [(e.lobes.r, "R"), (e.lobes.tt, "TT"), (e.lobes.trt, "TRT")]
            .into_iter()
            .filter(|(on, _)| *on)
            .map(|(_, n)| n)
            .collect();
        vec![
            format!("{} roots", self.config.mode),
            format!("lobes {}", lobes.join("+")),
            format!("glints {}", on_off(e.glints)),
            format!("eccentricity {}", on_off(e.eccentricity)),
        ]
    }
}
