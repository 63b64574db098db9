//! What `hairfit export` reads from a fit directory: the model family and its parameters
//! (`params.json`, read as its `"model"` says), the fit's quality, channel
//! names, switched-off terms and held parameters (`fit.json`, read loosely so every family's
//! records serve), and the measured directions (`curves.csv`, one per sample).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::error::{Error, Result};
use crate::families::effects::ModelConfig;
use crate::families::shared::quadrature::WidthNodes;
use crate::families::{
    FamilyModel, FamilyParams, FamilyRecord, ModelFamily, ModelSetup, SpecularLobe,
};
use crate::files::fit_json::FAMILY_RECORD_KEY;
use crate::files::Curves;
use crate::geometry::Angles;

/// At most this many measured directions enter a mapping (a 3-channel, 8-variable Jacobian of
/// 20 000 directions is ≈ 4 MB); larger fits are thinned evenly and the header says so.
pub const MAX_MEASURED_DIRECTIONS: usize = 20_000;

/// The fitted model whose `S` a renderer must reproduce: the fit's family and its model under
/// the configuration the fit ran with (a renderer's target may start from its parameters).
#[derive(Debug, Clone)]
pub struct SourceModel {
    pub family: ModelFamily,
    pub model: FamilyModel,
}

impl SourceModel {
    /// The family's name in sentences (`"Marschner"`).
    pub fn name(&self) -> &'static str {
        self.family.title()
    }

    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        self.model.n_channels()
    }

    /// Its R lobe, where another family's model starts its fit ([`SpecularLobe`]).
    pub fn specular_lobe(&self) -> Option<SpecularLobe> {
        self.model.scattering().specular_lobe()
    }

    /// `S` at every direction, `out[k·n + c]`.
    pub fn scattering(&self, angles: &[Angles]) -> Vec<f64> {
        let mut out = vec![0.0; angles.len() * self.n_channels()];
        self.model.eval_batch(angles, &mut out);
        out
    }
}

/// A fit directory as export sees it.
#[derive(Debug, Clone)]
pub struct SourceFit {
    pub dir: PathBuf,
    pub model: SourceModel,
    /// Channel names from fit.json (`c0, c1, …` when it has none).
    pub channels: Vec<String>,
    /// hairfit version that wrote the fit, when recorded.
    pub fitted_by: Option<String>,
    /// The fit's status and residual summary, one line.
    pub quality: String,
    /// One direction per measured sample (from curves.csv), in file order, duplicates removed.
    pub measured: Vec<Angles>,
    /// Where the measured directions came from, or why there are none.
    pub measured_from: String,
    /// Parameters the fit did not vary or the data did not determine, one phrase each
    /// (`beta_n = 0.3 (held: ...)`): the renderer gets these values all the same.
    pub held: Vec<String>,
}

impl SourceFit {
    /// Read `dir/params.json`, `dir/fit.json` and (if present) `dir/curves.csv`.
    pub fn load(dir: &Path) -> Result<SourceFit> {
        let params_path = dir.join("params.json");
        let text = crate::json_file::read_text(&params_path)?;
        let tag = serde_json::from_str::<Value>(&text)
            .ok()
            .and_then(|v| v.get("model").and_then(Value::as_str).map(str::to_owned));
        let fit_path = dir.join("fit.json");
        let fit: Value = crate::files::read_json(
            &fit_path,
            "fit.json is written by `hairfit fit` — re-run the fit to regenerate it",
        )?;
        // params.json is fit.json's `params` written apart: a file edited or copied in from
        // another fit would export under this fit's name, quality line and channels.
        if let (Some(recorded), Ok(given)) =
            (fit.get("params"), serde_json::from_str::<Value>(&text))
        {
            if *recorded != given {
                return Err(Error::Other(format!(
                    "{}: differs from the `params` of {} (edited, or copied from another fit?); \
                     export reads a fit's own files: re-run the fit, or put back its params.json",
                    params_path.display(),
                    fit_path.display()
                )));
            }
        }
        let family = match tag.as_deref() {
            Some(tag) => ModelFamily::parse(tag)
                .map_err(|e| Error::Other(format!("{}: {e}", params_path.display())))?,
            None => ModelFamily::default(),
        };
        let file = FamilyParams::from_json_text(text, &params_path, family)?;
        let mut setup = fit_setup(&fit, family)?;
        // At the default width rule, the renderers' reference, whatever rule the fit used.
        setup.width_nodes = WidthNodes::default();
        let model = SourceModel {
            family,
            model: FamilyModel::new(&file, &setup),
        };
        let n = model.n_channels();
        let channels = fit
            .pointer("/data/channels")
            .and_then(Value::as_array)
            .map(|a| {
                a.iter()
                    .filter_map(Value::as_str)
                    .map(str::to_owned)
                    .collect::<Vec<_>>()
            })
            .filter(|c| c.len() == n)
            .unwrap_or_else(|| (0..n).map(|c| format!("c{c}")).collect());
        let curves_path = dir.join("curves.csv");
        let (measured, measured_from) = if curves_path.exists() {
            let curves = Curves::read_csv(&curves_path)?;
            let mut seen = BTreeSet::new();
            let mut out = Vec::new();
            for (&id, angles) in curves.sample_id.iter().zip(&curves.sample_angles) {
                if seen.insert(id) {
                    let [ti, pi, tr, pr] = *angles;
                    let a = Angles::from_degrees(ti, pi, tr, pr);
                    if a.validate().is_ok() {
                        out.push(a);
                    }
                }
            }
            let total = out.len();
            // The mapping's Jacobian has a row per direction and channel: thin a huge fit
            // evenly rather than allocate gigabytes (the sphere is always added in full).
            if total > MAX_MEASURED_DIRECTIONS {
                let step = total.div_ceil(MAX_MEASURED_DIRECTIONS);
                out = out.into_iter().step_by(step).collect();
            }
            let from = if out.len() < total {
                format!(
                    "{} ({} of {total} samples, every {}th)",
                    curves_path.display(),
                    out.len(),
                    total.div_ceil(MAX_MEASURED_DIRECTIONS)
                )
            } else {
                format!("{} ({total} samples)", curves_path.display())
            };
            (out, from)
        } else {
            (
                Vec::new(),
                format!("none: {} is absent", curves_path.display()),
            )
        };
        Ok(SourceFit {
            dir: dir.to_path_buf(),
            model,
            channels,
            fitted_by: fit
                .get("hairfit_version")
                .and_then(Value::as_str)
                .map(str::to_owned),
            quality: quality_line(&fit),
            measured,
            measured_from,
            held: held_parameters(&fit),
        })
    }

    /// The channels as renderer RGB: 1 channel is grey, 3 are taken as R, G, B in file order.
    /// Returns the names in that order; anything else is an error (renderers take RGB).
    pub fn rgb_order(&self) -> Result<Vec<String>> {
        match self.channels.len() {
            1 | 3 => Ok(self.channels.clone()),
            n => Err(Error::Other(format!(
                "{}: the fit has {n} channels ({}); renderers take RGB, so export needs a fit \
                 with 1 channel (grey) or 3 (R, G, B in that order)",
                self.dir.display(),
                self.channels.join(", ")
            ))),
        }
    }
}

/// The configuration fit.json records (`model`, an `Own` family's record, a table family's
/// `terms`), read loosely: what it lacks (a file older than the record) is the family's
/// default, so the `S` matched is the fitted one.
fn fit_setup(fit: &Value, family: ModelFamily) -> Result<ModelSetup> {
    let read = |key: &str| fit.get(key).cloned();
    let config = read("model")
        .and_then(|m| serde_json::from_value::<ModelConfig>(m).ok())
        .unwrap_or_default();
    let record =
        read(FAMILY_RECORD_KEY).and_then(|r| serde_json::from_value::<FamilyRecord>(r).ok());
    let terms = read("terms").and_then(|t| serde_json::from_value::<Vec<String>>(t).ok());
    ModelSetup::from_records(family, config, record.as_ref(), terms.as_deref())
}

/// fit.json's parameters that were not free or not determined, with why:
/// `alpha_deg = -2 (fixed by --fix)`, `eta = 1.55 (not varied: default)`,
/// `beta_n = 0.3 (not varied: the terms in play do not depend on it)`, `sigma_a[0] = 50 (at a bound)`.
fn held_parameters(fit: &Value) -> Vec<String> {
    let Some(entries) = fit.get("parameters").and_then(Value::as_array) else {
        return Vec::new();
    };
    let fixed_by_user = fit.pointer("/options/fixed").and_then(Value::as_object);
    let not_in_play: Vec<&str> = fit
        .get("warnings")
        .and_then(Value::as_array)
        .map(|w| {
            w.iter()
                .filter_map(Value::as_str)
                // "... do not depend on it" (Chiang), "... do not read it" (table families).
                .filter(|t| t.contains("not fitted (the terms in play do not"))
                .filter_map(|t| t.split(':').next())
                .collect()
        })
        .unwrap_or_default();
    entries
        .iter()
        .filter_map(|e| {
            let name = e.get("name")?.as_str()?;
            let value = e
                .get("value")
                .and_then(Value::as_f64)
                .map_or("null".to_string(), |v| format!("{v}"));
            let why = match e.get("status")?.as_str()? {
                "free" => return None,
                "fixed" if fixed_by_user.is_some_and(|m| m.contains_key(name)) => "fixed by --fix",
                "fixed" if not_in_play.contains(&name) => {
                    "not varied: the terms in play do not depend on it"
                }
                "fixed" => "not varied by default",
                "at_bound" => "at a bound of the fit's range",
                "undetermined" => "not determined by the data",
                _ => return None,
            };
            Some(format!("{name} = {value} ({why})"))
        })
        .collect()
}

/// `status converged, rms 0.0201, reduced chi2 1.02 (log space, dof 2332)` from fit.json.
fn quality_line(fit: &Value) -> String {
    let num = |p: &str| fit.pointer(p).and_then(Value::as_f64);
    let text = |p: &str| fit.pointer(p).and_then(Value::as_str);
    let mut parts = vec![format!(
        "status {}",
        text("/status").unwrap_or("unrecorded")
    )];
    if let Some(verdict) = text("/verdict") {
        parts.push(format!("verdict {verdict}"));
    }
    if let Some(rms) = num("/residuals/rms") {
        parts.push(format!("residual rms {rms:.4}"));
    }
    if let Some(chi2) = num("/residuals/reduced_chi2") {
        parts.push(format!("reduced chi2 {chi2:.3}"));
    }
    if let Some(space) = text("/residuals/space") {
        parts.push(format!("{space} space"));
    }
    parts.join(", ")
}

/// Whether the fit in `dir` is one to hand a renderer: a `failed` fit's parameters are not a
/// fit (often the start point), so exporting one is an error unless `allow_failed`, and then a
/// warning; an `interrupted` fit's are the best so far, said in a warning. Returns the warnings.
pub fn exportable(dir: &Path, allow_failed: bool) -> Result<Vec<String>> {
    let fit_path = dir.join("fit.json");
    let fit: Value = crate::files::read_json(
        &fit_path,
        "fit.json is written by `hairfit fit` — re-run the fit to regenerate it",
    )?;
    let reasons = fit
        .get("reasons")
        .and_then(Value::as_array)
        .and_then(|r| r.first())
        .and_then(Value::as_str)
        .map_or(String::new(), |r| format!(" ({r})"));
    match fit.get("verdict").and_then(Value::as_str) {
        Some("failed") if !allow_failed => Err(Error::Other(format!(
            "{}: the fit's verdict is failed{reasons}: its parameters are not a fit, so a renderer would get numbers no data chose; fix the fit and re-run it, or pass --allow-failed to export them all the same",
            fit_path.display()
        ))),
        Some("failed") => Ok(vec![format!(
            "{}: the fit's verdict is failed{reasons}; exported because of --allow-failed: these parameters are not a fit",
            fit_path.display()
        )]),
        Some("interrupted") => Ok(vec![format!(
            "{}: the fit was interrupted: these are its best parameters so far, not a converged fit; re-run the fit to finish it",
            fit_path.display()
        )]),
        _ => Ok(Vec::new()),
    }
}
