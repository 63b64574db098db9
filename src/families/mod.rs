//! The model families hairfit evaluates and fits (`--model NAME`): which family
//! ([`ModelFamily`]), a parameter file of any ([`FamilyParams`], what fit.json's `params`,
//! params.json and truth.json hold), what the command line configures of each
//! ([`ModelSetup`]) and a family's model ready to evaluate ([`FamilyModel`]). Commands load and
//! evaluate through these, so each command's contract holds for every family. Marschner and
//! Chiang have their own types; every other family is a [`crate::families::table`].

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::families::chiang::{scattering_batch, ChiangModel, ChiangParamFile, ChiangParams};
use crate::families::marschner::params::ParamFile;
use crate::families::marschner::{
    scattering_batch as marschner_batch, scattering_by_lobe, scattering_lanes, ModelConfig, Params,
};
use crate::families::table::{DynTable, TableParamFile, TableParams, TermSet};
use crate::geometry::Angles;
use crate::json_file::ParameterFile;

pub mod chiang;
pub mod deon;
pub mod effects;
pub mod frostbite;
pub mod kajiya_kay;
pub mod karis;
pub mod marschner;
mod registry;
mod setup;
pub mod shared;
pub mod table;
pub use crate::geometry::FamilyFacts;
pub(crate) use registry::registry;
pub use registry::ModelFamily;
pub use setup::{ChiangRecord, ModelRecords, ModelSetup};

/// Colour channels of the demo's data (`hairfit demo`, the cost ledger, the battery).
pub const DEMO_CHANNELS: usize = 3;

/// What a family with its own types (listed `Own` in the registry) provides beyond its facts;
/// a table family has all of it from its table. Implemented in the family's folder.
pub trait OwnFamily: FamilyFacts {
    /// The demo's true parameters ([`DEMO_CHANNELS`] channels) as the family's parameter file.
    fn demo_truth(&self) -> FamilyParams;
}

/// A parameter file of any family. Written untagged, so a Marschner file is byte for byte
/// what it always was; every other family's file carries its `"model"` (Chiang's may leave it
/// out). Read as the tag says; untagged: a Marschner file (whose keys differ from Chiang's;
/// unknown keys are refused by both) else a Chiang file.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum FamilyParams {
    Marschner(ParamFile),
    Chiang(ChiangParamFile),
    Table(TableParamFile),
}

/// Read by the `"model"` tag (no tag: Marschner, else an untagged Chiang file), so a table
/// family whose keys happen to be another family's is still read as itself.
impl<'de> Deserialize<'de> for FamilyParams {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let value = serde_json::Value::deserialize(d)?;
        let tag = value
            .get("model")
            .and_then(|t| t.as_str())
            .map(str::to_owned);
        let err = |e: serde_json::Error| D::Error::custom(e.to_string());
        match tag.as_deref() {
            // Untagged: a Marschner file, else a Chiang file written without its tag.
            None => ParamFile::deserialize(&value)
                .map(FamilyParams::Marschner)
                .or_else(|e| {
                    ChiangParamFile::deserialize(&value)
                        .map(FamilyParams::Chiang)
                        .map_err(|_| e)
                })
                .map_err(err),
            Some(chiang::file::MODEL_TAG) => ChiangParamFile::deserialize(&value)
                .map(FamilyParams::Chiang)
                .map_err(err),
            Some(t) => {
                let family = ModelFamily::parse(t).map_err(|_| {
                    D::Error::custom(format!(
                        "\"model\": \"{t}\" is not a model family: use one of {}",
                        ModelFamily::names()
                    ))
                })?;
                let table = family.table().ok_or_else(|| {
                    D::Error::custom(format!(
                        "\"model\": \"{t}\": a {} parameter file is written without \"model\" \
                         (remove the key)",
                        family.title()
                    ))
                })?;
                TableParamFile::from_value(table, &value)
                    .map(FamilyParams::Table)
                    .map_err(err)
            }
        }
    }
}

impl From<ParamFile> for FamilyParams {
    fn from(p: ParamFile) -> Self {
        FamilyParams::Marschner(p)
    }
}

impl From<TableParamFile> for FamilyParams {
    fn from(p: TableParamFile) -> Self {
        FamilyParams::Table(p)
    }
}

impl From<ChiangParamFile> for FamilyParams {
    fn from(p: ChiangParamFile) -> Self {
        FamilyParams::Chiang(p)
    }
}

/// A fit.json or truth.json given where a parameter file goes: both hold the parameters under
/// `"params"` beside the model options they were made with, and `"model"` there is those
/// options, not a family. Refused with where the parameters are (not read from inside: the
/// options recorded there could silently disagree with this command's).
fn refuse_result_file(value: &serde_json::Value, path: &Path) -> Result<()> {
    let is_result = value.get("hairfit_version").is_some() && value.get("params").is_some();
    if !is_result {
        return Ok(());
    }
    let message = if value.get("verdict").is_some() {
        let beside = path.with_file_name("params.json");
        format!(
            "{}: this is a fit result (fit.json), not a parameter file: pass its params.json \
             (written beside it{})",
            path.display(),
            if beside.exists() {
                format!(": {}", beside.display())
            } else {
                String::new()
            }
        )
    } else {
        format!(
            "{}: this is a synth truth file, not a parameter file: its parameters are its \
             \"params\" object; save that object as a file of its own and pass that",
            path.display()
        )
    };
    Err(Error::Other(message))
}

impl FamilyParams {
    /// Which family the file belongs to.
    pub fn family(&self) -> ModelFamily {
        match self {
            FamilyParams::Marschner(_) => ModelFamily::Marschner,
            FamilyParams::Chiang(_) => ModelFamily::Chiang,
            FamilyParams::Table(p) => {
                ModelFamily::parse(p.table.name()).expect("every table family is a ModelFamily")
            }
        }
    }

    /// The Marschner file, if this is one.
    pub fn marschner(&self) -> Option<&ParamFile> {
        match self {
            FamilyParams::Marschner(p) => Some(p),
            _ => None,
        }
    }

    /// The Chiang file, if this is one.
    pub fn chiang(&self) -> Option<&ChiangParamFile> {
        match self {
            FamilyParams::Chiang(p) => Some(p),
            _ => None,
        }
    }

    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        match self {
            FamilyParams::Marschner(p) => p.n_channels(),
            FamilyParams::Chiang(p) => p.n_channels(),
            FamilyParams::Table(p) => p.n_channels(),
        }
    }

    /// True when the per-channel values are single numbers (eval then writes one column `s`).
    pub fn sigma_a_is_scalar(&self) -> bool {
        let s = match self {
            FamilyParams::Marschner(p) => &p.sigma_a,
            FamilyParams::Chiang(p) => &p.sigma_a,
            FamilyParams::Table(p) => return p.is_scalar(),
        };
        matches!(s, crate::geometry::SigmaA::Scalar(_))
    }

    /// Write every per-channel value given once as `n` values (`hairfit synth --channels n`);
    /// `Err((name, count))` names a per-channel value given for another number of channels.
    /// `Some(note)` when a value was replicated.
    pub fn replicate_channels(
        &mut self,
        n: usize,
    ) -> std::result::Result<Option<String>, (&'static str, usize)> {
        use crate::geometry::SigmaA;
        let sigma_a = match self {
            FamilyParams::Marschner(p) => &mut p.sigma_a,
            FamilyParams::Chiang(p) => &mut p.sigma_a,
            FamilyParams::Table(p) => {
                let mut replicated = Vec::new();
                for (f, v) in p.table.parameters().iter().zip(&mut p.values) {
                    if !f.per_channel || v.len() == n {
                        continue;
                    }
                    if v.len() != 1 {
                        return Err((f.name, v.len()));
                    }
                    *v = vec![v[0]; n];
                    replicated.push(format!("{} = {}", f.name, v[0]));
                }
                return Ok((!replicated.is_empty()).then(|| replicated.join(", ")));
            }
        };
        match sigma_a.clone() {
            SigmaA::Scalar(s) if n > 1 => {
                *sigma_a = SigmaA::PerChannel(vec![s; n]);
                Ok(Some(format!("sigma_a = {s}")))
            }
            SigmaA::PerChannel(v) if v.len() != n => Err(("sigma_a", v.len())),
            _ => Ok(None),
        }
    }

    /// Check every value's domain (and a Chiang file's tag).
    pub fn validate(&self) -> Result<()> {
        match self {
            FamilyParams::Marschner(p) => p.validate(),
            FamilyParams::Chiang(p) => p.validate(),
            FamilyParams::Table(p) => p.validate(),
        }
    }

    /// Values that look like a mistake though they are in the domain (radians in a degrees
    /// key), for the command to print as warnings.
    pub fn warnings(&self) -> Vec<String> {
        match self {
            FamilyParams::Marschner(p) => p.radians_in_degrees_keys(),
            _ => Vec::new(),
        }
    }

    /// The parameters as one JSON line (for error messages).
    pub fn json_line(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    /// Read the parameter file `path` as a `family` file. A `"model"` key, when present, must
    /// name `family` (the error names the file and `--model`); a Marschner file may carry
    /// `"model": "marschner"`, which is checked and dropped. A directory stands for the fit
    /// `hairfit fit --out` wrote there: its params.json (`eval --params fits/demo`, as
    /// `hairfit.eval("fits/demo", …)` in Python).
    pub fn load(path: &Path, family: ModelFamily) -> Result<FamilyParams> {
        let in_dir;
        let path = if path.is_dir() {
            in_dir = path.join("params.json");
            if !in_dir.is_file() {
                return Err(Error::Other(format!(
                    "{} is a directory without a params.json: give a parameter file, or the \
                     directory of a fit (`hairfit fit --out DIR` writes DIR/params.json)",
                    path.display()
                )));
            }
            in_dir.as_path()
        } else {
            path
        };
        let text = crate::json_file::read_text(path)?;
        Self::from_json_text(text, path, family)
    }

    /// [`FamilyParams::load`] of JSON text already read (the Python package's parameter dicts);
    /// `path` only names the source in error messages.
    pub fn from_json_text(text: String, path: &Path, family: ModelFamily) -> Result<FamilyParams> {
        let value = serde_json::from_str::<serde_json::Value>(&text).ok();
        if let Some(value) = &value {
            refuse_result_file(value, path)?;
        }
        let tag = value.as_ref().and_then(|v| v.get("model").cloned());
        if let Some(tag) = &tag {
            // Spelled as `--model` takes it: in any case.
            let named = tag.as_str().and_then(|n| ModelFamily::parse(n).ok());
            if named != Some(family) {
                return Err(Error::Other(format!(
                    "{}: the file says \"model\": {tag}, but --model is {family}: pass --model {} \
                     (or use a {family} parameter file)",
                    path.display(),
                    match named {
                        Some(f) => f.as_str().to_string(),
                        None => ModelFamily::ALL.map(ModelFamily::as_str).join("|"),
                    }
                )));
            }
        }
        // `"KARIS"` read as `"karis"`, the spelling the family's own reader checks.
        let text = match (&value, &tag) {
            (Some(v), Some(t)) if t.as_str() != Some(family.as_str()) => {
                let mut v = v.clone();
                v["model"] = serde_json::Value::from(family.as_str());
                serde_json::to_string(&v).unwrap_or(text)
            }
            _ => text,
        };
        let located = |e: Error| match e {
            Error::Parameter { .. } => Error::Other(format!("{}: {e}", path.display())),
            other => other,
        };
        if let Some(table) = family.table() {
            if tag.is_none() {
                // Another family's file read as this one: say whose it looks like.
                let other = value.as_ref().and_then(|v| {
                    [("alpha_r_deg", "marschner"), ("beta_m", "chiang")]
                        .into_iter()
                        .find(|(key, _)| v.get(*key).is_some())
                });
                if let Some((key, owner)) = other {
                    return Err(Error::Other(format!(
                        "{}: this looks like a {owner} parameter file (it has {key}) but --model \
                         is {family}: pass --model {owner}",
                        path.display()
                    )));
                }
            }
            return Ok(FamilyParams::Table(TableParamFile::from_json_str(
                &text, path, table,
            )?));
        }
        match family {
            ModelFamily::Chiang => {
                if tag.is_none() && text.contains("\"alpha_r_deg\"") {
                    return Err(Error::Other(format!(
                        "{}: this is a Marschner parameter file (it has alpha_r_deg) but --model \
                         is chiang: pass --model marschner, or write docs/chiang.md's keys eta, \
                         sigma_a, beta_m, beta_n, alpha_deg",
                        path.display()
                    )));
                }
                Ok(FamilyParams::Chiang(
                    ChiangParamFile::from_json_str(&text, path).map_err(located)?,
                ))
            }
            ModelFamily::Marschner => {
                if tag.is_none() && text.contains("\"beta_m\"") {
                    return Err(Error::Other(format!(
                        "{}: this looks like a Chiang parameter file (it has beta_m) but --model \
                         is marschner (the default): pass --model chiang",
                        path.display()
                    )));
                }
                let text = if tag.is_some() {
                    let mut v: serde_json::Map<String, serde_json::Value> =
                        serde_json::from_str(&text).map_err(|e| Error::json(path, &e, None))?;
                    v.remove("model");
                    serde_json::to_string(&v).unwrap_or_default()
                } else {
                    text
                };
                Ok(FamilyParams::Marschner(
                    ParamFile::from_json_str(&text, path).map_err(located)?,
                ))
            }
            _ => unreachable!("table families returned above"),
        }
    }
}

/// A family's model with its parameters, ready to evaluate `S` per channel.
#[derive(Debug, Clone)]
pub enum FamilyModel {
    Marschner {
        params: Params<f64>,
        config: ModelConfig,
    },
    Chiang {
        params: ChiangParams<f64>,
        model: ChiangModel,
    },
    Table {
        table: &'static dyn DynTable,
        params: TableParams<f64>,
        terms: TermSet,
    },
}

impl FamilyModel {
    /// The model of `file` under the configuration of its family.
    pub fn new(file: &FamilyParams, setup: &ModelSetup) -> FamilyModel {
        match file {
            FamilyParams::Marschner(p) => FamilyModel::Marschner {
                params: p.to_params(),
                config: setup.config,
            },
            FamilyParams::Chiang(p) => FamilyModel::Chiang {
                params: p.to_params(),
                model: setup.chiang.clone(),
            },
            FamilyParams::Table(p) => FamilyModel::Table {
                table: p.table,
                params: p.to_params(),
                terms: setup.table_terms(p.table),
            },
        }
    }

    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        match self {
            FamilyModel::Marschner { params, .. } => params.sigma_a.len(),
            FamilyModel::Chiang { params, .. } => params.sigma_a.len(),
            FamilyModel::Table { params, .. } => params.n_channels,
        }
    }

    /// `S` of a batch, `out[k·n + c]` for sample k, channel c, by the reference (scalar) model.
    /// Chiang batches share the width integral per exit direction.
    pub fn eval_batch(&self, angles: &[Angles], out: &mut [f64]) {
        match self {
            // One batch: the parameter-only factors are prepared once, not per row.
            FamilyModel::Marschner { params, config } => {
                marschner_batch(params, config, angles, out)
            }
            FamilyModel::Chiang { params, model } => scattering_batch(params, model, angles, out),
            FamilyModel::Table {
                table,
                params,
                terms,
            } => table.eval_batch(params, *terms, angles, out),
        }
    }

    /// [`Self::eval_batch`] the fastest way, for `hairfit eval`: Marschner's cubic mode four
    /// samples per vector ([`crate::families::marschner::scattering_lanes`], ~1e-13 relative from the
    /// reference).
    pub fn eval_batch_fast(&self, angles: &[Angles], out: &mut [f64]) {
        match self {
            FamilyModel::Marschner { params, config } => {
                scattering_lanes(params, config, angles, out)
            }
            _ => self.eval_batch(angles, out),
        }
    }

    /// Per-lobe values `[R, TT, TRT]` per channel; for Chiang the TRT entry also holds the
    /// p ≥ 3 residual term, for a table family each term adds to its column, so the three add
    /// up to `S`.
    pub fn by_lobe(&self, angles: &Angles, out: &mut [[f64; 3]]) {
        match self {
            FamilyModel::Marschner { params, config } => {
                scattering_by_lobe(params, config, angles, out)
            }
            FamilyModel::Chiang { params, model } => {
                chiang::evaluator::scattering_by_lobe(params, model, angles, out);
            }
            FamilyModel::Table {
                table,
                params,
                terms,
            } => table.by_lobe(params, *terms, angles, out),
        }
    }
}
