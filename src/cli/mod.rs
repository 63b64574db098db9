//! The command line's side of the library: clap option groups shared by several commands (so
//! `main.rs` only composes them and every command spells an option the same way), the fit
//! command's options and flag-worded checks ([`fit`]), the summary it prints ([`summary`]), and
//! its exit codes and signal handling ([`exit`]).

pub mod compare;
pub mod exit;
pub mod export;
pub mod fit;
pub mod summary;
pub mod synth;

use clap::Args;

use crate::chiang::{ChiangEffects, ChiangModel, DEFAULT_WIDTH_NODES};
use crate::error::{Error, Result};
use crate::family::ModelFamily;
use crate::model::{Effects, Measurement, ModelConfig, RootMode};

/// Write one line to stderr, as `eprintln!` would, but without its panic when stderr has gone (a
/// pipe whose reader left): then no one is left to tell, and the exit code still says how the
/// run ended.
pub fn tell(line: std::fmt::Arguments<'_>) {
    use std::io::Write as _;
    let _ = writeln!(std::io::stderr(), "{line}");
}

/// The model family (`--model`), its accuracy knobs and effect switches (Marschner: `--mode`,
/// `--lobes`, `--no-glints`, `--no-eccentricity`; Chiang: `--terms`, `--width-nodes`).
#[derive(Debug, Clone, Args)]
pub struct ModelArgs {
    /// Model family: `marschner` (Marschner 2003) or `chiang` (Chiang 2016, pbrt-v4's hair).
    #[arg(long = "model", value_enum, default_value_t = ModelFamily::Marschner)]
    pub family: ModelFamily,
    /// Chiang only: terms of S, comma-separated (R, TT, TRT, residual) [default: all four].
    #[arg(long)]
    pub terms: Option<String>,
    /// Chiang only: Gauss-Legendre nodes of the width integral [default: 1024].
    #[arg(long)]
    pub width_nodes: Option<usize>,
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
    /// The Chiang model these options ask for (`--terms`, `--width-nodes`); with `--model
    /// marschner` those options are an error, since they would silently do nothing.
    pub fn chiang(&self) -> Result<ChiangModel> {
        if self.family != ModelFamily::Chiang {
            for (given, flag) in [
                (self.terms.is_some(), "--terms"),
                (self.width_nodes.is_some(), "--width-nodes"),
            ] {
                if given {
                    return Err(Error::Other(format!(
                        "{flag} applies to --model chiang only (the Marschner model takes --lobes, --mode, --no-glints, --no-eccentricity)"
                    )));
                }
            }
        }
        let effects = match &self.terms {
            Some(t) => ChiangEffects::parse(t)?,
            None => ChiangEffects::default(),
        };
        ChiangModel::new(effects, self.width_nodes.unwrap_or(DEFAULT_WIDTH_NODES))
            .map_err(|e| Error::Other(format!("--width-nodes: {e}")))
    }

    /// True when a Marschner-only option was given a non-default value.
    pub fn marschner_options_given(&self) -> Option<&'static str> {
        if self.mode != RootMode::Cubic {
            Some("--mode")
        } else if Effects::parse_lobes(&self.lobes).ok() != Some(crate::model::Lobes::default()) {
            Some("--lobes")
        } else if self.no_glints {
            Some("--no-glints")
        } else if self.no_eccentricity {
            Some("--no-eccentricity")
        } else {
            None
        }
    }

    /// [`ModelArgs::marschner_options_given`] as an error under `--model chiang`.
    pub fn check_family_options(&self) -> Result<()> {
        self.chiang()?;
        if self.family == ModelFamily::Chiang {
            if let Some(flag) = self.marschner_options_given() {
                return Err(Error::Other(format!(
                    "{flag} applies to --model marschner only; the Chiang model takes --terms and --width-nodes"
                )));
            }
        }
        Ok(())
    }

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
