//! `hairfit export`: from a fit directory, the files a renderer or engine loads, with the
//! program's own hair model FITTED to the fit's `S` (never converted by a formula) and the
//! mapping's error in the files. A target ([`ExportTarget`]) belongs to the family whose model
//! the program draws and lives in that family's folder (`families/<name>/export/`); the list
//! `--to` takes ([`Target::all`]) is read from the registry.
//!
//! - [`source`]: what a fit directory holds (model, parameters, quality, measured directions);
//! - [`reference`]: what every target fits to (the source's `S` over measured directions and a
//!   dense sphere) and the least-squares run;
//! - [`log_fit`]: the log-`S` fit of a target whose model is not a variant of the source's;
//! - [`text`]: numbers, colours and names as the targets' files write them.

pub mod log_fit;
pub mod reference;
pub mod source;
pub mod text;

use std::fmt;
use std::marker::PhantomData;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::OnceLock;

use crate::error::{Error, Result};

pub use reference::dense_sphere;
pub use source::{SourceFit, SourceModel};

/// One `--to` target: a renderer or engine whose hair model is a family's, fitted to a fit's `S`
/// and written in the program's format. Implemented in that family's `export` folder.
pub trait ExportTarget: Sync {
    /// Its `--to` name (`pbrt`).
    fn name(&self) -> &'static str;
    /// Other spellings `--to` accepts (`pbrt-v4`).
    fn aliases(&self) -> &'static [&'static str];
    /// The renderer or engine that loads the file, for help ("pbrt-v4", "Unreal Engine 5").
    fn program(&self) -> &'static str;
    /// The extension of the (main) file written, without the dot.
    fn extension(&self) -> &'static str;
    /// A file name of the target's kind, for hints (`hair.pbrt`).
    fn file_name(&self) -> &'static str;
    /// What the written file is, for messages.
    fn file_kind(&self) -> &'static str;
    /// The file written beside `output` (a script that loads it), if the target writes one.
    fn companion(&self, _output: &Path) -> Option<PathBuf> {
        None
    }
    /// `--output` checked before anything is fitted (fitting takes a while).
    fn check_output(&self, _output: Option<&Path>) -> Result<()> {
        Ok(())
    }
    /// Fit the target to the fit in `dir` and write its files to `output` (all or nothing), or
    /// return the main file's text for stdout: (the summary line for stderr, that text).
    fn run(&self, dir: &Path, output: Option<&Path>) -> Result<(String, Option<String>)>;
}

/// The targets of a family's model, implemented in its `export` folder; a family without one
/// implements nothing.
pub trait FamilyTargets {
    fn targets() -> &'static [&'static dyn ExportTarget];
}

/// What `--to` names: one of [`Target::all`].
#[derive(Clone, Copy)]
pub struct Target(pub &'static dyn ExportTarget);

/// A family's targets, or none when its type does not implement [`FamilyTargets`] (so a family
/// without targets writes nothing): method lookup on `&TargetsProbe<T>` takes
/// [`ProbeTargets`] when `T: FamilyTargets` holds and otherwise falls back, one autoref later,
/// to [`ProbeNoTargets`] (autoref specialisation).
struct TargetsProbe<T>(PhantomData<T>);

trait ProbeTargets {
    fn targets(&self) -> &'static [&'static dyn ExportTarget];
}

impl<T: FamilyTargets> ProbeTargets for TargetsProbe<T> {
    fn targets(&self) -> &'static [&'static dyn ExportTarget] {
        T::targets()
    }
}

trait ProbeNoTargets {
    fn targets(&self) -> &'static [&'static dyn ExportTarget] {
        &[]
    }
}

impl<T> ProbeNoTargets for &TargetsProbe<T> {}

/// [`registry_targets`]: every family's targets, in the registry's order.
macro_rules! registry_targets {
    ($($variant:ident => $kind:ident($ty:path)),* $(,)?) => {
        fn registry_targets() -> Vec<Target> {
            let mut all = Vec::new();
            $(all.extend((&TargetsProbe::<$ty>(PhantomData)).targets().iter().map(|t| Target(*t)));)*
            all
        }
    };
}
crate::families::registry!(registry_targets);

impl Target {
    /// Every target, in `--to`'s order: each family's, in the registry's order.
    pub fn all() -> &'static [Target] {
        static ALL: OnceLock<Vec<Target>> = OnceLock::new();
        ALL.get_or_init(registry_targets)
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
        let others: Vec<Target> = (Target::all().iter())
            .filter(|t| ext.eq_ignore_ascii_case(t.extension()))
            .copied()
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

impl std::ops::Deref for Target {
    type Target = dyn ExportTarget;
    fn deref(&self) -> &(dyn ExportTarget + 'static) {
        self.0
    }
}

impl PartialEq for Target {
    fn eq(&self, other: &Target) -> bool {
        self.name() == other.name()
    }
}

impl Eq for Target {}

impl fmt::Debug for Target {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Target({})", self.name())
    }
}

impl fmt::Display for Target {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Target {
    type Err = Error;
    fn from_str(s: &str) -> Result<Target> {
        let s = s.to_ascii_lowercase();
        let found = Target::all()
            .iter()
            .find(|t| t.name() == s || t.aliases().contains(&s.as_str()));
        found.copied().ok_or_else(|| {
            let names: Vec<String> = Target::all().iter().map(|t| t.to_string()).collect();
            Error::Other(format!(
                "unknown export target `{s}`: use --to {}",
                or_list(&names)
            ))
        })
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

/// Warnings first, each on its own line (main prefixes the first with `hairfit: `).
pub fn warning_lines(warnings: &[String]) -> String {
    warnings
        .iter()
        .map(|w| format!("warning: {w}\nhairfit: "))
        .collect()
}
