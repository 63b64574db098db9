//! Option parsing: the argument lists the Python layer builds, parsed by the CLI's clap types.

use clap::Parser;
use pyo3::prelude::*;

use hairfit::cli::fit::FitArgs;
use hairfit::cli::ModelArgs;
use hairfit::data::LoadOptions;

use crate::errors::HairfitError;

/// A clap error as one message: its first paragraph, without `error: ` and the usage lines
/// (which name command-line flags a Python caller did not type).
fn clap_text(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let text = text.trim_start().trim_start_matches("error: ");
    let mut parts = text.split("\n\n").map(str::trim);
    let first = parts.next().unwrap_or(text).to_string();
    // clap's "tip: a similar argument exists: '--loss'" names what was meant: keep it.
    match parts.find(|p| p.starts_with("tip:")) {
        Some(tip) => format!("{first} ({tip})"),
        None => first,
    }
}

/// Parse `args` (command-line flags built by the Python layer) with the CLI's own option type.
pub(crate) fn parse<T: Parser>(args: Vec<String>) -> PyResult<T> {
    T::try_parse_from(std::iter::once("hairfit".to_string()).chain(args))
        .map_err(|e| HairfitError::new_err(clap_text(&e)))
}

#[derive(Parser)]
#[command(name = "hairfit")]
pub(crate) struct ModelCli {
    #[command(flatten)]
    pub(crate) model: ModelArgs,
}

#[derive(Parser)]
#[command(name = "hairfit")]
pub(crate) struct LoadCli {
    #[command(flatten)]
    pub(crate) load: LoadOptions,
}

#[derive(Parser)]
#[command(name = "hairfit")]
pub(crate) struct FitCli {
    #[command(flatten)]
    pub(crate) fit: FitArgs,
}

#[derive(Parser)]
#[command(name = "hairfit")]
pub(crate) struct SynthCli {
    #[command(flatten)]
    pub(crate) synth: hairfit::cli::synth::SynthArgs,
}

#[derive(Parser)]
#[command(name = "hairfit")]
pub(crate) struct CompareCli {
    #[command(flatten)]
    pub(crate) compare: hairfit::cli::compare::CompareArgs,
}

#[derive(Parser)]
#[command(name = "hairfit")]
pub(crate) struct ExportCli {
    #[command(flatten)]
    pub(crate) export: hairfit::cli::export::ExportArgs,
}
