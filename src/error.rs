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

/// A size in bytes for a message, in the largest binary unit it reaches (bytes, KiB, MiB, GiB,
/// TiB) with up to one decimal: `512 bytes`, `6.2 KiB`, `64 MiB`, `1.5 GiB`. Every message that
/// states a size uses this, so small sizes stay readable (never "0.0 GB").
pub fn readable_bytes(bytes: u64) -> String {
    const UNITS: [&str; 4] = ["KiB", "MiB", "GiB", "TiB"];
    if bytes < 1024 {
        return format!("{bytes} byte{}", if bytes == 1 { "" } else { "s" });
    }
    let mut value = bytes as f64 / 1024.0;
    let mut unit = 0;
    while value >= 1023.95 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    let text = format!("{value:.1}");
    let text = text.strip_suffix(".0").unwrap_or(&text);
    format!("{text} {}", UNITS[unit])
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

    /// A JSON syntax or schema error in `path` at serde_json's line and column (from 1: serde_json
    /// says column 0 at the end of an empty file), with its message less serde_json's own
    /// ` at line L column C`, and then `; hint` when a hint is given.
    pub fn json(path: impl Into<PathBuf>, e: &serde_json::Error, hint: Option<&str>) -> Self {
        let text = e.to_string();
        let message = text
            .rsplit_once(" at line ")
            .map_or(text.as_str(), |(m, _)| m);
        let message = match hint {
            Some(hint) => format!("{message}; {hint}"),
            None => message.to_string(),
        };
        Error::input(
            path,
            e.line().max(1) as u64,
            e.column().max(1) as u64,
            message,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::{readable_bytes, Error};

    /// Positions count from 1 and serde_json's own position is not said twice.
    #[test]
    fn json_errors_name_a_position_from_one_and_say_it_once() {
        let at = |text: &str| {
            let e = serde_json::from_str::<serde_json::Value>(text).unwrap_err();
            Error::json("p.json", &e, Some("hint")).to_string()
        };
        assert_eq!(at(""), "p.json:1:1: EOF while parsing a value; hint");
        assert_eq!(
            at("{\"a\": 1,\n  x}"),
            "p.json:2:3: key must be a string; hint"
        );
        assert_eq!(
            at("{\"a\": 1,\n"),
            "p.json:2:1: EOF while parsing a value; hint"
        );
    }

    #[test]
    fn sizes_read_in_their_own_unit() {
        assert_eq!(readable_bytes(0), "0 bytes");
        assert_eq!(readable_bytes(1), "1 byte");
        assert_eq!(readable_bytes(1023), "1023 bytes");
        assert_eq!(readable_bytes(1024), "1 KiB");
        assert_eq!(readable_bytes(6336), "6.2 KiB");
        assert_eq!(readable_bytes(64 << 20), "64 MiB");
        assert_eq!(readable_bytes((1 << 20) - 1), "1 MiB");
        assert_eq!(readable_bytes(3 << 29), "1.5 GiB");
        assert_eq!(readable_bytes(5 << 40), "5 TiB");
        assert_eq!(readable_bytes(u64::MAX), "16777216 TiB");
    }
}
