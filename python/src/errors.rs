//! Errors: the `HairfitError` exception, error chains as the CLI prints them, and warnings.

use std::path::Path;

use pyo3::create_exception;
use pyo3::exceptions::{PyUserWarning, PyValueError};
use pyo3::prelude::*;

create_exception!(
    _native,
    HairfitError,
    PyValueError,
    "An error hairfit reports about its input (file:line:column where it has one); the message \
     is what the `hairfit` command line prints after `hairfit: error: ` for the same input."
);

/// An error and its causes joined by `: `, each said once: `error_text` of src/main.rs, so the
/// exception says what the CLI prints.
pub(crate) fn error_text(err: &(dyn std::error::Error + 'static)) -> String {
    let mut text = String::new();
    let mut cause = Some(err);
    while let Some(c) = cause {
        let part = c.to_string();
        if !text.ends_with(&part) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&part);
        }
        cause = c.source();
    }
    text
}

pub(crate) fn hf(err: hairfit::Error) -> PyErr {
    HairfitError::new_err(error_text(&err))
}

/// src/main.rs's `name_parameter_file`: a domain error says which file it is in.
pub(crate) fn name_parameter_file(err: hairfit::Error, path: &Path) -> String {
    match err {
        hairfit::Error::Parameter { .. } => {
            format!("in parameter file {}: {}", path.display(), error_text(&err))
        }
        other => error_text(&other),
    }
}

pub(crate) fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    let text = std::ffi::CString::new(message.replace('\0', " ")).unwrap_or_default();
    PyErr::warn(py, &py.get_type::<PyUserWarning>(), &text, 2)
}
