//! `hairfit synth`: its options ([`SynthArgs`]) and the run that reconciles them with the
//! parameter file, synthesizes through [`crate::synth`] and writes the CSV and its truth file.

use std::path::{Path, PathBuf};

use super::{MeasurementArgs, ModelArgs};
use crate::data::write_csv;
use crate::error::{Error, Result};
use crate::families::{FamilyModel, FamilyParams};
use crate::synth::noise::{self, Noise};
use crate::synth::{
    memory, random, record_truth, synthesize_model, truth_path, Acquisition, Rig, Source,
};

/// Options of `hairfit synth`.
#[derive(Debug, Clone, clap::Args)]
pub struct SynthArgs {
    /// Parameter file with the true parameters (JSON, docs/model.md's names; with --model
    /// NAME, that family's page's: docs/families.md lists them).
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

/// Run `hairfit synth`: load and reconcile the inputs, synthesize, write the CSV and the truth
/// file. `command_line` is recorded in the truth file.
pub fn run(args: &SynthArgs, command_line: Option<String>) -> Result<SynthSummary> {
    crate::atomic::require_csv_pair(&args.output, "synth", "its truth file FILE.truth.json")?;
    refuse_overwriting_input(&args.params, &args.output)?;
    let rig = Rig::parse(&args.rig)?;
    let noise =
        Noise::parse(&args.noise)?.with_outlier_options(args.outlier_kind, args.outlier_range)?;
    args.model.check_family_options()?;
    let setup = args.model.setup()?;
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
    let model = FamilyModel::new(&file, &setup);
    let source = Source {
        model: &model,
        file: &file,
        records: setup.records(file.family()),
    };
    let directions = rig.angles(&mut random::generator(args.seed, random::Stream::Angles));
    let how = Acquisition {
        directions: &directions,
        label: &rig.to_string(),
        noise: &noise,
        scale: &scale,
        measurement: args.measurement.measurement,
        seed: args.seed,
    };
    let (mut dataset, mut truth) = synthesize_model(&source, &how)?;
    truth.params = file;
    truth.notes = notes;
    truth.command_line = command_line;
    record_truth(&mut dataset, &truth)?;

    // The data and its truth are published together: both or neither.
    let truth_file = truth_path(&args.output);
    let mut staged = crate::atomic::StagedFiles::new();
    let csv_tmp = staged.stage(&args.output)?;
    write_csv(&dataset, &csv_tmp)
        .map_err(|e| crate::atomic::name_target(e, &csv_tmp, &args.output))?;
    let truth_tmp = staged.stage(&truth_file)?;
    truth
        .save(&truth_tmp)
        .map_err(|e| crate::atomic::name_target(e, &truth_tmp, &truth_file))?;
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

/// Apply `--channels`: a scalar sigma_a is replicated (with a note), an array must match.
fn reconcile_channels(
    mut file: FamilyParams,
    channels: Option<usize>,
    path: &Path,
) -> Result<(FamilyParams, Vec<String>)> {
    let mut notes = Vec::new();
    match channels {
        Some(0) => {
            return Err(Error::Other(
                "--channels 0: give at least one colour channel".into(),
            ))
        }
        Some(n) => match file.replicate_channels(n) {
            Ok(Some(what)) => notes.push(format!(
                "{what} (a scalar in {}) replicated to all {n} channels",
                path.display()
            )),
            Ok(None) => {}
            Err((name, count)) => {
                return Err(Error::Other(format!(
                    "--channels {n}, but {name} in {} has {count} values: give one {name} per \
                     channel, or a single number to use in every channel",
                    path.display()
                )))
            }
        },
        None => {}
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
