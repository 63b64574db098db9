//! `hairfit export`'s options: the fit directory, the renderer, the output file.

use std::path::PathBuf;

use clap::Args;

use crate::error::{Error, Result};
use crate::export::unity::export_unity;
use crate::export::{export, write_export, Renderer};

/// Write what a renderer loads from a fit directory.
#[derive(Debug, Clone, Args)]
#[command(
    after_help = "The renderer's own formulation (pbrt-v4, Cycles' or MaterialX's variant of the Chiang model) is \
fitted to the fit's S over its measured directions (curves.csv) and a dense sphere; the file's header and \
stderr state that mapping's error. A Marschner fit is exported the same way: the Chiang model is fitted to \
the fitted Marschner S. --to unity fits Unity HDRP's hair inputs (Base Color, Smoothness, Radial Smoothness, \
Cuticle Angle) through the frostbite family with one shared light gain, and writes NAME.json and the C# \
editor script NAME.cs beside it (--output NAME.json is required)."
)]
pub struct ExportArgs {
    /// The fit's directory (params.json, fit.json, curves.csv from `hairfit fit`).
    pub dir: PathBuf,
    /// Renderer: pbrt (a MakeNamedMaterial block), blender (a bpy script), materialx (.mtlx),
    /// unity (HDRP hair inputs: a .json and a C# editor script).
    #[arg(long, value_parser = parse_renderer)]
    pub to: Renderer,
    /// Output file (written atomically); stdout when absent. A name with another renderer's
    /// extension (--to pbrt --output hair.mtlx) is refused; use .pbrt, .py, .mtlx or .json as
    /// --to says. --to unity needs it and writes the C# script beside it (NAME.cs).
    #[arg(long)]
    pub output: Option<PathBuf>,
}

fn parse_renderer(s: &str) -> std::result::Result<Renderer, String> {
    s.parse().map_err(|e: crate::error::Error| e.to_string())
}

/// Run the export; returns the summary line for stderr, and the file's text when it goes to
/// stdout.
pub fn export_command(args: &ExportArgs) -> Result<(String, Option<String>)> {
    if args.to == Renderer::Unity {
        return unity_command(args).map(|summary| (summary, None));
    }
    // Checked before the renderer model is fitted, which takes a while.
    if let Some(path) = &args.output {
        crate::atomic::refuse_directory_output("--output", path, args.to.file_name())?;
        args.to.check_output_name("--output", path)?;
    }
    let result = export(&args.dir, args.to)?;
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

/// Warnings first, each on its own line (main prefixes the first with `hairfit: `).
fn warning_lines(warnings: &[String]) -> String {
    warnings
        .iter()
        .map(|w| format!("warning: {w}\nhairfit: "))
        .collect()
}

/// `--to unity`: two files, the JSON at `--output` and the C# script beside it (`.cs`), each
/// written atomically; the checks run before the fit.
fn unity_command(args: &ExportArgs) -> Result<String> {
    let json = args.output.as_ref().ok_or_else(|| {
        Error::Other(
            "--to unity writes two files, NAME.json and the C# editor script NAME.cs beside it: \
             pass --output NAME.json"
                .into(),
        )
    })?;
    crate::atomic::refuse_directory_output("--output", json, args.to.file_name())?;
    args.to.check_output_name("--output", json)?;
    if json
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("cs"))
    {
        return Err(Error::Other(format!(
            "--output {}: --to unity's --output names the JSON file; the C# script is written \
             beside it with .cs: pass --output {}",
            json.display(),
            json.with_extension("json").display()
        )));
    }
    let script = json.with_extension("cs");
    let script_name = script
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let result = export_unity(&args.dir, &script_name)?;
    for (path, text) in [(&script, &result.script), (json, &result.json)] {
        crate::atomic::write_atomically(path, |w| {
            w.write_all(text.as_bytes()).map_err(|e| Error::io(path, e))
        })?;
    }
    Ok(format!(
        "{}{}; wrote {} and {}",
        warning_lines(&result.warnings),
        result.summary,
        json.display(),
        script.display()
    ))
}
