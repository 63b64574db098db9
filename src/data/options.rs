//! What [`super::load`] is told: the file formats, the angle unit, the loader's options
//! (flattened into every command that reads data) and what each column of a file holds.

use std::path::Path;

use crate::error::{Error, Result};

/// What one column of a CSV or scan file holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Role {
    /// Angle k of [`ANGLE_COLUMNS`].
    Angle(usize),
    /// Radiance of channel k.
    Radiance(usize),
    /// Sigma of channel k, or of every channel (`None`, broadcast).
    Sigma(Option<usize>),
    /// Weight of channel k, or of every channel (`None`, broadcast).
    Weight(Option<usize>),
    /// Not used.
    Ignored,
}
/// The file formats [`load`] reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// CSV with a header row (`theta_i,phi_i,theta_r,phi_r,radiance...`).
    Csv,
    /// Headerless goniometer scan; columns given by `--columns`, fixed angles by `--fixed`.
    Scan,
    /// JSON dataset as written by hairfit.
    Json,
}

impl Format {
    /// Lower-case name used in reports.
    pub fn name(self) -> &'static str {
        match self {
            Format::Csv => "csv",
            Format::Scan => "scan",
            Format::Json => "json",
        }
    }
}

/// Unit of the angles in CSV and scan files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum AngleUnit {
    Deg,
    Rad,
}

impl AngleUnit {
    /// The exclusive bound on |θ|: 90° (π/2), the fiber axis.
    pub fn theta_limit(self) -> f64 {
        match self {
            AngleUnit::Deg => 90.0,
            AngleUnit::Rad => std::f64::consts::FRAC_PI_2,
        }
    }

    /// The inclusive bound on |φ|: two turns either way (720°, 4π) covers every convention
    /// (−180..180, 0..360, unwrapped sweeps); beyond it a value is meaningless after wrapping
    /// (at `1e20` one ulp is many turns).
    pub fn phi_limit(self) -> f64 {
        match self {
            AngleUnit::Deg => 720.0,
            AngleUnit::Rad => 4.0 * std::f64::consts::PI,
        }
    }
}

/// Options for [`load`]; every command that reads data flattens these into its arguments.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct LoadOptions {
    /// Input format (default: from the extension: .csv, .json, anything else = scan).
    #[arg(long, value_enum)]
    pub format: Option<Format>,
    /// Unit of the angles in CSV/scan files [default: deg, or what a `# angles: rad` line says].
    #[arg(long, value_enum)]
    pub angles: Option<AngleUnit>,
    /// Scan columns in order, e.g. `phi_r,theta_r,radiance` (`_` or `skip` ignores a column).
    /// Implies --format scan unless --format is given.
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    pub columns: Vec<String>,
    /// Angles a scan holds fixed, e.g. `theta_i=30,phi_i=0` (in the --angles unit).
    #[arg(long, value_delimiter = ',', value_name = "NAME=VALUE")]
    pub fixed: Vec<String>,
    /// Map a scan column through a linear expression in x, e.g. `theta_r=90-x` (repeatable).
    #[arg(long = "map", value_name = "NAME=EXPR")]
    pub maps: Vec<String>,
    /// Token meaning "not measured" (empty cells are always missing).
    #[arg(long, default_value = "?", value_name = "TOKEN")]
    pub missing: String,
    /// Reject rows whose radiance is below -TOL in any channel [default: keep all negatives].
    #[arg(long, value_name = "TOL")]
    pub negative_tolerance: Option<f64>,
    /// Column separator of a CSV file with a header: one character, or `tab`
    /// [default: tab for .tsv files, else a comma].
    #[arg(long, value_name = "CHAR")]
    pub delimiter: Option<String>,
}

impl LoadOptions {
    /// The column separator of a header table at `path` (see `--delimiter`).
    pub(super) fn delimiter_for(&self, path: &Path) -> Result<u8> {
        match self.delimiter.as_deref() {
            None if has_extension(path, "tsv") => Ok(b'\t'),
            None => Ok(b','),
            Some(t) if t.eq_ignore_ascii_case("tab") || t == "\\t" || t == "\t" => Ok(b'\t'),
            Some(t) if t.len() == 1 && !matches!(t, "\"" | "#" | "\n" | "\r") => {
                Ok(t.as_bytes()[0])
            }
            Some(t) => Err(Error::Other(format!(
                "--delimiter `{t}`: give one ASCII character such as `;` or `|`, or `tab` \
                 (not a quote, `#` or a line break)"
            ))),
        }
    }
}

/// True when `path` ends in `.ext` (any case).
fn has_extension(path: &Path, ext: &str) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(ext))
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            format: None,
            angles: None,
            columns: Vec::new(),
            fixed: Vec::new(),
            maps: Vec::new(),
            missing: "?".into(),
            negative_tolerance: None,
            delimiter: None,
        }
    }
}
