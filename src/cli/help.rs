//! The help text that names families and export targets, written from the lists the code uses
//! ([`ModelFamily::ALL`], [`Target::all`]) so a family or target added there shows in
//! `hairfit --help` without anyone editing a doc comment.

use clap::Command;

use super::compare::DEFAULT_MODELS;
use crate::export::Target;
use crate::families::ModelFamily;

/// `marschner: Marschner 2003; chiang: Chiang 2016 (pbrt-v4's hair); …`.
pub fn family_list() -> String {
    ModelFamily::ALL
        .map(|f| format!("{}: {}", f.as_str(), f.citation()))
        .join("; ")
}

/// `pbrt (pbrt-v4), blender (Blender Cycles), …`.
pub fn target_list() -> String {
    let targets = Target::all().iter();
    let each: Vec<String> = targets.map(|t| format!("{t} ({})", t.program())).collect();
    each.join(", ")
}

/// The command's one-line description.
pub fn about() -> String {
    let names = ModelFamily::ALL.map(ModelFamily::citation).join(", ");
    format!("Fit hair scattering models to fiber-scattering data: {names}")
}

/// `command` (the derived parser) with the family and target lists filled in.
pub fn with_registries(command: Command) -> Command {
    let families = family_list();
    let mut command = command.about(about());
    let subcommands: Vec<String> = command
        .get_subcommands()
        .map(|c| c.get_name().to_string())
        .collect();
    for name in subcommands {
        command = command.mut_subcommand(name, |sub| {
            if !sub.get_arguments().any(|a| a.get_id() == "family") {
                return sub;
            }
            sub.mut_arg("family", |a| {
                let own = a.get_help().map(|h| h.to_string()).unwrap_or_default();
                a.help(format!("{own}. One of {families}"))
            })
        });
    }
    let n = ModelFamily::ALL.len();
    command
        .mut_subcommand("compare", |c| {
            c.about(format!(
                "Fit several of the {n} model families to the same data and rank them \
                 (default {DEFAULT_MODELS}): DIR/<family>/, DIR/compare.json, DIR/index.html"
            ))
            .mut_arg("models", |a| {
                a.help(format!(
                    "Model families to fit and rank, comma-separated, or `all`. Families: {families}"
                ))
            })
        })
        .mut_subcommand("export", |c| {
            let programs: Vec<&str> = Target::all().iter().map(|t| t.program()).collect();
            let programs = programs.join(", ");
            c.about(format!(
                "Write what a renderer or engine loads ({programs}) from a fit, \
                 its model fitted to the fit's S"
            ))
            .mut_arg("to", |a| {
                let each: Vec<String> = (Target::all().iter())
                    .map(|t| format!("{t}: {}", t.file_kind()))
                    .collect();
                let each = each.join("; ");
                a.help(format!("Target, one of {}. {each}", target_list()))
            })
        })
}
