//! `hairfit export`: from a fit directory, the file a renderer loads — a pbrt-v4
//! `MakeNamedMaterial` block, a Blender script creating a Principled Hair BSDF (Chiang), a
//! MaterialX document with a `chiang_hair_bsdf` — with the renderer's own formulation FITTED to
//! the fit's `S` (never converted by a formula), and the mapping's error in the file's header.
//!
//! - [`source`]: what a fit directory holds (model, parameters, quality, measured directions);
//! - [`mapping`]: the least-squares fit of a renderer's variant to the source `S`;
//! - [`writers`]: the three file formats;
//! - [`unreal`]: Unreal Engine 5's hair material inputs (the Karis family) fitted the same way,
//!   written as a JSON file and a Python script beside it;
//! - [`unity`] (with [`log_fit`]): Unity HDRP's hair inputs, fitted through
//!   the frostbite family, as a JSON file and a C# editor script beside it.

pub mod log_fit;
pub mod mapping;
pub mod source;
pub mod unity;
pub mod unreal;
pub mod writers;

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use crate::error::{Error, Result};
use crate::families::chiang::family::ChiangEvaluation;
use crate::families::chiang::variant::Formulation;
use crate::families::FamilyModel;

pub use mapping::{dense_sphere, fit_mapping, Mapping};
pub use source::{SourceFit, SourceModel};

/// A renderer `hairfit export` writes for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Renderer {
    Pbrt,
    Blender,
    Materialx,
}

impl Renderer {
    /// How the renderer's `f` differs from pbrt-v4's (docs/chiang.md).
    pub fn formulation(&self) -> Formulation {
        match self {
            Renderer::Pbrt => Formulation::PBRT_V4,
            Renderer::Blender => Formulation::CYCLES,
            Renderer::Materialx => Formulation::MATERIALX,
        }
    }

    /// A file name of the renderer's kind, for hints (`hair.pbrt`).
    pub fn file_name(&self) -> &'static str {
        match self {
            Renderer::Pbrt => "hair.pbrt",
            Renderer::Blender => "hair.py",
            Renderer::Materialx => "hair.mtlx",
        }
    }

    /// Every renderer, in `--to`'s order.
    pub const ALL: [Renderer; 3] = [Renderer::Pbrt, Renderer::Blender, Renderer::Materialx];

    /// The extension of the file the renderer loads (without the dot).
    pub fn extension(&self) -> &'static str {
        match self {
            Renderer::Pbrt => "pbrt",
            Renderer::Blender => "py",
            Renderer::Materialx => "mtlx",
        }
    }

    /// What the written file is, for messages.
    pub fn file_kind(&self) -> &'static str {
        match self {
            Renderer::Pbrt => "a pbrt-v4 MakeNamedMaterial block",
            Renderer::Blender => "a Blender Python script",
            Renderer::Materialx => "a MaterialX document",
        }
    }

    /// Refuse an output file named with another export's extension ([`Target::check_output_name`]).
    pub fn check_output_name(&self, flag: &str, path: &Path) -> Result<()> {
        Target::Renderer(*self).check_output_name(flag, path)
    }

    /// The model a header names.
    pub fn model_name(&self) -> &'static str {
        match self {
            Renderer::Pbrt => "pbrt-v4 hair (Chiang 2016, tilt on theta_r)",
            Renderer::Blender => {
                "Blender Cycles Principled Hair BSDF, model Chiang (tilt on theta_i)"
            }
            Renderer::Materialx => "MaterialX chiang_hair_bsdf (tilt on theta_i, f/pi, tints)",
        }
    }
}

impl FromStr for Renderer {
    type Err = Error;
    fn from_str(s: &str) -> Result<Renderer> {
        match s.to_ascii_lowercase().as_str() {
            "pbrt" | "pbrt-v4" => Ok(Renderer::Pbrt),
            "blender" | "cycles" => Ok(Renderer::Blender),
            "materialx" | "mtlx" => Ok(Renderer::Materialx),
            other => Err(Error::Other(format!(
                "unknown renderer `{other}`: use --to {}",
                or_list(&Renderer::ALL.map(|r| r.to_string()))
            ))),
        }
    }
}

impl fmt::Display for Renderer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Renderer::Pbrt => "pbrt",
            Renderer::Blender => "blender",
            Renderer::Materialx => "materialx",
        })
    }
}

/// What `--to` names: a renderer of the Chiang model (one file), or a game engine whose own
/// hair model is fitted (a JSON file of its material inputs and a script beside it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    Renderer(Renderer),
    /// Unreal Engine 5's Hair shading model ([`unreal`]).
    Unreal,
    /// Unity HDRP's hair, Material Type Physical ([`unity`]).
    Unity,
}

impl Target {
    /// Every target, in `--to`'s order.
    pub const ALL: [Target; 5] = [
        Target::Renderer(Renderer::Pbrt),
        Target::Renderer(Renderer::Blender),
        Target::Renderer(Renderer::Materialx),
        Target::Unreal,
        Target::Unity,
    ];

    /// The renderer or engine that loads the file, for help ("pbrt-v4", "Unreal Engine 5").
    pub fn program(&self) -> &'static str {
        match self {
            Target::Renderer(Renderer::Pbrt) => "pbrt-v4",
            Target::Renderer(Renderer::Blender) => "Blender Cycles",
            Target::Renderer(Renderer::Materialx) => "MaterialX",
            Target::Unreal => "Unreal Engine 5",
            Target::Unity => "Unity HDRP",
        }
    }

    /// The extension of the (main) file written, without the dot.
    pub fn extension(&self) -> &'static str {
        match self {
            Target::Renderer(r) => r.extension(),
            Target::Unreal | Target::Unity => "json",
        }
    }

    /// A file name of the target's kind, for hints.
    pub fn file_name(&self) -> &'static str {
        match self {
            Target::Renderer(r) => r.file_name(),
            Target::Unreal | Target::Unity => "hair.json",
        }
    }

    /// What the written file is, for messages.
    pub fn file_kind(&self) -> &'static str {
        match self {
            Target::Renderer(r) => r.file_kind(),
            Target::Unreal => {
                "an Unreal material-parameter file (JSON; its Python script goes beside it)"
            }
            Target::Unity => {
                "a Unity HDRP hair material (JSON; its C# editor script goes beside it)"
            }
        }
    }

    /// Refuse an output file named with another target's extension (`--to pbrt --output
    /// hair.mtlx`): it would hold one format under another's name, which the tool opening it
    /// by that name rejects or misreads. Any other name (the target's own extension, another
    /// extension, none) is the user's choice.
    pub fn check_output_name(&self, flag: &str, path: &Path) -> Result<()> {
        let Some(ext) = path.extension().and_then(|e| e.to_str()) else {
            return Ok(());
        };
        if ext.eq_ignore_ascii_case(self.extension()) {
            return Ok(());
        }
        let others: Vec<Target> = (Target::ALL.into_iter())
            .filter(|t| ext.eq_ignore_ascii_case(t.extension()))
            .collect();
        let Some(other) = others.first() else {
            return Ok(());
        };
        let to: Vec<String> = others.iter().map(|t| format!("--to {t}")).collect();
        let to = to.join(" or ");
        Err(Error::Other(format!(
            "{flag} {}: .{ext} is the extension of {} ({to}), but --to {self} writes {}: \
             name the file {}, or pass {to}",
            path.display(),
            other.file_kind(),
            self.file_kind(),
            path.with_extension(self.extension()).display()
        )))
    }
}

impl FromStr for Target {
    type Err = Error;
    fn from_str(s: &str) -> Result<Target> {
        match s.to_ascii_lowercase().as_str() {
            "unreal" | "ue" | "ue5" => Ok(Target::Unreal),
            "unity" | "hdrp" => Ok(Target::Unity),
            other => other.parse().map(Target::Renderer).map_err(|_| {
                Error::Other(format!(
                    "unknown export target `{other}`: use --to {}",
                    or_list(&Target::ALL.map(|t| t.to_string()))
                ))
            }),
        }
    }
}

/// `a, b or c`.
fn or_list(names: &[String]) -> String {
    match names {
        [] => String::new(),
        [one] => one.clone(),
        [rest @ .., last] => format!("{} or {last}", rest.join(", ")),
    }
}

impl fmt::Display for Target {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Target::Renderer(r) => r.fmt(f),
            Target::Unreal => f.write_str("unreal"),
            Target::Unity => f.write_str("unity"),
        }
    }
}

/// One export: the file's text and the mapping it was written from.
#[derive(Debug, Clone)]
pub struct Export {
    pub renderer: Renderer,
    pub text: String,
    pub mapping: Mapping,
    /// One line for stderr: what was fitted and how well.
    pub summary: String,
    /// What the renderer cannot represent of the fit (also in the file's header).
    pub warnings: Vec<String>,
}

/// Export the fit in `dir` for `renderer`.
pub fn export(dir: &Path, renderer: Renderer) -> Result<Export> {
    let source = SourceFit::load(dir)?;
    let rgb_channels = source.rgb_order()?;
    let mapping = fit_mapping(&source, renderer.formulation())?;
    let warnings = unrepresentable(&source, renderer, &mapping);
    let header = writers::header_lines(&source, renderer, &mapping, &rgb_channels, &warnings);
    let name = writers::material_name(&source);
    let text = match renderer {
        Renderer::Pbrt => writers::pbrt(&name, &header, &mapping),
        Renderer::Blender => writers::blender(&name, &header, &mapping),
        Renderer::Materialx => writers::materialx(&name, &header, &mapping),
    };
    let summary = format!(
        "export to {renderer}: {} from the {} fit in {}: {}",
        renderer.model_name(),
        source.model.name(),
        dir.display(),
        mapping.quality_text()
    );
    Ok(Export {
        renderer,
        text,
        mapping,
        summary,
        warnings,
    })
}

/// Warnings for what the fit used and `renderer` cannot render: a Chiang fit with a term
/// switched off (every renderer renders R, TT, TRT and the residual), with the rms cost of
/// exporting the fit's parameters as they are and of the refitted parameters actually written.
pub fn unrepresentable(source: &SourceFit, renderer: Renderer, mapping: &Mapping) -> Vec<String> {
    let FamilyModel::Chiang(ChiangEvaluation { model, .. }) = &source.model.model else {
        return Vec::new();
    };
    let effects = model.effects;
    let Some((rms_as_is, max_as_is)) = mapping.as_fitted else {
        return Vec::new();
    };
    let terms = [
        (effects.r, "R"),
        (effects.tt, "TT"),
        (effects.trt, "TRT"),
        (effects.residual, "residual"),
    ];
    let list = |on: bool| {
        terms
            .iter()
            .filter(|(t, _)| *t == on)
            .map(|(_, n)| *n)
            .collect::<Vec<_>>()
            .join("+")
    };
    vec![format!(
        "the fit ran with terms {} only ({} switched off), but {renderer} always renders all four \
         (R, TT, TRT, residual) and cannot switch one off: the fit's parameters as they are would \
         miss the fit's S by rms |d ln S| {rms_as_is:.4} (max {max_as_is:.3}); the exported \
         parameters were refitted to the fit's S instead and miss it by rms |d ln S| {:.4} \
         (max {:.3}) over {} measured + {} sphere directions",
        list(true),
        list(false),
        mapping.rms_log,
        mapping.max_log,
        mapping.n_measured,
        mapping.n_sphere
    )]
}

/// Write `export.text` to `path` atomically.
pub fn write_export(path: &Path, export: &Export) -> Result<()> {
    crate::atomic::write_atomically(path, |w| {
        w.write_all(export.text.as_bytes())
            .map_err(|e| Error::io(path, e))
    })
}
