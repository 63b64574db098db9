//! The command line's side of the library: clap option groups shared by several commands (so
//! `main.rs` only composes them and every command spells an option the same way), the fit
//! command's options and flag-worded checks ([`fit`]), the summary it prints ([`summary`]), and
//! its exit codes and signal handling ([`exit`]).

pub mod exit;
pub mod fit;
pub mod summary;

use clap::Args;

use crate::error::Result;
use crate::model::{Effects, Measurement, ModelConfig, RootMode};

/// The model's accuracy knob and effect switches (`--mode`, `--lobes`, `--no-glints`,
/// `--no-eccentricity`).
#[derive(Debug, Clone, Args)]
pub struct ModelArgs {
    /// Root mode of the exit-angle map: `cubic` (Marschner 2003) or `exact`.
    #[arg(long, default_value = "cubic", value_parser = parse_mode)]
    pub mode: RootMode,
    /// Lobes to simulate, comma-separated (R, TT, TRT); the others are not computed.
    #[arg(long, default_value = "R,TT,TRT")]
    pub lobes: String,
    /// Do not simulate the TRT glints (caustics): plain TRT roots only.
    #[arg(long)]
    pub no_glints: bool,
    /// Do not simulate eccentricity: TRT sees a circular cross-section.
    #[arg(long)]
    pub no_eccentricity: bool,
}

/// What the data file's values are (`--measurement`): `fit` and `demo` fit it, `synth` makes it.
#[derive(Debug, Clone, Args)]
pub struct MeasurementArgs {
    /// The values are `s` (scale·S) or `radiance` under a collimated source (scale·S·cos θ_i).
    #[arg(long, default_value = "s")]
    pub measurement: Measurement,
}

fn parse_mode(s: &str) -> std::result::Result<RootMode, String> {
    s.parse().map_err(|e: crate::error::Error| e.to_string())
}

impl ModelArgs {
    /// The model configuration these options ask for.
    pub fn config(&self) -> Result<ModelConfig> {
        Ok(ModelConfig {
            mode: self.mode,
            effects: Effects {
                lobes: Effects::parse_lobes(&self.lobes)?,
                glints: !self.no_glints,
                eccentricity: !self.no_eccentricity,
            },
        })
    }
}
