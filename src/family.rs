//! The model families hairfit evaluates and fits (`--model marschner|chiang`): which family
//! ([`ModelFamily`]), a parameter file of either ([`FamilyParams`], what fit.json's `params`,
//! params.json and truth.json hold), and a family's model ready to evaluate ([`FamilyModel`]).
//! Commands load and evaluate through these, so each command's contract holds for both.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::chiang::{
    self, scattering_batch, ChiangEffects, ChiangModel, ChiangParamFile, ChiangParams,
};
use crate::error::{Error, Result};
use crate::json_file::ParameterFile;
use crate::model::{
    scattering_batch as marschner_batch, scattering_by_lobe, scattering_lanes, Angles, ModelConfig,
    Params,
};
use crate::params::ParamFile;

/// A model family: Marschner 2003 (MODEL.md) or Chiang 2016 (CHIANG.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum ModelFamily {
    #[default]
    Marschner,
    Chiang,
}

impl ModelFamily {
    /// The `--model` / `"model"` spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            ModelFamily::Marschner => "marschner",
            ModelFamily::Chiang => "chiang",
        }
    }

    /// Every family, Marschner first (the order `compare --models all` reports them in).
    pub const ALL: [ModelFamily; 2] = [ModelFamily::Marschner, ModelFamily::Chiang];

    /// The family's name in sentences and figure legends ("Marschner", "Chiang").
    pub fn title(self) -> &'static str {
        match self {
            ModelFamily::Marschner => "Marschner",
            ModelFamily::Chiang => "Chiang",
        }
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
    /// family takes). A command that fits several families (`compare --models`) gives each one
    /// only these, and refuses such an option when no listed family takes it.
    pub fn own_options(self) -> &'static [&'static str] {
        match self {
            ModelFamily::Marschner => &["--mode", "--lobes", "--no-glints", "--no-eccentricity"],
            ModelFamily::Chiang => &["--terms", "--width-nodes"],
        }
    }
}

impl std::fmt::Display for ModelFamily {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A parameter file of either family. Written untagged, so a Marschner file is byte for byte
/// what it always was; a Chiang file carries `"model": "chiang"`. Read: a Marschner file (whose
/// keys differ from Chiang's; unknown keys are refused by both) else a Chiang file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum FamilyParams {
    Marschner(ParamFile),
    Chiang(ChiangParamFile),
}

impl From<ParamFile> for FamilyParams {
    fn from(p: ParamFile) -> Self {
        FamilyParams::Marschner(p)
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
        }
    }

    /// The Marschner file, if this is one.
    pub fn marschner(&self) -> Option<&ParamFile> {
        match self {
            FamilyParams::Marschner(p) => Some(p),
            FamilyParams::Chiang(_) => None,
        }
    }

    /// The Chiang file, if this is one.
    pub fn chiang(&self) -> Option<&ChiangParamFile> {
        match self {
            FamilyParams::Chiang(p) => Some(p),
            FamilyParams::Marschner(_) => None,
        }
    }

    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        match self {
            FamilyParams::Marschner(p) => p.n_channels(),
            FamilyParams::Chiang(p) => p.n_channels(),
        }
    }

    /// True when `sigma_a` is a single number (eval then writes one column `s`).
    pub fn sigma_a_is_scalar(&self) -> bool {
        let s = match self {
            FamilyParams::Marschner(p) => &p.sigma_a,
            FamilyParams::Chiang(p) => &p.sigma_a,
        };
        matches!(s, crate::params::SigmaA::Scalar(_))
    }

    /// `sigma_a` as written.
    pub fn sigma_a_mut(&mut self) -> &mut crate::params::SigmaA {
        match self {
            FamilyParams::Marschner(p) => &mut p.sigma_a,
            FamilyParams::Chiang(p) => &mut p.sigma_a,
        }
    }

    /// Check every value's domain (and a Chiang file's tag).
    pub fn validate(&self) -> Result<()> {
        match self {
            FamilyParams::Marschner(p) => p.validate(),
            FamilyParams::Chiang(p) => p.validate(),
        }
    }

    /// Values that look like a mistake though they are in the domain (radians in a degrees
    /// key), for the command to print as warnings.
    pub fn warnings(&self) -> Vec<String> {
        match self {
            FamilyParams::Marschner(p) => p.radians_in_degrees_keys(),
            FamilyParams::Chiang(_) => Vec::new(),
        }
    }

    /// The parameters as one JSON line (for error messages).
    pub fn json_line(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    /// Read the parameter file `path` as a `family` file. A `"model"` key, when present, must
    /// name `family` (the error names the file and `--model`); a Marschner file may carry
    /// `"model": "marschner"`, which is checked and dropped.
    pub fn load(path: &Path, family: ModelFamily) -> Result<FamilyParams> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::from_json_text(text, path, family)
    }

    /// [`FamilyParams::load`] of JSON text already read (the Python package's parameter dicts);
    /// `path` only names the source in error messages.
    pub fn from_json_text(text: String, path: &Path, family: ModelFamily) -> Result<FamilyParams> {
        let value = serde_json::from_str::<serde_json::Value>(&text).ok();
        if let Some(value) = &value {
            refuse_result_file(value, path)?;
        }
        let tag = value.and_then(|v| v.get("model").cloned());
        if let Some(tag) = &tag {
            let named = tag.as_str().unwrap_or_default();
            if named != family.as_str() {
                return Err(Error::Other(format!(
                    "{}: the file says \"model\": {tag}, but --model is {family}: pass --model {} \
                     (or use a {family} parameter file)",
                    path.display(),
                    if named.is_empty() {
                        "marschner|chiang"
                    } else {
                        named
                    }
                )));
            }
        }
        let located = |e: Error| match e {
            Error::Parameter { .. } => Error::Other(format!("{}: {e}", path.display())),
            other => other,
        };
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
}

impl FamilyModel {
    /// The model of `file` under the configuration of its family.
    pub fn new(file: &FamilyParams, config: ModelConfig, chiang: &ChiangModel) -> FamilyModel {
        match file {
            FamilyParams::Marschner(p) => FamilyModel::Marschner {
                params: p.to_params(),
                config,
            },
            FamilyParams::Chiang(p) => FamilyModel::Chiang {
                params: p.to_params(),
                model: chiang.clone(),
            },
        }
    }

    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        match self {
            FamilyModel::Marschner { params, .. } => params.sigma_a.len(),
            FamilyModel::Chiang { params, .. } => params.sigma_a.len(),
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
        }
    }

    /// [`Self::eval_batch`] the fastest way, for `hairfit eval`: Marschner's cubic mode four
    /// samples per vector ([`crate::model::scattering_lanes`], ~1e-13 relative from the
    /// reference).
    pub fn eval_batch_fast(&self, angles: &[Angles], out: &mut [f64]) {
        match self {
            FamilyModel::Marschner { params, config } => {
                scattering_lanes(params, config, angles, out)
            }
            FamilyModel::Chiang { .. } => self.eval_batch(angles, out),
        }
    }

    /// Per-lobe values `[R, TT, TRT]` per channel; for Chiang the TRT entry also holds the
    /// p ≥ 3 residual term, so the three add up to `S`.
    pub fn by_lobe(&self, angles: &Angles, out: &mut [[f64; 3]]) {
        match self {
            FamilyModel::Marschner { params, config } => {
                scattering_by_lobe(params, config, angles, out)
            }
            FamilyModel::Chiang { params, model } => {
                chiang::evaluator::scattering_by_lobe(params, model, angles, out);
            }
        }
    }
}

/// fit.json → `chiang`: a Chiang fit's model configuration (absent for Marschner fits, whose
/// configuration is `model`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ChiangRecord {
    /// The terms of `S` that were on.
    pub effects: ChiangEffects,
    /// Gauss–Legendre nodes of the width integral.
    pub width_nodes: usize,
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
        ChiangModel::new(self.effects, self.width_nodes)
    }
}
