//! The load report (`hairfit load --json`, `fit.json` → `data.load_report`): what happened to
//! every row of a loaded file (accepted, or rejected with a reason), so that nothing is lost
//! silently. Invariant: `rows_read == accepted + Σ rejected`.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// How many first lines a report keeps per reason (enough to find the problem, bounded in size).
pub const FIRST_LINES: usize = 5;

/// Why a row was not accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RejectReason {
    /// A cell held the missing token (e.g. `?`) or was empty, or a JSON field was null/absent.
    MissingValue,
    /// NaN, an infinity, or a number too large for f64 (e.g. `1e999`).
    NonFinite,
    /// `|θ_i|` or `|θ_r|` ≥ 90°: the direction lies on (or past) the fiber axis.
    ThetaOutOfRange,
    /// `|φ_i|` or `|φ_r|` > 720° (4π): meaningless after wrapping (e.g. `1e20`, where one ulp
    /// spans many turns), most likely a unit or column mix-up.
    PhiOutOfRange,
    /// Radiance below `-negative_tolerance`.
    NegativeRadiance,
    /// A sigma ≤ 0 (a zero or negative uncertainty cannot weight a residual).
    NonPositiveSigma,
    /// A weight ≤ 0.
    NonPositiveWeight,
    /// The same line as an earlier accepted row: the same direction (φ compared after
    /// wrapping) and the same values. (Same direction, other values: a replicate, kept.)
    Duplicate,
}

impl RejectReason {
    /// Human wording used by the summary.
    pub fn describe(self) -> &'static str {
        match self {
            RejectReason::MissingValue => "missing value",
            RejectReason::NonFinite => "non-finite number",
            RejectReason::ThetaOutOfRange => "|theta| >= 90 deg",
            RejectReason::PhiOutOfRange => "|phi| > 720 deg",
            RejectReason::NegativeRadiance => "negative radiance beyond tolerance",
            RejectReason::NonPositiveSigma => "sigma <= 0",
            RejectReason::NonPositiveWeight => "weight <= 0",
            RejectReason::Duplicate => "duplicate of an earlier row",
        }
    }
}

/// A count of rows and the first few (1-based) lines where they occurred.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct LineTally {
    pub count: u64,
    pub first_lines: Vec<u64>,
}

impl LineTally {
    /// Count one more row at `line`, keeping the first [`FIRST_LINES`] lines.
    pub fn add(&mut self, line: u64) {
        self.count += 1;
        if self.first_lines.len() < FIRST_LINES {
            self.first_lines.push(line);
        }
    }
}

/// What loading one file did with each of its rows (absent fields read as empty).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LoadReport {
    pub file: String,
    /// `csv`, `scan` or `json`.
    pub format: String,
    /// Data rows seen (comment and blank lines and the header are not rows).
    pub rows_read: u64,
    pub accepted: u64,
    pub rejected: BTreeMap<RejectReason, LineTally>,
    /// Accepted rows with a negative radiance in some channel (kept: dark-frame subtraction makes
    /// them real).
    pub negative_kept: LineTally,
    /// `[line, earlier line]` for the first duplicates: which earlier row each one repeats.
    pub duplicate_of: Vec<[u64; 2]>,
    pub notes: Vec<String>,
    /// Accepted rows that measure again the direction of an earlier row (φ compared after
    /// wrapping) with other values: repeated measurements, kept (they estimate the pure error).
    pub replicates: LineTally,
    /// Things that may make a fit of this file wrong (e.g. angles that look like radians read
    /// as degrees); `--strict` makes them errors.
    pub warnings: Vec<String>,
    /// The loader's settings when a command read the file (fit.json `options.load`); a fit of
    /// a loaded file also takes its warnings as its own. Not part of the report's JSON.
    #[serde(skip)]
    pub settings: Option<String>,
    /// Seconds the loading took (timing.json `load_s`).
    #[serde(skip)]
    pub seconds: Option<f64>,
}

impl LoadReport {
    /// Total rejected rows over all reasons.
    pub fn rejected_total(&self) -> u64 {
        self.rejected.values().map(|t| t.count).sum()
    }

    /// Rows rejected for `reason` (0 if none).
    pub fn rejected_count(&self, reason: RejectReason) -> u64 {
        self.rejected.get(&reason).map_or(0, |t| t.count)
    }

    /// Record a rejection of the row at `line`.
    pub fn reject(&mut self, reason: RejectReason, line: u64) {
        self.rejected.entry(reason).or_default().add(line);
    }
}
