//! `hairfit export --to unreal`: Unreal Engine 5's Hair shading model inputs (Base Color,
//! Roughness, Specular, Backlit, Scatter) FITTED to the fit's `S` with one shared gain (the
//! light's intensity), never converted by formula — the same philosophy as the renderer exports.
//! The engine's BSDF is the Karis family ([`crate::families::karis`]); [`fit`] fits its
//! inputs, [`files`] writes the JSON of the inputs with the mapping's quality and the source fit,
//! and a Python script that creates a material instance of a hair material in the editor.

pub mod files;
pub mod fit;

use std::path::{Path, PathBuf};

use super::Karis;
use crate::error::Result;
use crate::export::source::SourceFit;
use crate::export::{warning_lines, ExportTarget, FamilyTargets};
pub use fit::{fit_engine, EngineInputs, EngineMapping};

/// `--to unreal`: the engine draws the Karis model.
impl FamilyTargets for Karis {
    fn targets() -> &'static [&'static dyn ExportTarget] {
        &[&Unreal]
    }
}

/// Unreal Engine 5's Hair shading model: a JSON file of its inputs and a Python script beside it.
pub struct Unreal;

impl ExportTarget for Unreal {
    fn name(&self) -> &'static str {
        "unreal"
    }

    fn aliases(&self) -> &'static [&'static str] {
        &["ue", "ue5"]
    }

    fn program(&self) -> &'static str {
        "Unreal Engine 5"
    }

    fn extension(&self) -> &'static str {
        "json"
    }

    fn file_name(&self) -> &'static str {
        "hair.json"
    }

    fn file_kind(&self) -> &'static str {
        "an Unreal material-parameter file (JSON; its Python script goes beside it)"
    }

    fn companion(&self, output: &Path) -> Option<PathBuf> {
        Some(script_path(output))
    }

    /// The JSON (stdout without an output) and, with one, the script beside it.
    fn run(&self, dir: &Path, output: Option<&Path>) -> Result<(String, Option<String>)> {
        let result = export(dir)?;
        let warned = warning_lines(&result.warnings);
        match output {
            Some(path) => {
                write_files(path, &result)?;
                Ok((
                    format!(
                        "{warned}{}; wrote {} and {}",
                        result.summary,
                        path.display(),
                        script_path(path).display()
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
}

/// The engine versions whose conventions the export follows.
pub const ENGINE_VERSION: &str = "Unreal Engine 5.0-5.3";

/// The engine's model as the files name it.
pub const MODEL_NAME: &str = "Unreal Engine 5 Hair shading model (Karis 2016)";

/// The parent material's parameters: (name, what it feeds, Vector or Scalar Parameter).
pub const PARAMETERS: [(&str, &str, &str); 5] = [
    ("BaseColor", "Base Color", "Vector Parameter (linear RGB)"),
    ("Roughness", "Roughness", "Scalar Parameter"),
    ("Specular", "Specular", "Scalar Parameter"),
    ("Backlit", "Backlit (Custom Data 0)", "Scalar Parameter"),
    ("Scatter", "Scatter (the Metallic slot)", "Scalar Parameter"),
];

/// Below this Roughness UE 5.4+ clamps the lobes' normaliser (B ≥ 0.01), so they render
/// dimmer than 5.0-5.3 do.
pub const CLAMPED_ROUGHNESS: f64 = 0.1;

/// One Unreal export: the JSON text, the script, and the mapping they were written from.
#[derive(Debug, Clone)]
pub struct UnrealExport {
    pub json: String,
    pub script: String,
    pub mapping: EngineMapping,
    /// The channel names in R, G, B order (one: grey).
    pub channels: Vec<String>,
    /// One line for stderr: what was fitted and how well.
    pub summary: String,
    /// What the engine cannot represent of the fit (also in both files).
    pub warnings: Vec<String>,
}

/// Export the fit in `dir` to Unreal.
pub fn export(dir: &Path) -> Result<UnrealExport> {
    let source = SourceFit::load(dir)?;
    let channels = source.rgb_order()?;
    let mapping = fit_engine(&source)?;
    let warnings = warnings(&mapping);
    let json = files::json(&source, &mapping, &channels, &warnings);
    let script = files::script(&source, &mapping, &warnings);
    let summary = format!(
        "export to unreal: {MODEL_NAME}, {ENGINE_VERSION} conventions, from the {} fit in {}: {}",
        source.model.name(),
        dir.display(),
        mapping.quality_text()
    );
    Ok(UnrealExport {
        json,
        script,
        mapping,
        channels,
        summary,
        warnings,
    })
}

/// What the user should know the engine does with these inputs that the fit did not see.
pub fn warnings(m: &EngineMapping) -> Vec<String> {
    let mut out = Vec::new();
    if let Some((rms, max)) = m.as_fitted.filter(|(rms, _)| *rms > 1e-9) {
        out.push(format!(
            "the Karis fit's own parameters are not what the engine renders (its eta or cuticle \
             shift differ from the engine's 1.55 and 0.035 rad, or a term it ran without is \
             nonzero): as they are they would miss the fit's S by rms |d ln S| {rms:.4} (max \
             {max:.3}); the inputs written were refitted and miss it by rms {:.4} (max {:.3})",
            m.errors.rms, m.errors.max
        ));
    }
    // A Scatter whose removal costs less than this much rms is not worth a warning.
    const NOTICEABLE: f64 = 1e-3;
    if let Some((rms, max)) = m
        .without_scatter
        .filter(|(rms, _)| rms - m.errors.rms >= NOTICEABLE)
    {
        out.push(format!(
            "Scatter {:.4} is applied to hair cards and meshes only: hair strands ignore it and \
             would miss the fit's S by rms |d ln S| {rms:.4} (max {max:.3})",
            m.inputs.scatter
        ));
    }
    if m.inputs.backlit < 1.0 - NOTICEABLE {
        out.push(format!(
            "Backlit {:.4}: Unreal 5.0-5.3 applies Backlit on hair strands only (cards and meshes \
             render it as 1)",
            m.inputs.backlit
        ));
    }
    if m.inputs.roughness < CLAMPED_ROUGHNESS {
        out.push(format!(
            "Roughness {:.4} < {CLAMPED_ROUGHNESS}: Unreal 5.4 and later clamp the lobes' \
             normaliser there and render them dimmer than 5.0-5.3 (and this export) do",
            m.inputs.roughness
        ));
    }
    out
}

/// Write `export` to `path` (the JSON) and the script beside it ([`script_path`]): both or
/// neither, so the pair always comes from one fit.
pub fn write_files(path: &Path, export: &UnrealExport) -> Result<()> {
    crate::atomic::write_together(&[
        (path, export.json.as_bytes()),
        (&script_path(path), export.script.as_bytes()),
    ])
}

/// The script written beside the JSON `path`: the same name with `.py`.
pub fn script_path(path: &Path) -> PathBuf {
    path.with_extension("py")
}
