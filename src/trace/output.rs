//! What `hairfit trace` writes: the dataset (hairfit's CSV, `S` with its `sigma`, per-order
//! columns after them) and the sidecar `FILE.trace.json` ([`TraceRecord`]), published together.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{FiberFile, TraceResult, ORDERS};
use crate::data::{round_trip_degrees, write_csv_with, Dataset};
use crate::error::Result;
use crate::synth::{channel_names, CSV_FIRST_DATA_LINE};

/// The per-order columns' prefixes, in order R, TT, TRT, higher.
pub const ORDER_NAMES: [&str; ORDERS] = ["r", "tt", "trt", "higher"];

/// How the CSV's values were estimated (recorded in the sidecar).
pub const ESTIMATOR: &str = "S = sum of the weight leaving within kernel_deg of the direction \
    / (rays * cap solid angle * cos theta_r); weight 1 per ray = the power the fibre \
    intercepts from the beam; sigma = standard deviation of the 32 batch estimates / sqrt(32), \
    at least one ray's worth";

/// Where one channel's incident power went, as fractions of it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelBalance {
    pub channel: String,
    /// Left the fibre, per order R, TT, TRT, higher.
    pub tallied: [f64; ORDERS],
    pub absorbed: f64,
    /// Still inside after `max_segments` (or below the weight cut-off).
    pub inside: f64,
    /// `1 − tallied − absorbed − inside`: rounding only.
    pub residual: f64,
}

/// The sidecar `FILE.trace.json`: everything that made a traced dataset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TraceRecord {
    pub hairfit_version: String,
    pub fiber: FiberFile,
    pub channels: Vec<String>,
    /// Canonical rig spec.
    pub rig: String,
    pub rays_per_incidence: u64,
    pub incidences: usize,
    pub batches: usize,
    pub seed: u64,
    pub rng: String,
    pub kernel_deg: f64,
    pub estimator: String,
    /// The values are `S` (hairfit's `--measurement s`).
    pub measurement: String,
    pub n_samples: usize,
    pub energy: Vec<ChannelBalance>,
    /// Rays that missed the section at its edge by rounding (tallied as grazing R).
    pub grazing_rays: u64,
    /// Directions mirrored back across the geometric surface (see docs/trace.md).
    pub mirrored_directions: u64,
    /// Interfaces where no perturbed normal faced the ray.
    pub normal_fallbacks: u64,
    pub command_line: Option<String>,
}

impl TraceRecord {
    pub fn load(path: &Path) -> Result<TraceRecord> {
        crate::json_file::read_json(path, "not a hairfit trace sidecar (FILE.trace.json)")
    }

    pub fn save(&self, path: &Path) -> Result<()> {
        crate::json_file::write_json(path, self)
    }

    /// The energy table from a result.
    pub fn energy(result: &TraceResult, channels: &[String]) -> Vec<ChannelBalance> {
        let n = result.rays_total as f64;
        let b = &result.balance;
        channels
            .iter()
            .enumerate()
            .map(|(c, name)| {
                let tallied = [0, 1, 2, 3].map(|p| b.tallied[p][c] / n);
                let absorbed = b.absorbed[c] / n;
                let inside = b.inside[c] / n;
                ChannelBalance {
                    channel: name.clone(),
                    tallied,
                    absorbed,
                    inside,
                    residual: 1.0 - tallied.iter().sum::<f64>() - absorbed - inside,
                }
            })
            .collect()
    }
}

/// The sidecar's path: `FILE.csv` → `FILE.trace.json`.
pub fn record_path(csv: &Path) -> PathBuf {
    csv.with_extension("trace.json")
}

/// The dataset (`S`, `sigma`) at `directions` (radians) and its per-order columns.
pub fn dataset(
    result: &TraceResult,
    directions: &[[f64; 4]],
) -> (Dataset, Vec<(String, Vec<f64>)>) {
    let nc = result.nc;
    let n = directions.len();
    let channels = channel_names(nc);
    let mut values = vec![0.0; n * nc];
    let mut sigma = vec![0.0; n * nc];
    let mut orders = vec![vec![0.0; n]; ORDERS * nc];
    for inc in &result.incidences {
        for (j, &k) in inc.rows.iter().enumerate() {
            for c in 0..nc {
                let mut total = 0.0;
                for (p, col) in orders.chunks_mut(nc).enumerate() {
                    let v = inc.s[(j * ORDERS + p) * nc + c];
                    col[c][k] = v;
                    total += v;
                }
                values[k * nc + c] = total;
                sigma[k * nc + c] = inc.sigma[j * nc + c];
            }
        }
    }
    let column = |a: usize| directions.iter().map(|d| d[a]).collect();
    let ds = Dataset {
        channels: channels.clone(),
        theta_i: column(0),
        phi_i: column(1),
        theta_r: column(2),
        phi_r: column(3),
        radiance: values,
        sigma: Some(sigma),
        weight: None,
        source_line: (0..n as u64).map(|i| CSV_FIRST_DATA_LINE + i).collect(),
        meta: serde_json::Map::new(),
    };
    let extra = orders
        .into_iter()
        .enumerate()
        .map(|(k, col)| {
            let (p, c) = (k / nc, k % nc);
            (format!("s_{}_{}", ORDER_NAMES[p], channels[c]), col)
        })
        .collect();
    (ds, extra)
}

/// Write the CSV and its sidecar together (both or neither).
pub fn write(
    ds: &Dataset,
    extra: &[(String, Vec<f64>)],
    record: &TraceRecord,
    csv: &Path,
) -> Result<()> {
    let sidecar = record_path(csv);
    let mut staged = crate::atomic::StagedFiles::new();
    let csv_tmp = staged.stage(csv)?;
    write_csv_with(ds, extra, &csv_tmp)
        .map_err(|e| crate::atomic::name_target(e, &csv_tmp, csv))?;
    let side_tmp = staged.stage(&sidecar)?;
    record
        .save(&side_tmp)
        .map_err(|e| crate::atomic::name_target(e, &side_tmp, &sidecar))?;
    staged.publish()
}

/// The radians of rig directions given in degrees, as the loader will read them back.
pub fn radians(directions_deg: &[[f64; 4]]) -> Vec<[f64; 4]> {
    directions_deg
        .iter()
        .map(|a| a.map(|d| round_trip_degrees(d.to_radians()).to_radians()))
        .collect()
}
