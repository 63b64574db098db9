//! `hairfit export --to pbrt|blender|materialx`: the renderers that draw the Chiang model, each
//! with its own formulation ([`Formulation`]) FITTED to a fit's `S` (never converted by a
//! formula), written as a pbrt-v4 `MakeNamedMaterial` block, a Blender script creating a
//! Principled Hair BSDF, or a MaterialX document with a `chiang_hair_bsdf`, the mapping's error
//! in the file's header.
//!
//! - [`mapping`]: the least-squares fit of a renderer's variant to the source `S`;
//! - [`writers`]: the three file formats.

pub mod mapping;
pub mod writers;

use std::fmt;
use std::path::Path;

use super::family::ChiangEvaluation;
use super::variant::Formulation;
use super::ChiangFamily;
use crate::error::{Error, Result};
use crate::export::source::SourceFit;
use crate::export::{warning_lines, ExportTarget, FamilyTargets};
use crate::families::FamilyModel;

pub use mapping::{fit_mapping, Mapping};

/// The renderers that draw the Chiang model, in `--to`'s order.
impl FamilyTargets for ChiangFamily {
    fn targets() -> &'static [&'static dyn ExportTarget] {
        &[&Renderer::Pbrt, &Renderer::Blender, &Renderer::Materialx]
    }
}

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

impl ExportTarget for Renderer {
    fn name(&self) -> &'static str {
        match self {
            Renderer::Pbrt => "pbrt",
            Renderer::Blender => "blender",
            Renderer::Materialx => "materialx",
        }
    }

    fn aliases(&self) -> &'static [&'static str] {
        match self {
            Renderer::Pbrt => &["pbrt-v4"],
            Renderer::Blender => &["cycles"],
            Renderer::Materialx => &["mtlx"],
        }
    }

    fn program(&self) -> &'static str {
        match self {
            Renderer::Pbrt => "pbrt-v4",
            Renderer::Blender => "Blender Cycles",
            Renderer::Materialx => "MaterialX",
        }
    }

    fn extension(&self) -> &'static str {
        Renderer::extension(self)
    }

    fn file_name(&self) -> &'static str {
        Renderer::file_name(self)
    }

    fn file_kind(&self) -> &'static str {
        Renderer::file_kind(self)
    }

    /// One file: written atomically to `output`, or its text for stdout.
    fn run(&self, dir: &Path, output: Option<&Path>) -> Result<(String, Option<String>)> {
        let result = export(dir, *self)?;
        let warned = warning_lines(&result.warnings);
        match output {
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
}

impl fmt::Display for Renderer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
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
    let name = crate::export::text::material_name(&source);
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
