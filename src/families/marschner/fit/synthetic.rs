//! Synthetic Marschner data in memory, from `crate::synth` (the project's synthesizer): a
//! dataset with its truth on a rig or at given directions, and the same as the fit sees a
//! loaded file (for the fit's tests, benchmarks and cost ledger).

use crate::data::Dataset;
use crate::error::Result;
use crate::families::effects::ModelConfig;
use crate::families::marschner::family::MarschnerModel;
use crate::families::marschner::params::ParamFile;
use crate::families::marschner::Params;
use crate::families::{FamilyModel, FamilyParams, ModelRecords};
use crate::files::Truth;
use crate::fit::problem::FitData;
use crate::geometry::{Angles, Measurement};
use crate::synth::{random, synthesize_model, Acquisition, Noise, Rig, Source};

/// In-memory data for the fit's tests and benchmark: the project's synthesizer at `angles` with
/// relative Gaussian noise (`noise = 0`: none, unweighted), as the fit sees a loaded file.
/// Panics on inputs the synthesizer rejects (invalid parameters or |θ| ≥ 90°): a caller's bug.
pub fn synthesize(
    truth: &Params<f64>,
    config: &ModelConfig,
    angles: &[Angles],
    scale: &[f64],
    noise: f64,
    seed: u64,
) -> FitData {
    let directions: Vec<[f64; 4]> = angles
        .iter()
        .map(|a| [a.theta_i, a.phi_i, a.theta_r, a.phi_r].map(f64::to_degrees))
        .collect();
    let noise = if noise > 0.0 {
        Noise::parse(&format!("relative:{noise}"))
    } else {
        Noise::parse("none")
    }
    .expect("a relative noise level parses");
    let (dataset, _) = synthesize_directions(
        truth,
        config,
        &directions,
        "in-memory test data",
        &noise,
        scale,
        Measurement::S,
        seed,
    )
    .expect("valid synthetic inputs");
    crate::fit::fit_data(&dataset)
}

/// Synthesize a dataset: the rig's directions (degrees, converted to radians once with
/// `to_radians`, as the loader does), value = `scale[c] · S_c` from [`crate::families::marschner::scattering`] under
/// `config` (times `cos θ_i` when `measurement` is radiance), then `noise` seeded by `seed`. One channel per `params.sigma_a` entry; `scale` has
/// one positive entry per channel. With `Noise::default()` the values are exactly
/// `scale[c] * S_c` at the stored radians, which are the radians the loader makes of the degrees
/// [`crate::data::write_csv`] writes, so a written and reloaded dataset reproduces the model bit for bit.
/// `Truth::params` is `ParamFile::from_params(params)` and `command_line` is `None`.
pub fn synthesize_rig(
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

/// [`synthesize_rig`] at explicit directions `[θ_i, φ_i, θ_r, φ_r]` in degrees (for geometries no
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
    let model = FamilyModel::Marschner(MarschnerModel {
        params: params.clone(),
        config: *config,
    });
    let file = FamilyParams::Marschner(ParamFile::from_params(params));
    let source = Source {
        model: &model,
        file: &file,
        records: ModelRecords::of_config(*config),
    };
    let how = Acquisition {
        directions,
        label,
        noise,
        scale,
        measurement,
        seed,
    };
    synthesize_model(&source, &how)
}
