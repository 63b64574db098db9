//! The model families hairfit evaluates and fits (`--model NAME`): which family
//! ([`ModelFamily`]), a parameter file of any ([`FamilyParams`], what fit.json's `params`,
//! params.json and truth.json hold), what the command line configures of each
//! ([`ModelSetup`]) and a family's model ready to evaluate ([`FamilyModel`]). Commands load and
//! evaluate through these, so each command's contract holds for every family. A family listed
//! `Own` in the registry brings its own file and model types ([`OwnTypes`]); every other family
//! is a [`crate::families::table`].

use std::fmt::Debug;
use std::path::Path;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::geometry::{Angles, SigmaA};
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
pub use registry::{FamilyModel, FamilyParams, FamilyRecord, ModelFamily};
pub use setup::{ModelRecords, ModelSetup};
pub use table::TableModel;

/// Colour channels of the demo's data (`hairfit demo`, the cost ledger, the battery).
pub const DEMO_CHANNELS: usize = 3;

/// What a family with its own types (listed `Own` in the registry) provides beyond its facts;
/// a table family has all of it from its table. Implemented in the family's folder.
pub trait OwnFamily: FamilyFacts {
    /// The demo's true parameters ([`DEMO_CHANNELS`] channels) as the family's parameter file.
    fn demo_truth(&self) -> FamilyParams;

    /// What fit.json and truth.json record of the family's configuration in `setup` (by default
    /// `model` alone).
    fn records(&self, setup: &ModelSetup) -> ModelRecords {
        ModelRecords::of_config(setup.config)
    }

    /// Its terms, when `--terms` switches them (`None`: it takes no `--terms`).
    fn terms(&self) -> Option<&'static [table::Term]> {
        None
    }
}

/// The types of a family listed `Own` in the registry, which make its variants of
/// [`FamilyParams`] and [`FamilyModel`].
pub trait OwnTypes {
    /// Its parameter file.
    type File: FamilyFile + ParameterFile + Clone + Debug + PartialEq + Serialize + DeserializeOwned;
    /// Its model with parameters, ready to evaluate.
    type Model: ScatteringModel + Clone + Debug;
    /// What result files record of its configuration beside `model` ([`NoRecord`]: nothing).
    type Record: OwnRecord + Clone + Debug + PartialEq + Serialize + DeserializeOwned;
    /// A key only this family's parameter files have: a file given to another `--model` that
    /// has it is named as this family's.
    const SIGNATURE_KEY: &'static str;
    /// True when its files may carry `"model": NAME`; false: they are written without, and a
    /// tag is checked and dropped when read.
    const TAGGED: bool;
}

/// What an `Own` family records of its configuration in result files ([`OwnTypes::Record`]).
pub trait OwnRecord {
    /// The configuration in words, one item each, as the fit's summary and report show it.
    fn describe(&self) -> Vec<String>;
    /// Set what the record holds in `setup` (an out-of-range value is an error).
    fn configure(&self, setup: &mut ModelSetup) -> Result<()>;
}

/// The record of a family that records nothing beyond `model`: there is no value of it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum NoRecord {}

impl OwnRecord for NoRecord {
    fn describe(&self) -> Vec<String> {
        match *self {}
    }
    fn configure(&self, _: &mut ModelSetup) -> Result<()> {
        match *self {}
    }
}

/// What every command asks of a parameter file, whatever its family.
pub trait FamilyFile {
    /// Number of colour channels.
    fn n_channels(&self) -> usize;
    /// True when the per-channel values are single numbers (eval then writes one column `s`).
    fn is_scalar(&self) -> bool;
    /// Write every per-channel value given once as `n` values (`hairfit synth --channels n`);
    /// `Err((name, count))` names a per-channel value given for another number of channels.
    /// `Some(note)` when a value was replicated.
    fn replicate_channels(
        &mut self,
        n: usize,
    ) -> std::result::Result<Option<String>, (&'static str, usize)>;
    /// Check every value's domain (and a tag's).
    fn check(&self) -> Result<()>;
    /// Values that look like a mistake though they are in the domain (radians in a degrees
    /// key), for the command to print as warnings.
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
    /// The model of these parameters under the configuration `setup` holds of the family.
    fn model(&self, setup: &ModelSetup) -> FamilyModel;
}

/// A parameter file whose only per-channel value is σ_a (Marschner's, Chiang's): what it
/// provides for [`FamilyFile`], which it then has.
pub trait SigmaAFile: ParameterFile {
    fn sigma_a(&self) -> &SigmaA;
    fn sigma_a_mut(&mut self) -> &mut SigmaA;
    /// [`FamilyFile::warnings`].
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
    /// [`FamilyFile::model`].
    fn model(&self, setup: &ModelSetup) -> FamilyModel;
}

impl<T: SigmaAFile> FamilyFile for T {
    fn n_channels(&self) -> usize {
        self.sigma_a().n_channels()
    }

    fn is_scalar(&self) -> bool {
        self.sigma_a().is_scalar()
    }

    fn replicate_channels(
        &mut self,
        n: usize,
    ) -> std::result::Result<Option<String>, (&'static str, usize)> {
        self.sigma_a_mut().replicate(n)
    }

    fn check(&self) -> Result<()> {
        ParameterFile::validate(self)
    }

    fn warnings(&self) -> Vec<String> {
        SigmaAFile::warnings(self)
    }

    fn model(&self, setup: &ModelSetup) -> FamilyModel {
        SigmaAFile::model(self, setup)
    }
}

/// A family's model with its parameters: `S` per channel.
pub trait ScatteringModel {
    /// Number of colour channels.
    fn n_channels(&self) -> usize;
    /// `S` of a batch, `out[k·n + c]` for sample k, channel c, by the reference (scalar) model.
    fn eval_batch(&self, angles: &[Angles], out: &mut [f64]);
    /// [`Self::eval_batch`] the fastest way, for `hairfit eval` (a family's lanes, within
    /// ~1e-13 relative of the reference).
    fn eval_batch_fast(&self, angles: &[Angles], out: &mut [f64]) {
        self.eval_batch(angles, out)
    }
    /// Per-lobe values `[R, TT, TRT]` per channel; terms beyond TRT add to the TRT column, a
    /// table family's terms each to its column, so the three add up to `S`.
    fn by_lobe(&self, angles: &Angles, out: &mut [[f64; 3]]);
    /// Its R lobe in the terms every family that has one shares, where a model of another
    /// family starts its fit to this one's `S` (`hairfit export`); `None`: no such lobe.
    fn specular_lobe(&self) -> Option<SpecularLobe> {
        None
    }
}

/// A model's R lobe (reflection at the cuticle), described alike by every family that has one.
#[derive(Debug, Clone, PartialEq)]
pub struct SpecularLobe {
    /// Refractive index of the fibre.
    pub eta: f64,
    /// Absorption per channel, per unit of the fibre's radius.
    pub sigma_a: Vec<f64>,
    /// R's standard deviation in θ_h = (θ_i + θ_r)/2, radians.
    pub width: f64,
    /// R's longitudinal shift, radians (Marschner's α_R and Chiang's α share its sign).
    pub shift: f64,
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
    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        self.file().n_channels()
    }

    /// True when the per-channel values are single numbers (eval then writes one column `s`).
    pub fn sigma_a_is_scalar(&self) -> bool {
        self.file().is_scalar()
    }

    /// [`FamilyFile::replicate_channels`].
    pub fn replicate_channels(
        &mut self,
        n: usize,
    ) -> std::result::Result<Option<String>, (&'static str, usize)> {
        self.file_mut().replicate_channels(n)
    }

    /// Check every value's domain (and a tag's).
    pub fn validate(&self) -> Result<()> {
        self.file().check()
    }

    /// [`FamilyFile::warnings`].
    pub fn warnings(&self) -> Vec<String> {
        self.file().warnings()
    }

    /// The parameters as one JSON line (for error messages).
    pub fn json_line(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    /// Read the parameter file `path` as a `family` file. A `"model"` key, when present, must
    /// name `family` (the error names the file and `--model`); a family whose files are written
    /// without it may carry it, checked and dropped. A directory stands for the fit
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
        } else if let Some(value) = &value {
            refuse_other_familys_file(value, path, family)?;
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
        if let Some(table) = family.table() {
            return Ok(FamilyParams::Table(table::TableParamFile::from_json_str(
                &text, path, table,
            )?));
        }
        FamilyParams::read_own(family, &text, path, tag.is_some())
            .expect("a family without a table is an Own family")
    }
}

/// An untagged file with a key only another family's files have, given to `family`: an error
/// naming whose it looks like.
fn refuse_other_familys_file(
    value: &serde_json::Value,
    path: &Path,
    family: ModelFamily,
) -> Result<()> {
    let other = FamilyParams::SIGNATURES
        .iter()
        .find(|(key, owner)| *owner != family && value.get(*key).is_some());
    match other {
        Some((key, owner)) => Err(Error::Other(format!(
            "{}: this looks like a {owner} parameter file (it has {key}) but --model is \
             {family}: pass --model {owner}",
            path.display()
        ))),
        None => Ok(()),
    }
}

/// Read `text` as a parameter file of the `Own` family `F` (`tagged`: it has a `"model"` key,
/// already checked to name `F`, which is dropped when `F`'s files are written without it).
fn read_own_file<F: OwnTypes>(text: &str, path: &Path, tagged: bool) -> Result<F::File> {
    let located = |e: Error| match e {
        Error::Parameter { .. } => Error::Other(format!("{}: {e}", path.display())),
        other => other,
    };
    if tagged && !F::TAGGED {
        let mut v: serde_json::Map<String, serde_json::Value> =
            serde_json::from_str(text).map_err(|e| Error::json(path, &e, None))?;
        v.remove("model");
        let text = serde_json::to_string(&v).unwrap_or_default();
        return F::File::from_json_str(&text, path).map_err(located);
    }
    F::File::from_json_str(text, path).map_err(located)
}

/// Read by the `"model"` tag (no tag: the first `Own` family, in registry order, whose file it
/// reads as), so a table family whose keys happen to be another family's is still read as
/// itself.
impl<'de> Deserialize<'de> for FamilyParams {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let value = serde_json::Value::deserialize(d)?;
        let err = |e: serde_json::Error| D::Error::custom(e.to_string());
        let Some(tag) = value.get("model").and_then(|t| t.as_str()) else {
            return FamilyParams::deserialize_untagged(&value).map_err(err);
        };
        let family = ModelFamily::parse(tag).map_err(|_| {
            D::Error::custom(format!(
                "\"model\": \"{tag}\" is not a model family: use one of {}",
                ModelFamily::names()
            ))
        })?;
        match family.table() {
            Some(table) => table::TableParamFile::from_value(table, &value)
                .map(FamilyParams::Table)
                .map_err(err),
            None => match FamilyParams::deserialize_tagged(family, &value) {
                Some(read) => read.map_err(err),
                None => Err(D::Error::custom(format!(
                    "\"model\": \"{tag}\": a {} parameter file is written without \"model\" \
                     (remove the key)",
                    family.title()
                ))),
            },
        }
    }
}

impl FamilyModel {
    /// The model of `file` under the configuration of its family.
    pub fn new(file: &FamilyParams, setup: &ModelSetup) -> FamilyModel {
        file.file().model(setup)
    }

    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        self.scattering().n_channels()
    }

    /// [`ScatteringModel::eval_batch`].
    pub fn eval_batch(&self, angles: &[Angles], out: &mut [f64]) {
        self.scattering().eval_batch(angles, out)
    }

    /// [`ScatteringModel::eval_batch_fast`].
    pub fn eval_batch_fast(&self, angles: &[Angles], out: &mut [f64]) {
        self.scattering().eval_batch_fast(angles, out)
    }

    /// [`ScatteringModel::by_lobe`].
    pub fn by_lobe(&self, angles: &Angles, out: &mut [[f64; 3]]) {
        self.scattering().by_lobe(angles, out)
    }
}
