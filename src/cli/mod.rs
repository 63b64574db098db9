//! The command line's side of the library: clap option groups shared by several commands (so
//! `main.rs` only composes them and every command spells an option the same way), the fit
//! command's options and flag-worded checks ([`fit`]), the summary it prints ([`summary`]), and
//! its exit codes and signal handling ([`exit`]).

pub mod compare;
pub mod exit;
pub mod export;
mod family_options;
pub mod fit;
pub mod help;
pub mod oom;
pub mod summary;
pub mod synth;
pub mod trace;

use clap::Args;

use crate::error::{Error, Result};
use crate::families::chiang::{ChiangEffects, ChiangModel, WidthNodes};
use crate::families::effects::{Effects, ModelConfig, RootMode};
use crate::families::table::TermSet;
use crate::families::{ModelFamily, ModelSetup};
use crate::geometry::Measurement;

/// Write one line to stderr, as `eprintln!` would, but without its panic when stderr has gone (a
/// pipe whose reader left): then no one is left to tell, and the exit code still says how the
/// run ended.
pub fn tell(line: std::fmt::Arguments<'_>) {
    use std::io::Write as _;
    let _ = writeln!(std::io::stderr(), "{line}");
}

/// The model family (`--model`), its accuracy knobs and effect switches (Marschner: `--mode`,
/// `--lobes`, `--no-glints`, `--no-eccentricity`; Chiang: `--terms`, `--width-nodes`; the
/// table families: `--terms`).
#[derive(Debug, Clone, Args)]
pub struct ModelArgs {
    // help::with_registries appends the list of families.
    /// Model family; docs/families.md lists each one's parameters and terms
    #[arg(long = "model", value_enum, default_value_t = ModelFamily::default())]
    pub family: ModelFamily,
    /// Terms of S, comma-separated [default: all]: Chiang's R, TT, TRT, residual; a table
    /// family's own (kajiya-kay: diffuse, specular; deon: R, TT, TRT, residual; karis: R, TT,
    /// TRT, scatter, default without scatter; frostbite: R, TT, TRT). Not for marschner (see
    /// --lobes).
    #[arg(long)]
    pub terms: Option<String>,
    /// Chiang only: the width integral's rule, `auto` (default: split at the lobes' kinks,
    /// nodes chosen by beta_n, S within 1e-7) or N for the plain N-node Gauss-Legendre rule.
    #[arg(long, value_parser = parse_width_nodes)]
    pub width_nodes: Option<WidthNodes>,
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

fn parse_width_nodes(s: &str) -> std::result::Result<WidthNodes, String> {
    s.parse().map_err(|e: crate::error::Error| e.to_string())
}

impl ModelArgs {
    /// The Chiang model these options ask for (`--terms`, `--width-nodes`; their defaults for
    /// another family, which may not be given them: [`ModelArgs::setup`]).
    fn chiang(&self) -> Result<ChiangModel> {
        let effects = match (&self.terms, self.family) {
            (Some(t), ModelFamily::Chiang) => ChiangEffects::parse(t)?,
            _ => ChiangEffects::default(),
        };
        ChiangModel::with_width(effects, self.width_nodes.unwrap_or_default())
            .map_err(|e| Error::Other(format!("--width-nodes: {e}")))
    }

    /// Every family's configuration these options ask for (what is not the chosen family's
    /// stays at its default; giving it is an error, [`ModelArgs::check_family_options`]).
    pub fn setup(&self) -> Result<ModelSetup> {
        self.refuse_foreign_options()?;
        let terms = match (self.family.table(), &self.terms) {
            (Some(table), Some(list)) => {
                Some(TermSet::parse(list, table.terms(), self.family.as_str())?)
            }
            _ => None,
        };
        Ok(ModelSetup {
            config: self.config()?,
            chiang: self.chiang()?,
            terms,
        })
    }

    /// Every option of another family than `--model`'s is an error naming whose it is, and the
    /// chosen family's are checked.
    pub fn check_family_options(&self) -> Result<()> {
        self.setup().map(drop)
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
