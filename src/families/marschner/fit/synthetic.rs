//! Synthetic Marschner data in memory for the fit's tests and benchmarks: the project's
//! synthesizer at given directions, as the fit sees a loaded file.

use crate::families::effects::ModelConfig;
use crate::families::marschner::Params;
use crate::fit::problem::FitData;
use crate::geometry::Angles;

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
        crate::synth::Noise::parse(&format!("relative:{noise}"))
    } else {
        crate::synth::Noise::parse("none")
    }
    .expect("a relative noise level parses");
    let (dataset, _) = crate::synth::synthesize_directions(
        truth,
        config,
        &directions,
        "in-memory test data",
        &noise,
        scale,
        crate::geometry::Measurement::S,
        seed,
    )
    .expect("valid synthetic inputs");
    crate::fit::fit_data(&dataset)
}
