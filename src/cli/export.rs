//! `hairfit export`'s options: the fit directory, the target (a renderer or an engine), the
//! output file(s).

use std::path::{Path, PathBuf};

use clap::Args;

use crate::error::{Error, Result};
use crate::export::{warning_lines, Target};

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
    args.to.check_output(args.output.as_deref())?;
    if let Some(path) = &args.output {
        crate::atomic::refuse_directory_output("--output", path, args.to.file_name())?;
        args.to.check_output_name("--output", path)?;
        let mut written = vec![path.clone()];
        written.extend(args.to.companion(path));
        let inputs = ["params.json", "fit.json", "curves.csv"].map(|f| args.dir.join(f));
        let inputs: Vec<(&str, &std::path::Path)> =
            inputs.iter().map(|p| ("the fit", p.as_path())).collect();
        for out in &written {
            crate::atomic::refuse_replacing_inputs("--output", out, &inputs)?;
            refuse_inside_a_set(path, out)?;
        }
    }
    let verdict_warnings = crate::export::source::exportable(&args.dir, args.allow_failed)?;
    let (summary, text) = args.to.run(&args.dir, args.output.as_deref())?;
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
