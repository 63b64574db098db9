//! The library's error type: every error that comes from user input says where (file, line,
//! column) and what to do about it.

use std::path::PathBuf;

/// Result alias used across the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors hairfit reports to its user.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Malformed input at a known place in a file (line and column are 1-based).
    #[error("{}:{line}:{column}: {message}", file.display())]
    Input {
        file: PathBuf,
        line: u64,
        column: u64,
        message: String,
    },
    /// A parameter outside its valid domain.
    #[error("parameter `{name}` = {} is invalid: {message}", readable(*value))]
    Parameter {
        name: String,
        value: f64,
        message: String,
    },
    /// An I/O failure on a named file.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Anything else, with a message that says what to do.
    #[error("{0}")]
    Other(String),
}

/// A number for a message: every digit of an ordinary value, exponent form for extreme ones
/// (1e200, not 201 digits).
pub fn readable(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e15).contains(&x.abs()) {
        x.to_string()
    } else {
        format!("{x:e}")
    }
}

impl Error {
    /// An input error at `file:line:column`.
    pub fn input(
        file: impl Into<PathBuf>,
        line: u64,
        column: u64,
        message: impl Into<String>,
    ) -> Self {
        Error::Input {
            file: file.into(),
            line,
            column,
            message: message.into(),
        }
    }

    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}
