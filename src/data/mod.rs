//! Loading measured or synthetic samples: owns the [`Dataset`] (struct of arrays, angles in
//! radians) that the fit and the synthesizer use, the three file formats (header CSV, headerless
//! fixed-angle goniometer scans, JSON), and the [`LoadReport`] that accounts for every row.
//!
//! A malformed file is an [`Error::Input`] naming file, line and column; a well-formed row with
//! a bad value is a rejection counted in the report, never silently dropped.

mod csv;
mod csv_rows;

/// The four angle columns every dataset has, in this order.
pub const ANGLE_COLUMNS: [&str; 4] = ["theta_i", "phi_i", "theta_r", "phi_r"];

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
mod expr;
mod json;
pub(crate) mod lines;
pub(crate) mod records;
mod report;
mod rows;
mod scan;
pub(crate) mod unit;

pub(crate) use self::csv::{repeated_column, repeated_column_message};

use std::path::Path;

use crate::error::{Error, Result};

pub use self::csv::write_csv;
pub use self::expr::Linear;
pub use self::json::write_json;
pub use self::report::{LineTally, LoadReport, RejectReason, FIRST_LINES};

/// Samples in struct-of-arrays form; memory is proportional to the accepted samples.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Dataset {
    /// Channel names, e.g. `["radiance"]` or `["r", "g", "b"]` (from `radiance_<name>`).
    pub channels: Vec<String>,
    /// Incident inclination, radians.
    pub theta_i: Vec<f64>,
    /// Incident azimuth, radians.
    pub phi_i: Vec<f64>,
    /// Outgoing inclination, radians.
    pub theta_r: Vec<f64>,
    /// Outgoing azimuth, radians.
    pub phi_r: Vec<f64>,
    /// Row-major: `radiance[i * n_channels + c]`.
    pub radiance: Vec<f64>,
    /// Per sample per channel, same layout as `radiance` (an unsuffixed column is broadcast).
    pub sigma: Option<Vec<f64>>,
    /// Per sample per channel, same layout as `radiance`.
    pub weight: Option<Vec<f64>>,
    /// 1-based line in the source file of each accepted sample.
    pub source_line: Vec<u64>,
    /// Free-form metadata (from JSON datasets or the synthesizer).
    pub meta: serde_json::Map<String, serde_json::Value>,
}

impl Dataset {
    /// An empty dataset with these channels (and sigma/weight arrays when asked for).
    pub fn with_channels(channels: Vec<String>, sigma: bool, weight: bool) -> Self {
        Dataset {
            channels,
            sigma: sigma.then(Vec::new),
            weight: weight.then(Vec::new),
            ..Dataset::default()
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.theta_i.len()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.theta_i.is_empty()
    }

    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        self.channels.len()
    }

    /// Radiance of sample `i` in channel `c`.
    pub fn value(&self, i: usize, c: usize) -> f64 {
        self.radiance[i * self.n_channels() + c]
    }

    /// Sigma of sample `i` in channel `c`, if the dataset has sigmas.
    pub fn sigma_of(&self, i: usize, c: usize) -> Option<f64> {
        let n = self.n_channels();
        self.sigma.as_ref().map(|s| s[i * n + c])
    }

    /// Weight of sample `i` in channel `c`, if the dataset has weights.
    pub fn weight_of(&self, i: usize, c: usize) -> Option<f64> {
        let n = self.n_channels();
        self.weight.as_ref().map(|w| w[i * n + c])
    }

    /// The four angles of sample `i` in radians: `[θ_i, φ_i, θ_r, φ_r]`.
    pub fn angles(&self, i: usize) -> [f64; 4] {
        [
            self.theta_i[i],
            self.phi_i[i],
            self.theta_r[i],
            self.phi_r[i],
        ]
    }

    /// The four angles of sample `i` in degrees, `[θ_i, φ_i, θ_r, φ_r]`, as
    /// [`round_trip_degrees`] gives them (what the writers put in files).
    pub fn angles_deg(&self, i: usize) -> [f64; 4] {
        self.angles(i).map(round_trip_degrees)
    }

    /// Append one sample (angles in radians; `radiance`, `sigma`, `weight` one per channel).
    /// Panics if the slices do not match the dataset's channels (a programming error).
    pub fn push(
        &mut self,
        angles: [f64; 4],
        radiance: &[f64],
        sigma: Option<&[f64]>,
        weight: Option<&[f64]>,
        source_line: u64,
    ) {
        assert_eq!(radiance.len(), self.n_channels(), "radiance per channel");
        self.theta_i.push(angles[0]);
        self.phi_i.push(angles[1]);
        self.theta_r.push(angles[2]);
        self.phi_r.push(angles[3]);
        self.radiance.extend_from_slice(radiance);
        if let Some(s) = self.sigma.as_mut() {
            s.extend_from_slice(sigma.expect("dataset has sigma"));
        }
        if let Some(w) = self.weight.as_mut() {
            w.extend_from_slice(weight.expect("dataset has weight"));
        }
        self.source_line.push(source_line);
    }
}

/// Radians → degrees such that the loader's `f64::to_radians` gives back exactly `radians`,
/// choosing the shortest text among such degrees; when no degree value maps back exactly, the
/// one that maps back nearest (1 ulp off).
///
/// Why: `radians.to_degrees()` alone can come back 1 ulp off, so a file in degrees would not
/// reload bit-exactly even for angles that began as degrees. `to_radians` is monotone, so the
/// degrees that map back to `radians` are a run of at most two neighbouring f64s (measured over
/// 2·10⁷ random angles), and `to_degrees` lands within one ulp of them: searching ±3 ulp is
/// ample. Every `d.to_radians()` round-trips exactly (`d` itself is a candidate); about 9% of
/// arbitrary normal radian values have no exact preimage (`to_radians` scales by less than one
/// and skips them) and come back 1 ulp off. Non-finite values are `to_degrees` unchanged.
pub fn round_trip_degrees(radians: f64) -> f64 {
    let nearest = radians.to_degrees();
    if !nearest.is_finite() {
        return nearest;
    }
    // Candidates from the nearest outwards: 0, −1, +1, −2, +2, −3, +3 ulp.
    let mut candidates = [nearest; 7];
    let (mut down, mut up) = (nearest, nearest);
    for k in 1..=3 {
        down = next_f64(down, false);
        up = next_f64(up, true);
        candidates[2 * k - 1] = down;
        candidates[2 * k] = up;
    }
    let maps_back = |d: &f64| d.to_radians().to_bits() == radians.to_bits();
    let mut exact = candidates.iter().copied().filter(maps_back);
    match (exact.next(), exact.next()) {
        // Two exact candidates: the shorter text (the nearer when equally long).
        (Some(a), Some(b)) => {
            if format!("{b:?}").len() < format!("{a:?}").len() {
                b
            } else {
                a
            }
        }
        (Some(a), None) => a,
        // min_by keeps the first (nearest) of equal misses.
        _ => candidates
            .into_iter()
            .min_by(|a, b| {
                let miss = |d: f64| (d.to_radians() - radians).abs();
                miss(*a).total_cmp(&miss(*b))
            })
            .unwrap_or(nearest),
    }
}

/// The neighbouring f64 of a finite `x`, above or below (`f64::next_up`/`next_down`, which are
/// newer than the crate's minimum Rust version).
fn next_f64(x: f64, up: bool) -> f64 {
    if x == 0.0 {
        let tiny = f64::from_bits(1);
        return if up { tiny } else { -tiny };
    }
    // Bits order magnitudes: one more is one ulp further from zero.
    let bits = x.to_bits();
    f64::from_bits(if (x > 0.0) == up { bits + 1 } else { bits - 1 })
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
    fn delimiter_for(&self, path: &Path) -> Result<u8> {
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

/// The format of `path`: `--format`, else `--columns` means scan, else the extension.
pub fn detect_format(path: &Path, options: &LoadOptions) -> Format {
    if let Some(f) = options.format {
        return f;
    }
    if !options.columns.is_empty() {
        return Format::Scan;
    }
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("csv" | "tsv") => Format::Csv,
        Some("json") => Format::Json,
        _ => Format::Scan,
    }
}

/// Load samples from `path`, returning the accepted samples and a report on every row.
pub fn load(path: &Path, options: &LoadOptions) -> Result<(Dataset, LoadReport)> {
    // A missing file or a directory says so before any format-specific advice (a mistyped
    // `data.cvs` would otherwise be read as a scan and asked for --columns).
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(Error::Other(format!(
            "{}: is a directory, not a data file",
            path.display()
        )));
    }
    if !meta.is_file() {
        // Reading a pipe a second time would wait forever for a writer that is gone.
        return Err(Error::Other(format!(
            "{}: is a pipe or a device, not a file: a data file is read more than once (its \
             format, unit line and rows), so save the stream to a file first (e.g. \
             `… > data.csv`) and give that file",
            path.display()
        )));
    }
    let format = detect_format(path, options);
    check_options_fit_format(path, format, options)?;
    if let Some(t) = options.negative_tolerance {
        // NaN fails this too.
        if t.is_nan() || t < 0.0 {
            return Err(Error::Other(format!(
                "--negative-tolerance must be a number >= 0 (got {t})"
            )));
        }
    }
    let (dataset, mut report) = match format {
        Format::Csv => csv::load_csv(path, options)?,
        Format::Scan => scan::load_scan(path, options)?,
        Format::Json => json::load_json(path, options)?,
    };
    report.file = path.display().to_string();
    report.format = format.name().into();
    debug_assert_eq!(report.rows_read, report.accepted + report.rejected_total());
    Ok((dataset, report))
}

/// The channel names of the data at `path` as far as they can be known without reading its
/// rows: a CSV file's header or a scan's `--columns`. `None` for a JSON dataset (its
/// `"channels"` can only be found by parsing the whole file) and for a file or header that
/// cannot be read (loading it says why). For checks made before anything runs (`hairfit
/// batch`'s manifest): the header is one line, however large the file.
pub fn channels_without_loading(path: &Path, options: &LoadOptions) -> Option<Vec<String>> {
    if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
        return None;
    }
    match detect_format(path, options) {
        Format::Csv => csv::header_channels(path, options),
        Format::Scan => scan::column_channels(options),
        Format::Json => None,
    }
}

/// Scan-only options on another format are a mistake worth an error, not a silent no-op.
fn check_options_fit_format(path: &Path, format: Format, options: &LoadOptions) -> Result<()> {
    let scan_only = [
        ("--columns", !options.columns.is_empty()),
        ("--fixed", !options.fixed.is_empty()),
        ("--map", !options.maps.is_empty()),
    ];
    if format != Format::Csv && options.delimiter.is_some() {
        return Err(Error::Other(format!(
            "{}: --delimiter applies to CSV files with a header; this file is read as {}",
            path.display(),
            format.name()
        )));
    }
    if format != Format::Scan {
        if let Some((name, _)) = scan_only.iter().find(|(_, given)| *given) {
            return Err(Error::Other(format!(
                "{}: {name} applies to headerless scan files only; this file is read as {} \
                 (use --format scan to read it as a scan)",
                path.display(),
                format.name()
            )));
        }
    }
    if format == Format::Json && options.angles == Some(AngleUnit::Rad) {
        return Err(Error::Other(format!(
            "{}: JSON datasets are always in degrees; drop --angles rad",
            path.display()
        )));
    }
    Ok(())
}

/// Open `path` for buffered reading of text (see [`lines::TextGuard`]).
fn open(path: &Path) -> Result<std::io::BufReader<lines::TextGuard<std::fs::File>>> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    if file.metadata().is_ok_and(|m| m.is_dir()) {
        return Err(Error::Other(format!(
            "{}: is a directory, not a data file",
            path.display()
        )));
    }
    Ok(std::io::BufReader::with_capacity(
        1 << 16,
        lines::TextGuard::new(file),
    ))
}

/// `hairfit load`: load `path` and return the report as text (a summary, or JSON when `json`).
pub fn load_command(path: &Path, options: &LoadOptions, json: bool) -> Result<String> {
    let (_, report) = load(path, options)?;
    if json {
        let mut text = serde_json::to_string_pretty(&report)
            .map_err(|e| Error::Other(format!("cannot serialize the report: {e}")))?;
        text.push('\n');
        Ok(text)
    } else {
        Ok(report.to_string())
    }
}
