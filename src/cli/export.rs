//! `hairfit export`'s options: the fit directory, the target (a renderer or an engine), the
//! output file(s).

use std::path::{Path, PathBuf};

use clap::Args;

use crate::error::{Error, Result};
use crate::export::unity::export_unity;
use crate::export::{export, unreal, write_export, Renderer, Target};

/// Write what a renderer loads from a fit directory.
#[derive(Debug, Clone, Args)]
#[command(
    after_help = "The renderer's own formulation (pbrt-v4, Cycles' or MaterialX's variant of the Chiang model) is \
fitted to the fit's S over its measured directions (curves.csv) and a dense sphere; the file's header and \
stderr state that mapping's error. A Marschner fit is exported the same way: the Chiang model is fitted to \
the fitted Marschner S. --to unreal fits Unreal Engine 5's Hair material inputs (Base Color, Roughness, \
Specular, Backlit, Scatter; docs/karis.md) the same way and writes a JSON file with a Python script beside it. \
--to unity fits Unity HDRP's hair inputs (Base Color, Smoothness, Radial Smoothness, Cuticle Angle; \
docs/frostbite.md) through the frostbite family and writes NAME.json with the C# editor script NAME.cs beside it \
(--output NAME.json is required)."
)]
pub struct ExportArgs {
    /// The fit's directory (params.json, fit.json, curves.csv from `hairfit fit`).
    pub dir: PathBuf,
    /// Target: pbrt (a MakeNamedMaterial block), blender (a bpy script), materialx (.mtlx),
    /// unreal (Unreal Engine 5 hair material inputs: a .json file and a .py script beside it),
    /// or unity (Unity HDRP hair inputs: a .json file and a C# editor script beside it).
    #[arg(long, value_parser = parse_target)]
    pub to: Target,
    /// Output file (written atomically); stdout when absent. A name with another target's
    /// extension (--to pbrt --output hair.mtlx) is refused; use .pbrt, .py, .mtlx or .json as
    /// --to says. --to unreal --output hair.json also writes hair.py beside it; --to unity
    /// needs --output and writes hair.cs beside it.
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Export a fit whose verdict is `failed` (refused without this: its parameters are not a
    /// fit); the summary warns that they are not.
    #[arg(long)]
    pub allow_failed: bool,
}

fn parse_target(s: &str) -> std::result::Result<Target, String> {
    s.parse().map_err(|e: crate::error::Error| e.to_string())
}

/// Run the export; returns the summary line for stderr, and the file's text when it goes to
/// stdout.
pub fn export_command(args: &ExportArgs) -> Result<(String, Option<String>)> {
    // Checked before the model is fitted, which takes a while: the options first, then the fit.
    if args.to == Target::Unity {
        unity_output(args.output.as_deref())?;
    }
    if let Some(path) = &args.output {
        crate::atomic::refuse_directory_output("--output", path, args.to.file_name())?;
        args.to.check_output_name("--output", path)?;
        let mut written = vec![path.clone()];
        match args.to {
            Target::Unreal => written.push(unreal::script_path(path)),
            Target::Unity => written.push(path.with_extension("cs")),
            Target::Renderer(_) => {}
        }
        let inputs = ["params.json", "fit.json", "curves.csv"].map(|f| args.dir.join(f));
        let inputs: Vec<(&str, &std::path::Path)> =
            inputs.iter().map(|p| ("the fit", p.as_path())).collect();
        for out in &written {
            crate::atomic::refuse_replacing_inputs("--output", out, &inputs)?;
            refuse_inside_a_set(path, out)?;
        }
    }
    let verdict_warnings = crate::export::source::exportable(&args.dir, args.allow_failed)?;
    let (summary, text) = match args.to {
        Target::Renderer(renderer) => renderer_command(args, renderer),
        Target::Unreal => unreal_command(args),
        Target::Unity => unity_command(args).map(|summary| (summary, None)),
    }?;
    Ok((
        format!("{}{summary}", warning_lines(&verdict_warnings)),
        text,
    ))
}

/// An export written into a hairfit output set would be lost when the set is replaced (the next
/// `hairfit fit --out` there), or would overwrite one of its files: refused.
fn refuse_inside_a_set(output: &Path, written: &Path) -> Result<()> {
    let Some((dir, marker)) = crate::outdir::enclosing_set(written) else {
        return Ok(());
    };
    let name = written
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    Err(Error::Other(format!(
        "--output {}: {} lies inside {}, an output directory written by {}, which hairfit replaces as a whole; write the export outside it, e.g. --output exports/{name}",
        output.display(),
        written.display(),
        dir.display(),
        marker.command,
    )))
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

/// `--to unity`'s `--output`: required (two files cannot go to stdout), and the JSON's name,
/// not the script's.
fn unity_output(output: Option<&Path>) -> Result<&Path> {
    let json = output.ok_or_else(|| {
        Error::Other(
            "--to unity writes two files, NAME.json and the C# editor script NAME.cs beside it: \
             pass --output NAME.json"
                .into(),
        )
    })?;
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
    Ok(json)
}

/// `--to unity`: the JSON and the C# script beside it.
fn unity_command(args: &ExportArgs) -> Result<String> {
    let json = unity_output(args.output.as_deref())?;
    let script = json.with_extension("cs");
    let script_name = script
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let result = export_unity(&args.dir, &script_name)?;
    // Both or neither: a pair from two different fits would load without complaint.
    crate::atomic::write_together(&[
        (json, result.json.as_bytes()),
        (&script, result.script.as_bytes()),
    ])?;
    Ok(format!(
        "{}{}; wrote {} and {}",
        warning_lines(&result.warnings),
        result.summary,
        json.display(),
        script.display()
    ))
}
