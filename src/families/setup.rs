//! What the command line configures of each family ([`ModelSetup`]) and what fit.json and
//! truth.json record of it ([`ModelRecords`]: `model`, `chiang`, `terms`), so commands carry
//! one value from their options to their files and back without matching on families.

use serde::{Deserialize, Serialize};

use super::ModelFamily;
use crate::error::Result;
use crate::families::chiang::{ChiangEffects, ChiangModel, WidthNodes};
use crate::families::effects::ModelConfig;
use crate::families::table::{self, DynTable, TermSet};

/// What the command line configures of each family's model (`--mode`, `--lobes`, … for
/// Marschner; `--terms`, `--width-nodes` for Chiang; `--terms` for a table family): a command
/// builds it once and each family reads its part.
#[derive(Debug, Clone, Default)]
pub struct ModelSetup {
    pub config: ModelConfig,
    pub chiang: ChiangModel,
    /// A table family's terms (`None`: every term).
    pub terms: Option<TermSet>,
}

impl ModelSetup {
    /// What fit.json and truth.json record of `family`'s configuration: `model` (for Chiang and
    /// the table families, the lobes they draw), Chiang's record, a table family's terms.
    pub fn records(&self, family: ModelFamily) -> ModelRecords {
        if let Some(table) = family.table() {
            return self.table_records(table);
        }
        match family {
            ModelFamily::Chiang => ModelRecords {
                config: crate::families::chiang::lobes_config(&self.chiang.effects),
                chiang: Some(ChiangRecord {
                    effects: self.chiang.effects,
                    width_nodes: self.chiang.width(),
                }),
                terms: None,
            },
            _ => ModelRecords::of_config(self.config),
        }
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

    /// The setup a result file records: `model`, Chiang's record, a table family's term names
    /// (read against `family`'s terms; an unknown name is an error naming the file's family).
    pub fn from_records(
        family: ModelFamily,
        config: ModelConfig,
        chiang: Option<&ChiangRecord>,
        terms: Option<&[String]>,
    ) -> Result<ModelSetup> {
        let chiang = match chiang {
            Some(r) => r.model()?,
            None => ChiangModel::default(),
        };
        let terms = match (family.table(), terms) {
            (Some(table), Some(names)) => Some(TermSet::parse(
                &names.join(","),
                table.terms(),
                family.as_str(),
            )?),
            _ => None,
        };
        Ok(ModelSetup {
            config,
            chiang,
            terms,
        })
    }
}

/// A family's configuration as result files record it ([`ModelSetup::records`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelRecords {
    pub config: ModelConfig,
    pub chiang: Option<ChiangRecord>,
    pub terms: Option<Vec<String>>,
}

impl ModelRecords {
    /// The records of a family whose configuration is `model` alone.
    pub fn of_config(config: ModelConfig) -> ModelRecords {
        ModelRecords {
            config,
            chiang: None,
            terms: None,
        }
    }

    /// The configuration in words, one item each, as the fit's summary and report show it:
    /// a table family's terms; Chiang's terms and width rule; the root mode and effects.
    pub fn describe(&self) -> Vec<String> {
        let on_off = |b: bool| if b { "on" } else { "off" };
        if let Some(c) = &self.chiang {
            return vec![
                format!("terms {}", c.effects_text()),
                format!("{} width nodes", c.width_nodes),
            ];
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

/// fit.json → `chiang`: a Chiang fit's model configuration (absent for Marschner fits, whose
/// configuration is `model`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ChiangRecord {
    /// The terms of `S` that were on.
    pub effects: ChiangEffects,
    /// The width rule: `"auto"` or the plain rule's Gauss–Legendre node count.
    pub width_nodes: WidthNodes,
}

impl ChiangRecord {
    /// `R+TT+TRT+residual`: the terms that were on.
    pub fn effects_text(&self) -> String {
        let e = &self.effects;
        [
            (e.r, "R"),
            (e.tt, "TT"),
            (e.trt, "TRT"),
            (e.residual, "residual"),
        ]
        .iter()
        .filter(|(on, _)| *on)
        .map(|(_, n)| *n)
        .collect::<Vec<_>>()
        .join("+")
    }

    /// The model this record describes (an out-of-range node count is an error).
    pub fn model(&self) -> Result<ChiangModel> {
        ChiangModel::with_width(self.effects, self.width_nodes)
    }
}
