//! `hairfit export`'s options: the fit directory, the target (a renderer or an engine), the
//! output file(s).

use std::path::PathBuf;

use clap::Args;

use crate::error::Result;
use crate::export::{export, unreal, write_export, Renderer, Target};

/// Write what a renderer loads from a fit directory.
#[derive(Debug, Clone, Args)]
#[command(
    after_help = "The renderer's own formulation (pbrt-v4, Cycles' or MaterialX's variant of the Chiang model) is \
fitted to the fit's S over its measured directions (curves.csv) and a dense sphere; the file's header and \
stderr state that mapping's error. A Marschner fit is exported the same way: the Chiang model is fitted to \
the fitted Marschner S. --to unreal fits Unreal Engine 5's Hair material inputs (Base Color, Roughness, \
Specular, Backlit, Scatter; docs/karis.md) the same way and writes a JSON file with a Python script beside it."
)]
pub struct ExportArgs {
    /// The fit's directory (params.json, fit.json, curves.csv from `hairfit fit`).
    pub dir: PathBuf,
    /// Target: pbrt (a MakeNamedMaterial block), blender (a bpy script), materialx (.mtlx), or
    /// unreal (Unreal Engine 5 hair material inputs: a .json file and a .py script beside it).
    #[arg(long, value_parser = parse_target)]
    pub to: Target,
    /// Output file (written atomically); stdout when absent. A name with another target's
    /// extension (--to pbrt --output hair.mtlx) is refused; use .pbrt, .py, .mtlx or .json as
    /// --to says. --to unreal --output hair.json also writes hair.py beside it.
    #[arg(long)]
    pub output: Option<PathBuf>,
}

fn parse_target(s: &str) -> std::result::Result<Target, String> {
    s.parse().map_err(|e: crate::error::Error| e.to_string())
}

/// Run the export; returns the summary line for stderr, and the file's text when it goes to
/// stdout.
pub fn export_command(args: &ExportArgs) -> Result<(String, Option<String>)> {
    // Checked before the model is fitted, which takes a while.
    if let Some(path) = &args.output {
        crate::atomic::refuse_directory_output("--output", path, args.to.file_name())?;
        args.to.check_output_name("--output", path)?;
        let mut written = vec![path.clone()];
        if args.to == Target::Unreal {
            written.push(unreal::script_path(path));
        }
        let inputs = ["params.json", "fit.json", "curves.csv"].map(|f| args.dir.join(f));
        let inputs: Vec<(&str, &std::path::Path)> =
            inputs.iter().map(|p| ("the fit", p.as_path())).collect();
        for out in &written {
            crate::atomic::refuse_replacing_inputs("--output", out, &inputs)?;
        }
    }
    match args.to {
        Target::Renderer(renderer) => renderer_command(args, renderer),
        Target::Unreal => unreal_command(args),
    }
}

/// `--to pbrt|blender|materialx`: one file.
fn renderer_command(args: &ExportArgs, renderer: Renderer) -> Result<(String, Option<String>)> {
    let result = export(&args.dir, renderer)?;
    let warned = warning_lines(&result.warnings);
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

/// `--to unreal`: the JSON (stdout without --output) and, with --output, the script beside it.
fn unreal_command(args: &ExportArgs) -> Result<(String, Option<String>)> {
    let result = unreal::export(&args.dir)?;
    let warned = warning_lines(&result.warnings);
    match &args.output {
        Some(path) => {
            unreal::write_files(path, &result)?;
            Ok((
                format!(
                    "{warned}{}; wrote {} and {}",
                    result.summary,
                    path.display(),
                    unreal::script_path(path).display()
                ),
                None,
            ))
        }
        None => Ok((
            format!(
                "{warned}{}; the Python script is written with --output (beside the JSON)",
                result.summary
            ),
            Some(result.json),
        )),
    }
}

/// Warnings first, each on its own line (main prefixes the first with `hairfit: `).
fn warning_lines(warnings: &[String]) -> String {
    warnings
        .iter()
        .map(|w| format!("warning: {w}\nhairfit: "))
        .collect()
}
