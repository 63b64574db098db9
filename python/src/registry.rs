//! `families`, `export_targets`: the library's registry as Python sees it, so a program lists
//! what `model=` and `to=` take from the same list the command line's help is written from.

use pyo3::prelude::*;

use hairfit::export::Target;
use hairfit::families::ModelFamily;

/// One family: (its `model=` name, title, citation, its parameters' names, its `terms=` words
/// or None when it takes none).
type FamilyRow = (String, String, String, Vec<String>, Option<Vec<String>>);

/// Every family, in the registry's order (the first is the default `model=`).
#[pyfunction]
pub(crate) fn families() -> Vec<FamilyRow> {
    ModelFamily::ALL
        .iter()
        .map(|f| {
            let parameters = f.facts().parameters().iter();
            let terms = f
                .terms()
                .map(|t| t.iter().map(|t| t.name.to_string()).collect());
            (
                f.as_str().to_string(),
                f.title().to_string(),
                f.citation().to_string(),
                parameters.map(|p| p.name.to_string()).collect(),
                terms,
            )
        })
        .collect()
}

/// Every `to=` target of `export`: (its name, the program that loads it, the main file's
/// extension, what that file is).
#[pyfunction]
pub(crate) fn export_targets() -> Vec<(String, String, String, String)> {
    Target::all()
        .iter()
        .map(|t| {
            (
                t.name().to_string(),
                t.program().to_string(),
                t.extension().to_string(),
                t.file_kind().to_string(),
            )
        })
        .collect()
}
