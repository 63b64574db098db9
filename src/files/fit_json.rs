//! `fit.json`: what a fit found and how ([`FitJson`]). Field names and order are the file's
//! contract; the fit writes and the report reads this one type. (About 430 lines of types plus
//! the tests that pin the file's spellings and key order: over 500 with them, kept together so
//! a change to a field meets its test.)

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::load_report::LoadReport;
use super::nan_if_missing_vec;
use super::settings::{Global, Loss, Space};
use crate::error::Result;
use crate::families::effects::{ModelConfig, RootMode};
use crate::families::{FamilyParams, FamilyRecord};
use crate::geometry::Measurement;

/// fit.json's key of [`FitJson::family_record`], the name the first family with a record gave it
/// (the `serde(rename)` there says the same; readers of the file as JSON use this).
pub const FAMILY_RECORD_KEY: &str = "chiang";

/// How a fit (or one solver run) ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FitStatus {
    Converged,
    Interrupted,
    MaxIterations,
    Failed,
}

impl FitStatus {
    /// The JSON spelling.
    pub fn as_str(&self) -> &'static str {
        match self {
            FitStatus::Converged => "converged",
            FitStatus::Interrupted => "interrupted",
            FitStatus::MaxIterations => "max_iterations",
            FitStatus::Failed => "failed",
        }
    }
}

impl std::fmt::Display for FitStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// What the fit did with one parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ParamStatus {
    Free,
    Fixed,
    AtBound,
    Undetermined,
}

impl ParamStatus {
    /// The JSON spelling.
    pub fn as_str(&self) -> &'static str {
        match self {
            ParamStatus::Free => "free",
            ParamStatus::Fixed => "fixed",
            ParamStatus::AtBound => "at_bound",
            ParamStatus::Undetermined => "undetermined",
        }
    }
}

impl std::fmt::Display for ParamStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// `fit.json` → `verdict`: what a fit's result is good for. Exit codes follow it (0 for
/// `good`, `poor_fit`, `undetermined`; 1 for `failed`; 128 + the signal for `interrupted`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The model describes the data within their noise and every free parameter is determined.
    Good,
    /// The residuals show the model does not describe the data (χ² test with a σ column, else
    /// structure along scans or lack of fit against replicates).
    PoorFit,
    /// The fit describes the data but some parameter is not determined by them.
    #[default]
    Undetermined,
    /// The numbers are not a fit (no progress, non-finite values, overflowing weights).
    Failed,
    /// Stopped by a signal: the best point so far.
    Interrupted,
}

impl Verdict {
    /// The JSON spelling.
    pub fn as_str(&self) -> &'static str {
        match self {
            Verdict::Good => "good",
            Verdict::PoorFit => "poor_fit",
            Verdict::Undetermined => "undetermined",
            Verdict::Failed => "failed",
            Verdict::Interrupted => "interrupted",
        }
    }
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// `fit.json` → `suggestions[]`: one thing to try and why this fit points to it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Suggestion {
    /// What to change, as options of `hairfit fit` where possible (e.g. `--loss cauchy`).
    pub action: String,
    /// The evidence from this fit, with its numbers.
    pub evidence: String,
}

/// `fit.json` → `goodness_of_fit.thresholds`: the limits the verdict applied (see
/// `src/fit/verdict.rs` for why each is what it is).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct GofThresholds {
    /// A test's p-value below this rejects the model.
    pub p_value: f64,
    /// With σ: reduced χ² must also exceed this (a misfit worth acting on).
    pub reduced_chi2: f64,
    /// Without σ: lag-1 autocorrelation must also exceed this.
    pub lag1: f64,
    /// Without σ: observed/expected runs must also be below this.
    pub runs_ratio: f64,
    /// Without σ: the lack-of-fit F must also exceed this.
    pub lack_of_fit_f: f64,
    /// With a robust loss and σ: residuals beyond this many σ are left out of the χ² test.
    pub robust_exclusion_sigma: f64,
}

/// `fit.json` → `goodness_of_fit`: the statistics of the residuals (normalised, in the fit's
/// space) that decide between `good` and `poor_fit`. `null` where a test does not apply.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct GoodnessOfFit {
    /// The data carry a σ column: the χ² test decides.
    pub sigma_given: bool,
    /// Σ r² over the residuals the test uses, its degrees of freedom and upper-tail p-value.
    pub chi2: Option<f64>,
    pub chi2_dof: usize,
    pub chi2_p_value: Option<f64>,
    /// Residuals left out of the χ² test (a robust loss discounts them; see thresholds).
    pub chi2_excluded: usize,
    /// The factor already in every linearised standard error: √(Σr̃²/dof), the residual
    /// scale (with σ: √(reduced χ²), the PDG scale factor of a poor fit).
    pub se_scale_factor: Option<f64>,
    /// Noise level the residuals show, robustly: 1.4826 × median |r| (normalised units).
    pub robust_noise: Option<f64>,
    /// Residuals beyond 5 × `robust_noise`, and their share of Σ r².
    pub large_residuals: usize,
    pub large_residual_share: Option<f64>,
    /// Scan slices (fixed incidence and one outgoing angle, ≥ 3 points) the structure tests use.
    pub slices: usize,
    /// Wald–Wolfowitz runs test of residual signs along the slices.
    pub runs: Option<super::statistics::RunsTest>,
    /// Lag-1 autocorrelation of residuals along the slices.
    pub lag1: Option<super::statistics::Autocorrelation>,
    /// Directions (per channel) measured more than once, and the lack-of-fit F test on them.
    pub replicate_groups: usize,
    pub lack_of_fit: Option<super::statistics::LackOfFit>,
    pub thresholds: GofThresholds,
}

/// `fit.json` → `data`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DataInfo {
    pub file: String,
    pub channels: Vec<String>,
    pub n_samples: usize,
    /// What the loader did with every row of the file.
    #[serde(default)]
    pub load_report: LoadReport,
}

/// `fit.json` → `parameters[]`: one model parameter (its JSON name, e.g. `alpha_r_deg`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterEntry {
    pub name: String,
    /// `null` when not finite.
    pub value: Option<f64>,
    /// `null` when fixed or undetermined.
    pub std_error: Option<f64>,
    pub status: ParamStatus,
    /// Profile-likelihood interval where Δχ² = 1 (68%); `null` when not profiled
    /// (`options.intervals` = `linear`, or fixed).
    #[serde(default)]
    pub interval_68: Option<Interval>,
    /// Profile-likelihood interval where Δχ² = 3.84 (95%).
    #[serde(default)]
    pub interval_95: Option<Interval>,
    /// The profile's points `[value, Δχ²]` in reporting units, ascending in value (the report
    /// draws them without refitting); empty when not profiled.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub profile: Vec<[f64; 2]>,
    /// How each side's ends (`[below, above]`) were found; absent when not profiled.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profile_method: Option<[ProfileMethod; 2]>,
}

/// How one side of a profile found its Δχ² = 1 and 3.84 ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProfileMethod {
    /// The local shape held: the re-fit at the linearised standard error landed on Δχ² ≈ 1
    /// and the re-fit aimed at the 95% crossing (the quadratic's, or a skewed profile's cubic)
    /// on 3.84, both accepted as they stand.
    Quadratic,
    /// The local quadratic held tightly: the re-fit at the linearised standard error landed on
    /// √Δχ² within 2.5e-3 of 1, so the 95% end is the quadratic's (no re-fit there; its error is
    /// under the 1% in √Δχ² a re-fitted crossing is accepted at).
    Extrapolated,
    /// The quadratic did not hold (or the side is open): the crossings were bracketed and
    /// refined by further re-fits.
    Refits,
}

/// A profile-likelihood interval in reporting units: `null` on a side where the profile stays
/// below the Δχ² threshold up to the parameter's fit bound (or the search limit), an open side.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    pub lower: Option<f64>,
    pub upper: Option<f64>,
}

/// `fit.json` → `residuals.down_weighted`: values the robust loss really discounted (weight
/// below [`crate::files::DOWN_WEIGHT`]).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct DownWeighted {
    /// The weight below which a value counts as discounted.
    pub threshold: f64,
    pub count: usize,
    /// Source lines of the discounted values (the first [`DownWeighted::MAX_LINES`]).
    pub lines: Vec<u64>,
}

impl DownWeighted {
    /// At most this many lines are listed (curves.csv has every weight).
    pub const MAX_LINES: usize = 200;
}

/// One channel's scale factor: `fit.json` → `scale[]` (fitted, with its standard error) and
/// `truth.json` → `scale[]` (exact, `std_error` null).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScaleEntry {
    pub channel: String,
    /// `null` when not finite.
    pub value: Option<f64>,
    /// `null` when unknown (exact, or not determined by the data).
    #[serde(default)]
    pub std_error: Option<f64>,
    /// Log-space fits: the scale a linear noise model (weights 1/σ, or relative weights without
    /// σ) puts at the same shape, for comparison only; `value` is the minimiser of the cost the
    /// fit minimised. Absent for linear-space fits and in truth files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub linear_noise_value: Option<f64>,
}

/// `fit.json` → `correlation`: `matrix[i][j]` between `names[i]` and `names[j]` (`null` where
/// undefined, e.g. an undetermined direction). With more than [`Correlation::FULL_MAX`] free
/// parameters (many channels) `names` holds the shared parameters only and `per_channel` each
/// per-channel parameter's correlations with them: the full matrix grows as channels².
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Correlation {
    pub names: Vec<String>,
    pub matrix: Vec<Vec<Option<f64>>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub per_channel: Vec<ChannelCorrelation>,
}

impl Correlation {
    /// Most free parameters whose full correlation matrix is written.
    pub const FULL_MAX: usize = 64;
}

/// `fit.json` → `correlation.per_channel[]`: one per-channel parameter's correlations with the
/// parameters in `correlation.names`, in that order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelCorrelation {
    pub name: String,
    pub with_shared: Vec<Option<f64>>,
}

/// `fit.json` → `residuals.per_channel[]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelResiduals {
    pub channel: String,
    pub rms: Option<f64>,
    pub reduced_chi2: Option<f64>,
}

/// `fit.json` → `residuals`: goodness of fit in the fit's space (`log` or `linear`) and loss.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResidualSummary {
    pub space: String,
    pub loss: String,
    pub rms: Option<f64>,
    pub reduced_chi2: Option<f64>,
    pub dof: usize,
    #[serde(default)]
    pub per_channel: Vec<ChannelResiduals>,
    /// Robust losses only: how many values the loss discounted, and which.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub down_weighted: Option<DownWeighted>,
}

/// `fit.json` → `trace[]`: one solver stage and its cost per iteration (its wall time is in
/// `timing.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceStage {
    pub stage: String,
    pub iterations: u64,
    /// Final cost of the stage (`null` when not finite).
    pub cost: Option<f64>,
    /// Cost per iteration of the run that won this stage (`null` entries read as NaN and are
    /// not drawn).
    #[serde(default, deserialize_with = "nan_if_missing_vec")]
    pub history: Vec<f64>,
}

/// `fit.json` → `options.log_floored`: values a log-space fit cannot take the logarithm of.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Floored {
    /// Per channel: how many values (`y ≤ 0`, or `y < 2σ`) are fitted as linear residuals.
    pub count: Vec<usize>,
    /// Per channel: the noise unit of those residuals when σ is unknown (half the smallest
    /// positive value: a reading at or below zero is below the detector's noise).
    #[serde(deserialize_with = "nan_if_missing_vec")]
    pub floor: Vec<f64>,
}

/// `fit.json` → `options.effects_choice`: how the lobes/effects were chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EffectsSource {
    /// From the data's geometry (`--effects auto`).
    #[default]
    Auto,
    /// Every lobe and effect (`--effects all`).
    All,
    /// As given (`--lobes/--no-glints/--no-eccentricity`, or the Chiang terms).
    Explicit,
}

impl std::fmt::Display for EffectsSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            EffectsSource::Auto => "auto",
            EffectsSource::All => "all",
            EffectsSource::Explicit => "explicit",
        })
    }
}

/// `fit.json` → `options.scale`: how the per-channel scales were fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum ScaleMethod {
    /// Solved in closed form at every step (least squares).
    #[default]
    #[serde(rename = "variable projection")]
    VariableProjection,
    /// Fitted as parameters beside the model's (robust losses have no closed form).
    #[serde(rename = "explicit (robust loss)")]
    Explicit,
}

/// `fit.json` → `options`: every setting the fit used. Fields are in alphabetical order, the
/// order the file has always had (it was a sorted JSON map). Enumerated settings are typed and
/// keep the spellings the file has always had (`fit::Space`, `fit::Loss`, `fit::Global` are the
/// fit's own option types).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct OptionsRecord {
    /// How much of the curves `curves.csv` holds (`--curves`; absent in older files: full).
    pub curves: super::curves::CurvesMode,
    /// Why `--curves auto` chose the summary (empty when the mode was given or is full).
    #[serde(skip_serializing_if = "String::is_empty")]
    pub curves_reason: String,
    /// `auto`, `all` or `explicit`: how the effects were chosen.
    pub effects_choice: EffectsSource,
    /// Why each lobe/effect is on or off.
    pub effects_reasons: Vec<String>,
    /// `--fix`: JSON name → value in reporting units (degrees for `*_deg`).
    pub fixed: BTreeMap<String, f64>,
    pub free_parameters: Vec<String>,
    /// Parameters freed that are fixed by default (`--free eta`).
    pub freed: Vec<String>,
    pub global: Global,
    /// How the parameter intervals were computed: `profile` or `linear` (`--intervals`).
    pub intervals: String,
    /// Why (`--intervals auto` records its estimate of the profiling cost).
    pub intervals_reason: String,
    /// The loader's settings (`hairfit fit` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load: Option<String>,
    pub log_floored: Floored,
    pub loss: Loss,
    /// The robust-loss scale used (normalised residual units).
    pub loss_scale: f64,
    /// True when `loss_scale` was estimated from the residuals (`--loss-scale auto`).
    pub loss_scale_auto: bool,
    /// What the data's values are: `s` (scale·S) or `radiance` (scale·S·cos θ_i).
    pub measurement: Measurement,
    pub mode: RootMode,
    pub polish: usize,
    pub polish_iters: u64,
    /// `variable projection` or `explicit (robust loss)`.
    pub scale: ScaleMethod,
    pub seed: u64,
    pub space: Space,
    pub start_iters: u64,
    pub starts: usize,
    /// Starts the multi-start ran (it stops early once a batch of them agree); absent in files
    /// written before it could.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub starts_run: Option<usize>,
    /// Samples the multi-start used.
    pub subsample: usize,
}

/// The whole of `fit.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitJson {
    pub hairfit_version: String,
    pub status: FitStatus,
    pub data: DataInfo,
    /// The forward model's configuration the fit used (the report evaluates the same). A
    /// Chiang fit records its lobes here (glints and eccentricity off) and its own
    /// configuration in `chiang`.
    pub model: ModelConfig,
    pub options: OptionsRecord,
    /// The fitted parameters, exactly a parameter file of the fit's family (a Chiang file
    /// carries `"model": "chiang"`).
    pub params: FamilyParams,
    pub parameters: Vec<ParameterEntry>,
    pub scale: Vec<ScaleEntry>,
    #[serde(default)]
    pub correlation: Correlation,
    #[serde(default)]
    pub warnings: Vec<String>,
    pub residuals: ResidualSummary,
    #[serde(default)]
    pub trace: Vec<TraceStage>,
    /// What the result is good for (`src/fit/verdict.rs` decides; precedence interrupted >
    /// failed > poor_fit > undetermined > good). Files written before verdicts read as
    /// `undetermined`: nobody judged them.
    #[serde(default)]
    pub verdict: Verdict,
    /// Why: sentences carrying their numbers, the deciding ones first.
    #[serde(default)]
    pub reasons: Vec<String>,
    /// Every goodness-of-fit statistic computed for the verdict.
    #[serde(default)]
    pub goodness_of_fit: GoodnessOfFit,
    /// What to try, each with the evidence from this fit that suggests it.
    #[serde(default)]
    pub suggestions: Vec<Suggestion>,
    /// What the fit's family records of its configuration beside `model`, when it records
    /// anything ([`crate::families::OwnTypes::Record`]), under [`FAMILY_RECORD_KEY`].
    #[serde(rename = "chiang", default, skip_serializing_if = "Option::is_none")]
    pub family_record: Option<FamilyRecord>,
    /// A table family's terms that were on (`--terms`); absent for an `Own` family.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub terms: Option<Vec<String>>,
}

impl FitJson {
    /// The model family the fit used.
    pub fn family(&self) -> crate::families::ModelFamily {
        self.params.family()
    }

    /// What fit.json records of the fit's model configuration (`model`, `chiang`, `terms`).
    pub fn records(&self) -> crate::families::ModelRecords {
        crate::families::ModelRecords {
            config: self.model,
            family_record: self.family_record.clone(),
            terms: self.terms.clone(),
        }
    }

    /// The model configuration the fit used, as its records say.
    pub fn setup(&self) -> Result<crate::families::ModelSetup> {
        crate::families::ModelSetup::from_records(
            self.family(),
            self.model,
            self.family_record.as_ref(),
            self.terms.as_deref(),
        )
    }

    /// Read `fit.json`; a syntax or schema error names line and column.
    pub fn load(path: &Path) -> Result<FitJson> {
        super::read_json(
            path,
            "fit.json is written by `hairfit fit` — re-run the fit to regenerate it",
        )
    }

    /// Write `fit.json` atomically (pretty-printed).
    pub fn save(&self, path: &Path) -> Result<()> {
        super::write_json(path, self)
    }

    /// The fitted scale of `channel`, when finite and positive.
    pub fn scale_of(&self, channel: &str) -> Option<f64> {
        self.scale
            .iter()
            .find(|s| s.channel == channel)
            .and_then(|s| s.value)
            .filter(|s| s.is_finite() && *s > 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `options` keeps the sorted key order fit.json has always had.
    #[test]
    fn options_fields_are_in_alphabetical_order() {
        let record = OptionsRecord {
            load: Some("x".into()),
            ..OptionsRecord::default()
        };
        let text = serde_json::to_string(&record).unwrap();
        let value: serde_json::Map<String, serde_json::Value> =
            serde_json::from_str(&text).unwrap();
        let mut at: Vec<(usize, &String)> = value
            .keys()
            .map(|k| (text.find(&format!("\"{k}\":")).unwrap(), k))
            .collect();
        at.sort();
        let written: Vec<&String> = at.into_iter().map(|(_, k)| k).collect();
        let mut sorted = written.clone();
        sorted.sort();
        assert_eq!(written, sorted);
        assert_eq!(written.len(), 24);
    }

    /// Every fit.json shipped under `fits/` reads into the typed options and writes them back
    /// with the file's own spellings (the typed enums changed no value on disk).
    #[test]
    fn shipped_fit_json_options_read_back_and_keep_their_spelling() {
        let fits = Path::new(env!("CARGO_MANIFEST_DIR")).join("fits");
        let mut read = 0;
        for entry in std::fs::read_dir(&fits).unwrap() {
            let path = entry.unwrap().path().join("fit.json");
            if !path.is_file() {
                continue;
            }
            let fit = FitJson::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let text = std::fs::read_to_string(&path).unwrap();
            let on_disk: serde_json::Value = serde_json::from_str(&text).unwrap();
            let written = serde_json::to_value(&fit.options).unwrap();
            for key in ["effects_choice", "global", "loss", "scale", "space", "mode"] {
                assert_eq!(
                    written[key],
                    on_disk["options"][key],
                    "{}: options.{key}",
                    path.display()
                );
            }
            read += 1;
        }
        assert!(read > 0, "no fit.json under {}", fits.display());
    }

    /// Unknown spellings are errors naming the field, not silently defaulted.
    #[test]
    fn an_unknown_option_spelling_is_an_error() {
        let err = serde_json::from_str::<OptionsRecord>(r#"{"loss": "tukey"}"#).unwrap_err();
        assert!(err.to_string().contains("tukey"), "{err}");
        let ok: OptionsRecord =
            serde_json::from_str(r#"{"loss": "soft-l1", "space": "linear", "global": "nelder-mead", "scale": "explicit (robust loss)", "effects_choice": "all"}"#)
                .unwrap();
        assert_eq!(
            (ok.loss, ok.space, ok.global, ok.scale, ok.effects_choice),
            (
                Loss::SoftL1,
                Space::Linear,
                Global::NelderMead,
                ScaleMethod::Explicit,
                EffectsSource::All
            )
        );
    }

    /// A fit.json written before the load report was typed (the demo's five fields) still reads.
    #[test]
    fn a_partial_load_report_reads_with_empty_defaults() {
        let r: LoadReport = serde_json::from_str(
            r#"{"accepted": 3, "file": "d.csv", "format": "synthetic", "notes": [], "rows_read": 3}"#,
        )
        .unwrap();
        assert_eq!((r.rows_read, r.accepted, r.rejected_total()), (3, 3, 0));
    }
}
