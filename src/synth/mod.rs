//! `hairfit synth`: synthetic measurements from known parameters — a rig's geometry
//! ([`Rig`]), the model × a per-channel scale, seeded noise ([`Noise`]) — written as a loader CSV
//! plus a `FILE.truth.json` sidecar ([`Truth`]) holding everything needed to check a fit.
//!
//! Reproducibility: every random number comes from ChaCha8 keyed by the seed with one stream
//! per purpose (see [`random`]), so a seed gives the same draws on any machine and any future
//! build; the model values themselves can differ in the last digit with the platform's `libm`.

pub mod memory;
pub mod noise;
pub mod random;
mod rig;

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::data::{round_trip_degrees, Dataset};
use crate::error::{Error, Result};
use crate::families::{FamilyModel, FamilyParams, ModelRecords};
pub use crate::files::{ScaleEntry, Truth};
use crate::geometry::{Angles, Measurement};

pub use self::noise::{Noise, Noisy, OutlierKind, OUTLIER_FACTOR};
pub use self::rig::{Rig, MAX_THETA_DEG};

/// Generator description recorded in every truth file.
pub const RNG_DESCRIPTION: &str = "ChaCha8 (rand_chacha 0.9), key = seed as u64 little-endian \
    zero-padded, stream 0 angles, 1 photon, 2 relative, 3 floor, 4 outliers";

/// Line of the first sample in the CSV that [`write_csv`] writes (two comment lines, then the
/// header): a synthesized dataset's `source_line` is what loading its file gives back.
pub const CSV_FIRST_DATA_LINE: u64 = 4;

/// Channel names for `n` channels: `radiance` (one column `radiance`), `r,g,b`, or `c0…`.
pub fn channel_names(n: usize) -> Vec<String> {
    match n {
        1 => vec!["radiance".into()],
        3 => vec!["r".into(), "g".into(), "b".into()],
        _ => (0..n).map(|c| format!("c{c}")).collect(),
    }
}

/// What a synthetic dataset is made from: a family's model, its parameter file and
/// configuration (recorded in the truth).
pub struct Source<'a> {
    pub model: &'a FamilyModel,
    pub file: &'a FamilyParams,
    /// What the truth records of the family's configuration (`model`, `chiang`, `terms`).
    pub records: ModelRecords,
}

/// How a synthetic dataset's samples are taken: at which directions `[θ_i, φ_i, θ_r, φ_r]`
/// (degrees; `label` names the geometry in the truth), with what noise, per-channel scale and
/// measured quantity, from which seed.
#[derive(Debug, Clone, Copy)]
pub struct Acquisition<'a> {
    pub directions: &'a [[f64; 4]],
    pub label: &'a str,
    pub noise: &'a Noise,
    pub scale: &'a [f64],
    pub measurement: Measurement,
    pub seed: u64,
}

/// A synthetic dataset of any family's model (`source`) taken as `how` says; `source.file`
/// must be valid.
pub fn synthesize_model(source: &Source<'_>, how: &Acquisition<'_>) -> Result<(Dataset, Truth)> {
    if let Some((i, a)) =
        how.directions.iter().enumerate().find(|(_, a)| {
            !(a.iter().all(|x| x.is_finite()) && a[0].abs() < 90.0 && a[2].abs() < 90.0)
        })
    {
        return Err(Error::Other(format!(
            "direction {i} = {a:?} (degrees): angles must be finite and |theta| < 90"
        )));
    }
    source.file.validate()?;
    let nc = source.model.n_channels();
    if how.scale.len() != nc {
        return Err(Error::Other(format!(
            "--scale: {} values for {nc} channels; give one per channel (or one for all)",
            how.scale.len()
        )));
    }
    if let Some(bad) = how.scale.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
        return Err(Error::Other(format!(
            "--scale: {bad} is not a positive finite number"
        )));
    }
    // Evaluate at the radians the loader will make of the degree text the writer will write.
    // `round_trip_degrees` guarantees that is `d.to_radians()` itself; going through it anyway
    // keeps the bit-exact round trip from resting on that proof.
    let radians: Vec<[f64; 4]> = how
        .directions
        .iter()
        .map(|a| a.map(|d| round_trip_degrees(d.to_radians()).to_radians()))
        .collect();
    let clean = clean_values(source, &radians, how.scale, how.measurement)?;
    let noisy = how.noise.apply(&clean, nc, how.seed);
    how.noise.check_finite(&noisy)?;

    let channels = channel_names(nc);
    let column = |k: usize| radians.iter().map(|a| a[k]).collect();
    let dataset = Dataset {
        channels: channels.clone(),
        theta_i: column(0),
        phi_i: column(1),
        theta_r: column(2),
        phi_r: column(3),
        radiance: noisy.values,
        sigma: noisy.sigma,
        weight: None,
        source_line: (0..radians.len() as u64)
            .map(|i| CSV_FIRST_DATA_LINE + i)
            .collect(),
        meta: serde_json::Map::new(),
    };
    let truth = Truth {
        hairfit_version: env!("CARGO_PKG_VERSION").into(),
        params: source.file.clone(),
        scale: channels
            .iter()
            .zip(how.scale)
            .map(|(c, &v)| ScaleEntry {
                channel: c.clone(),
                value: Some(v),
                std_error: None,
                linear_noise_value: None,
            })
            .collect(),
        measurement: how.measurement,
        channels,
        rig: how.label.to_string(),
        noise: how.noise.to_string(),
        sigma_written: dataset.sigma.is_some(),
        seed: how.seed,
        rng: RNG_DESCRIPTION.into(),
        model: source.records.config,
        family_record: source.records.family_record.clone(),
        terms: source.records.terms.clone(),
        n_samples: dataset.len(),
        outliers: noisy.outliers,
        notes: Vec::new(),
        command_line: None,
    };
    let mut dataset = dataset;
    record_truth(&mut dataset, &truth)?;
    Ok((dataset, truth))
}

/// Keep the truth in the dataset's metadata too (key `truth`), for in-memory users.
pub fn record_truth(dataset: &mut Dataset, truth: &Truth) -> Result<()> {
    let value = serde_json::to_value(truth).map_err(|e| Error::Other(e.to_string()))?;
    dataset.meta.insert("truth".into(), value);
    Ok(())
}

/// `scale[c] · S_c` (times the measurement factor) at every direction (row-major), evaluated in
/// parallel; a value that is not finite and ≥ 0 is a model bug and reported with its angles.
fn clean_values(
    source: &Source<'_>,
    radians: &[[f64; 4]],
    scale: &[f64],
    measurement: Measurement,
) -> Result<Vec<f64>> {
    let nc = scale.len();
    let mut values = vec![0.0; radians.len() * nc];
    let angles: Vec<Angles> = radians
        .iter()
        .map(|a| Angles {
            theta_i: a[0],
            phi_i: a[1],
            theta_r: a[2],
            phi_r: a[3],
        })
        .collect();
    // Batches of samples share the Chiang width integral per exit direction.
    const BATCH: usize = 256;
    values
        .par_chunks_mut(nc * BATCH)
        .zip(angles.par_chunks(BATCH))
        .for_each(|(out, batch)| {
            source.model.eval_batch(batch, out);
            for (row, a) in out.chunks_mut(nc).zip(batch) {
                let f = measurement.factor(a);
                for (v, s) in row.iter_mut().zip(scale) {
                    *v *= s * f;
                }
            }
        });
    if let Some(j) = values.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
        let a = radians[j / nc].map(round_trip_degrees);
        return Err(Error::Other(format!(
            "the model returned {} at theta_i={}, phi_i={}, theta_r={}, phi_r={} (degrees) for \
             the parameters {}: use parameters the model can evaluate",
            values[j],
            a[0],
            a[1],
            a[2],
            a[3],
            source.file.json_line()
        )));
    }
    Ok(values)
}

/// The sidecar path: `FILE.csv` → `FILE.truth.json`.
pub fn truth_path(csv: &Path) -> PathBuf {
    csv.with_extension("truth.json")
}
