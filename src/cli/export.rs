//! `hairfit export`'s options: the fit directory, the renderer, the output file.

use std::path::PathBuf;

use clap::Args;

use crate::error::Result;
use crate::export::{export, write_export, Renderer};

/// Write what a renderer loads from a fit directory.
#[derive(Debug, Clone, Args)]
#[command(
    after_help = "The renderer's own formulation (pbrt-v4, Cycles' or MaterialX's variant of the Chiang model) is \
fitted to the fit's S over its measured directions (curves.csv) and a dense sphere; the file's header and \
stderr state that mapping's error. A Marschner fit is exported the same way: the Chiang model is fitted to \
the fitted Marschner S."
)]
pub struct ExportArgs {
    /// The fit's directory (params.json, fit.json, curves.csv from `hairfit fit`).
    pub dir: PathBuf,
    /// Renderer: pbrt (a MakeNamedMaterial block), blender (a bpy script), materialx (.mtlx).
    #[arg(long, value_parser = parse_renderer)]
    pub to: Renderer,
    /// Output file (written atomically); stdout when absent. A name with another renderer's
    /// extension (--to pbrt --output hair.mtlx) is refused; use .pbrt, .py or .mtlx as --to says.
    #[arg(long)]
    pub output: Option<PathBuf>,
}

fn parse_renderer(s: &str) -> std::result::Result<Renderer, String> {
    s.parse().map_err(|e: crate::error::Error| e.to_string())
}

/// Run the export; returns the summary line for stderr, and the file's text when it goes to
/// stdout.
pub fn export_command(args: &ExportArgs) -> Result<(String, Option<String>)> {
    // Checked before the renderer model is fitted, which takes a while.
    if let Some(path) = &args.output {
        crate::atomic::refuse_directory_output("--output", path, args.to.file_name())?;
        args.to.check_output_name("--output", path)?;
    }
    let result = export(&args.dir, args.to)?;
    // Warnings first, each on its own line (main prefixes the first with `hairfit: `).
    let warned: String = result
        .warnings
        .iter()
        .map(|w| format!("warning: {w}\nhairfit: "))
        .collect();
    match &args.output {
        Some(path) => {
            write_export(path, &result)?;
            Ok((
                format!("{warned}{}; wrote {}", result.summary, path.display()),
                None,
            ))
        }
        None => Ok((format!("{warned}{}", result.summary), Some(result.text))),
    }
}
