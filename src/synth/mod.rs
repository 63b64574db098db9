//! `hairfit synth`: synthetic measurements from known parameters — a rig's geometry
//! ([`Rig`]), the model × a per-channel scale, seeded noise ([`Noise`]) — written as a loader CSV
//! plus a `FILE.truth.json` sidecar ([`Truth`]) holding everything needed to check a fit.
//!
//! Reproducibility: every random number comes from ChaCha8 keyed by the seed with one stream
//! per purpose (see [`random`]), so a seed gives the same draws on any machine and any future
//! build; the model values themselves can differ in the last digit with the platform's `libm`.

pub mod memory;
mod noise;
pub mod random;
mod rig;

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::cli::{MeasurementArgs, ModelArgs};
use crate::data::{round_trip_degrees, write_csv, Dataset};
use crate::error::{Error, Result};
use crate::family::{ChiangRecord, FamilyModel, FamilyParams};
pub use crate::files::{ScaleEntry, Truth};
use crate::model::{Angles, Measurement, ModelConfig, Params};
use crate::params::{ParamFile, SigmaA};

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

/// Synthesize a dataset: the rig's directions (degrees, converted to radians once with
/// `to_radians`, as the loader does), value = `scale[c] · S_c` from [`scattering`] under
/// `config` (times `cos θ_i` when `measurement` is radiance), then `noise` seeded by `seed`. One channel per `params.sigma_a` entry; `scale` has
/// one positive entry per channel. With `Noise::default()` the values are exactly
/// `scale[c] * S_c` at the stored radians, which are the radians the loader makes of the degrees
/// [`write_csv`] writes, so a written and reloaded dataset reproduces the model bit for bit.
/// `Truth::params` is `ParamFile::from_params(params)` and `command_line` is `None`.
pub fn synthesize(
    params: &Params<f64>,
    config: &ModelConfig,
    rig: &Rig,
    noise: &Noise,
    scale: &[f64],
    measurement: Measurement,
    seed: u64,
) -> Result<(Dataset, Truth)> {
    let directions = rig.angles(&mut random::generator(seed, random::Stream::Angles));
    synthesize_directions(
        params,
        config,
        &directions,
        &rig.to_string(),
        noise,
        scale,
        measurement,
        seed,
    )
}

/// [`synthesize`] at explicit directions `[θ_i, φ_i, θ_r, φ_r]` in degrees (for geometries no
/// [`Rig`] describes, e.g. a demo's scan); `label` is recorded as the truth's `rig`. Each |θ|
/// must be below 90° and every angle finite.
#[allow(clippy::too_many_arguments)]
pub fn synthesize_directions(
    params: &Params<f64>,
    config: &ModelConfig,
    directions: &[[f64; 4]],
    label: &str,
    noise: &Noise,
    scale: &[f64],
    measurement: Measurement,
    seed: u64,
) -> Result<(Dataset, Truth)> {
    params.validate()?;
    let model = FamilyModel::Marschner {
        params: params.clone(),
        config: *config,
    };
    let file = FamilyParams::Marschner(ParamFile::from_params(params));
    let source = Source {
        model: &model,
        file: &file,
        config,
        chiang: None,
    };
    synthesize_model(&source, directions, label, noise, scale, measurement, seed)
}

/// What a synthetic dataset is made from: a family's model, its parameter file and
/// configuration (recorded in the truth).
pub struct Source<'a> {
    pub model: &'a FamilyModel,
    pub file: &'a FamilyParams,
    /// The truth's `model` (for Chiang data: its lobes, see `chiang::lobes_config`).
    pub config: &'a ModelConfig,
    pub chiang: Option<ChiangRecord>,
}

/// [`synthesize_directions`] for either model family; `source.file` must be valid.
pub fn synthesize_model(
    source: &Source<'_>,
    directions: &[[f64; 4]],
    label: &str,
    noise: &Noise,
    scale: &[f64],
    measurement: Measurement,
    seed: u64,
) -> Result<(Dataset, Truth)> {
    if let Some((i, a)) = directions
        .iter()
        .enumerate()
        .find(|(_, a)| !(a.iter().all(|x| x.is_finite()) && a[0].abs() < 90.0 && a[2].abs() < 90.0))
    {
        return Err(Error::Other(format!(
            "direction {i} = {a:?} (degrees): angles must be finite and |theta| < 90"
        )));
    }
    source.file.validate()?;
    let nc = source.model.n_channels();
    if scale.len() != nc {
        return Err(Error::Other(format!(
            "--scale: {} values for {nc} channels; give one per channel (or one for all)",
            scale.len()
        )));
    }
    if let Some(bad) = scale.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
        return Err(Error::Other(format!(
            "--scale: {bad} is not a positive finite number"
        )));
    }
    // Evaluate at the radians the loader will make of the degree text the writer will write.
    // `round_trip_degrees` guarantees that is `d.to_radians()` itself; going through it anyway
    // keeps the bit-exact round trip from resting on that proof.
    let radians: Vec<[f64; 4]> = directions
        .iter()
        .map(|a| a.map(|d| round_trip_degrees(d.to_radians()).to_radians()))
        .collect();
    let clean = clean_values(source, &radians, scale, measurement)?;
    let noisy = noise.apply(&clean, nc, seed);
    noise.check_finite(&noisy)?;

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
            .zip(scale)
            .map(|(c, &v)| ScaleEntry {
                channel: c.clone(),
                value: Some(v),
                std_error: None,
            })
            .collect(),
        measurement,
        channels,
        rig: label.to_string(),
        noise: noise.to_string(),
        sigma_written: dataset.sigma.is_some(),
        seed,
        rng: RNG_DESCRIPTION.into(),
        model: *source.config,
        chiang: source.chiang,
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
fn record_truth(dataset: &mut Dataset, truth: &Truth) -> Result<()> {
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

/// Options of `hairfit synth`.
#[derive(Debug, Clone, clap::Args)]
pub struct SynthArgs {
    /// Parameter file with the true parameters (JSON, MODEL.md's names; CHIANG.md's with
    /// --model chiang).
    #[arg(long)]
    pub params: PathBuf,
    /// Sample geometry: azimuthal, longitudinal, sphere or photo, with options, e.g.
    /// `azimuthal:incidences=15,30,45:steps=180` (see data/README.md).
    #[arg(long)]
    pub rig: String,
    /// Noise: `none`, or terms joined by `+`: relative:R, photon:N, floor:F, outliers:P.
    #[arg(long, default_value = "none")]
    pub noise: String,
    /// What an outlier (`outliers:P` in --noise) does to its sample: `spike` (× 3–10), `dropout`
    /// (a near-zero reading, × 0–0.01), `sign` (negated), `offset` (± 1–10 × the channel's
    /// median value) or `mixed` (each outlier one of the four) [default: spike].
    #[arg(long)]
    pub outlier_kind: Option<noise::OutlierKind>,
    /// The outliers' magnitude range `LO..HI` for --outlier-kind (e.g. `5..50` for spikes ×5–50;
    /// for `mixed` it sets the spikes') [default: the kind's range above].
    #[arg(long, value_parser = noise::parse_outlier_range)]
    pub outlier_range: Option<(f64, f64)>,
    /// Seed of every random draw (same seed, same bytes).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Number of colour channels; a scalar sigma_a is replicated to every channel, an array
    /// must have exactly this many entries [default: sigma_a's length].
    #[arg(long)]
    pub channels: Option<usize>,
    /// Scale factor(s): one for all channels, or one per channel, comma-separated.
    #[arg(
        long,
        default_value = "1",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    pub scale: Vec<f64>,
    /// Output CSV (`FILE.csv`); the truth goes to `FILE.truth.json`. Both written atomically.
    #[arg(long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub model: ModelArgs,
    #[command(flatten)]
    pub measurement: MeasurementArgs,
    /// Most memory the dataset may take, e.g. 500M or 2G (checked before allocating)
    /// [default: half this machine's memory].
    #[arg(long, value_parser = memory::parse_size)]
    pub max_memory: Option<u64>,
}

/// What `hairfit synth` wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthSummary {
    pub csv: PathBuf,
    pub truth: PathBuf,
    pub n_samples: usize,
    pub n_outliers: usize,
    /// Choices made on the user's behalf (also in the truth file).
    pub notes: Vec<String>,
}

/// The sidecar path: `FILE.csv` → `FILE.truth.json`.
pub fn truth_path(csv: &Path) -> PathBuf {
    csv.with_extension("truth.json")
}

/// Run `hairfit synth`: load and reconcile the inputs, synthesize, write the CSV and the truth
/// file. `command_line` is recorded in the truth file.
pub fn run(args: &SynthArgs, command_line: Option<String>) -> Result<SynthSummary> {
    let is_csv = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if !is_csv {
        return Err(Error::Other(format!(
            "--output {}: name the file FILE.csv (the loader picks the format by extension; the \
             truth goes to FILE.truth.json)",
            args.output.display()
        )));
    }
    if crate::atomic::is_special_file(&args.output) {
        return Err(Error::Other(format!(
            "--output {}: is a device, FIFO or socket; synth writes the CSV and its truth file \
             (FILE.truth.json) beside each other, so --output names a file",
            args.output.display()
        )));
    }
    refuse_overwriting_input(&args.params, &args.output)?;
    let rig = Rig::parse(&args.rig)?;
    let noise =
        Noise::parse(&args.noise)?.with_outlier_options(args.outlier_kind, args.outlier_range)?;
    args.model.check_family_options()?;
    let config = args.model.config()?;
    let chiang = args.model.chiang()?;
    let file = FamilyParams::load(&args.params, args.model.family)?;
    let (file, notes) = reconcile_channels(file, args.channels, &args.params)?;
    let nc = file.n_channels();
    let limit = args.max_memory.unwrap_or_else(memory::machine_default);
    rig.check_memory(nc, &args.rig, limit)?;
    let scale = match args.scale.len() {
        1 => vec![args.scale[0]; nc],
        n if n == nc => args.scale.clone(),
        n => {
            return Err(Error::Other(format!(
                "--scale has {n} values but there are {nc} channels: give one value for all \
                 channels or exactly {nc}"
            )))
        }
    };
    let model = FamilyModel::new(&file, config, &chiang);
    let (config, record) = match &file {
        FamilyParams::Marschner(_) => (config, None),
        FamilyParams::Chiang(_) => (
            crate::chiang::lobes_config(&chiang.effects),
            Some(ChiangRecord {
                effects: chiang.effects,
                width_nodes: chiang.width_nodes(),
            }),
        ),
    };
    let source = Source {
        model: &model,
        file: &file,
        config: &config,
        chiang: record,
    };
    let directions = rig.angles(&mut random::generator(args.seed, random::Stream::Angles));
    let (mut dataset, mut truth) = synthesize_model(
        &source,
        &directions,
        &rig.to_string(),
        &noise,
        &scale,
        args.measurement.measurement,
        args.seed,
    )?;
    truth.params = file;
    truth.notes = notes;
    truth.command_line = command_line;
    record_truth(&mut dataset, &truth)?;

    // The data and its truth are published together: both or neither.
    let truth_file = truth_path(&args.output);
    let mut staged = crate::atomic::StagedFiles::new();
    let csv_tmp = staged.stage(&args.output)?;
    write_csv(&dataset, &csv_tmp).map_err(|e| name_target(e, &csv_tmp, &args.output))?;
    let truth_tmp = staged.stage(&truth_file)?;
    truth
        .save(&truth_tmp)
        .map_err(|e| name_target(e, &truth_tmp, &truth_file))?;
    staged.publish()?;
    Ok(SynthSummary {
        csv: args.output.clone(),
        truth: truth_file,
        n_samples: truth.n_samples,
        n_outliers: truth.outliers.len(),
        notes: truth.notes,
    })
}

/// `--params X.truth.json --output X.csv` would replace the parameter file being read (or the
/// CSV itself): refuse, by the rule `eval` applies too.
fn refuse_overwriting_input(params: &Path, output: &Path) -> Result<()> {
    let inputs = [("--params", params)];
    crate::atomic::refuse_replacing_inputs("--output", output, &inputs)?;
    crate::atomic::refuse_replacing_inputs("--output's truth file", &truth_path(output), &inputs)
}

/// An error about the staged temporary file `tmp`, worded about the file the user asked for.
fn name_target(e: Error, tmp: &Path, target: &Path) -> Error {
    let text = e.to_string();
    let tmp = tmp.display().to_string();
    if text.contains(&tmp) {
        Error::Other(text.replace(&tmp, &target.display().to_string()))
    } else {
        e
    }
}

/// Apply `--channels`: a scalar sigma_a is replicated (with a note), an array must match.
fn reconcile_channels(
    mut file: FamilyParams,
    channels: Option<usize>,
    path: &Path,
) -> Result<(FamilyParams, Vec<String>)> {
    let mut notes = Vec::new();
    match (channels, file.sigma_a_mut().clone()) {
        (Some(0), _) => {
            return Err(Error::Other(
                "--channels 0: give at least one colour channel".into(),
            ))
        }
        (Some(n), SigmaA::Scalar(s)) if n > 1 => {
            *file.sigma_a_mut() = SigmaA::PerChannel(vec![s; n]);
            notes.push(format!(
                "sigma_a = {s} (a scalar in {}) replicated to all {n} channels",
                path.display()
            ));
        }
        (Some(n), SigmaA::PerChannel(v)) if v.len() != n => {
            return Err(Error::Other(format!(
                "--channels {n}, but sigma_a in {} has {} values: give one sigma_a per channel, \
                 or a single number to use in every channel",
                path.display(),
                v.len()
            )))
        }
        _ => {}
    }
    Ok((file, notes))
}

/// The command line as one string, arguments with spaces or quotes single-quoted.
pub fn command_line_string(args: impl IntoIterator<Item = String>) -> String {
    args.into_iter()
        .map(|a| {
            if a.is_empty() || a.contains([' ', '\'', '"', '\t']) {
                format!("'{}'", a.replace('\'', r"'\''"))
            } else {
                a
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}
