//! compare.json ([`Comparison`]): the one type that writes and reads it, with its parts — each
//! family's fit ([`ModelSummary`]), the ranking ([`Ranked`]), the regions with every family's
//! RMS residual there ([`Region`], [`PerFamily`]).

use std::path::Path;

use serde::de::{MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::Result;
use crate::families::{FamilyParams, ModelFamily};
use crate::files::{ParameterEntry, ScaleEntry, Verdict};

/// What compare.json says about scales.
pub const SCALE_NOTE: &str = "scales are not comparable across models: the families \
normalise S differently, so each fit's per-channel scale absorbs a different factor; compare \
residuals, chi2 and AIC/BIC instead";

/// A difference in AIC below this is no preference (Burnham & Anderson: ΔAIC < 2 means
/// substantial support for both): such families are tied.
pub const AIC_TIE: f64 = 2.0;

/// A family misses the data in a region when its RMS residual there is at least this many
/// times another's (and the difference exceeds [`MIN_RMS_GAP`]).
pub const BIN_RATIO: f64 = 1.5;
/// Smallest RMS difference (normalised residual units) worth calling out.
pub const MIN_RMS_GAP: f64 = 0.05;

/// `-25` → `−25°` (a minus sign, not a hyphen), rounded to whole degrees.
pub fn degrees(x: f64) -> String {
    let x = x.round();
    if x < 0.0 {
        format!("−{}°", -x)
    } else {
        format!("{}°", x.abs())
    }
}

/// One value per family, in the order of compare.json's `models`; written as a JSON object
/// keyed by the family's `--model` name (`{"marschner": 1.02, "chiang": 3.4}`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PerFamily(pub Vec<(ModelFamily, f64)>);

impl PerFamily {
    /// The value of `family`, if it is listed.
    pub fn get(&self, family: ModelFamily) -> Option<f64> {
        self.0.iter().find(|(f, _)| *f == family).map(|&(_, v)| v)
    }
}

impl Serialize for PerFamily {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (family, value) in &self.0 {
            map.serialize_entry(family.as_str(), value)?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for PerFamily {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Entries;
        impl<'de> Visitor<'de> for Entries {
            type Value = PerFamily;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("an object of model family names to numbers")
            }
            fn visit_map<A: MapAccess<'de>>(
                self,
                mut map: A,
            ) -> std::result::Result<PerFamily, A::Error> {
                let mut out = Vec::new();
                while let Some(entry) = map.next_entry::<ModelFamily, f64>()? {
                    out.push(entry);
                }
                Ok(PerFamily(out))
            }
        }
        d.deserialize_map(Entries)
    }
}

/// One family's fit as compare.json reports it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelSummary {
    pub family: ModelFamily,
    /// The fit directory, relative to compare.json.
    pub dir: String,
    pub status: String,
    /// Σ r² of the normalised residuals in the fit space.
    pub chi2: f64,
    pub n_residuals: usize,
    /// Free shape parameters plus one scale per channel.
    pub n_params: usize,
    pub aic: f64,
    pub bic: f64,
    pub reduced_chi2: Option<f64>,
    pub rms: Option<f64>,
    /// The fit's verdict (fit.json's `verdict`); absent in files written before verdicts.
    #[serde(default)]
    pub verdict: Option<Verdict>,
    pub params: FamilyParams,
    pub parameters: Vec<ParameterEntry>,
    /// Not comparable across models (see `scale_note`).
    pub scale: Vec<ScaleEntry>,
}

impl ModelSummary {
    /// The verdict's JSON spelling, `unknown` when there is none.
    pub fn verdict_str(&self) -> &'static str {
        self.verdict.map_or("unknown", |v| v.as_str())
    }

    /// Whether the fit takes part in the ranking: a fit whose verdict is `failed` or
    /// `interrupted`, or whose AIC is not finite, is not a fit to rank.
    pub fn rankable(&self) -> bool {
        !matches!(self.verdict, Some(Verdict::Failed | Verdict::Interrupted))
            && self.aic.is_finite()
            && self.bic.is_finite()
    }
}

/// One place in the ranking (lowest AIC first).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Ranked {
    pub family: ModelFamily,
    /// 1 for the best and every family tied with it; otherwise the position by AIC.
    pub rank: usize,
    pub aic: f64,
    pub bic: f64,
    /// AIC − AIC of the best (≥ 0).
    pub delta_aic: f64,
    /// BIC − BIC of the best by AIC (may be negative when BIC prefers this family).
    pub delta_bic: f64,
    /// χ² / χ² of the best (absent when the best's χ² is 0).
    pub chi2_ratio: Option<f64>,
    /// ΔAIC < [`AIC_TIE`]: no preference between this family and the best.
    pub tied_with_best: bool,
}

/// A region of the data and every family's RMS normalised residual over it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Region {
    /// `lobe` (where one lobe of S dominates: R, TT, TRT), `abs_phi` or `theta_h` (a 10° bin).
    pub axis: String,
    /// `R`, `TT`, `TRT`, or the bin (`|φ| 170° to 180°`, `θh −10° to 0°`).
    pub name: String,
    /// Which residuals the region holds, in words and bounds.
    pub definition: String,
    /// A bin's centre and half-width, degrees (absent for lobe regions).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub half_width_deg: Option<f64>,
    /// Residuals (samples × channels) in the region.
    pub n: usize,
    /// RMS normalised residual of each family's fit over those residuals (empty when the
    /// region holds fewer than 3).
    pub rms: PerFamily,
}

impl Region {
    /// `family` misses the data here compared with `other`: its RMS is at least [`BIN_RATIO`]
    /// times `other`'s and larger by [`MIN_RMS_GAP`] or more.
    pub fn misses(&self, family: ModelFamily, other: ModelFamily) -> bool {
        match (self.rms.get(family), self.rms.get(other)) {
            (Some(a), Some(b)) => a - b >= MIN_RMS_GAP && a >= BIN_RATIO * b,
            _ => false,
        }
    }

    /// How findings name the region.
    pub fn place(&self) -> String {
        match (self.axis.as_str(), self.centre_deg) {
            ("abs_phi", Some(c)) => format!("|φ| ≈ {}", degrees(c)),
            ("theta_h", Some(c)) => format!("θh ≈ {}", degrees(c)),
            // The definition's bounds, without the words after them.
            _ => format!(
                "the {} region ({})",
                self.name,
                self.definition.split(':').next().unwrap_or_default()
            ),
        }
    }
}

/// The whole of compare.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    pub hairfit_version: String,
    pub data: String,
    pub n_samples: usize,
    pub channels: Vec<String>,
    /// `chi2 + 2k` (σ known: χ² is a log-likelihood) or `n ln(chi2/n) + 2k` (σ unknown).
    pub criterion: String,
    /// One summary per family, in the order `--models` listed them.
    pub models: Vec<ModelSummary>,
    /// The families by AIC, lowest first; a fit that failed has no place (empty when no fit
    /// succeeded).
    pub ranking: Vec<Ranked>,
    /// The lobe regions (R, TT, TRT; always, with an empty `rms` when they hold fewer than 3
    /// residuals), then the 10° bins of |φ| and of θh that hold at least 3.
    pub regions: Vec<Region>,
    /// Sentences: who fits best, and what each other family loses against it and where.
    pub findings: Vec<String>,
    pub scale_note: String,
}

impl Comparison {
    /// The family with the lowest AIC, if any fit succeeded.
    pub fn best(&self) -> Option<ModelFamily> {
        self.ranking.first().map(|r| r.family)
    }

    /// The ranking entry of `family`.
    pub fn rank_of(&self, family: ModelFamily) -> Option<&Ranked> {
        self.ranking.iter().find(|r| r.family == family)
    }

    /// The summary of `family`.
    pub fn model(&self, family: ModelFamily) -> Option<&ModelSummary> {
        self.models.iter().find(|m| m.family == family)
    }

    /// Write compare.json atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        crate::files::write_json(path, self)
    }

    /// Read compare.json.
    pub fn load(path: &Path) -> Result<Comparison> {
        crate::files::read_json(path, "compare.json is written by `hairfit compare`")
    }
}
