//! JSON files, read and written one way everywhere: a syntax or schema error names the file,
//! line and column and what the file is; a parameter file must be one object and is validated
//! after reading ([`ParameterFile`]); writes are pretty-printed and atomic. Below every module
//! that has a JSON format (parameter files, fit.json, compare.json).

use std::path::Path;

use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::atomic::write_atomically;
use crate::error::{Error, Result};

/// The text of `path`, which must be a regular file (or a link to one): a FIFO or device is
/// refused before it is opened, since reading one would wait forever or never end. A UTF-8
/// byte-order mark, which some editors write, is dropped.
pub fn read_text(path: &Path) -> Result<String> {
    check_regular_file(path)?;
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

/// An error unless `path` is a regular file (links followed): a FIFO, socket or device would
/// block or never end, and a directory is no file.
pub fn check_regular_file(path: &Path) -> Result<()> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_file() {
        return Ok(());
    }
    let what = if meta.is_dir() {
        "a directory"
    } else {
        "a FIFO, socket or device"
    };
    Err(Error::Other(format!(
        "{}: is {what}, not a regular file; hairfit reads this file whole, so give it a file (copy the content to one)",
        path.display()
    )))
}

/// Read a JSON file as `T`; a syntax or schema error names line and column, followed by `hint`
/// (what the file is and how to regenerate it).
pub fn read_json<T: DeserializeOwned>(path: &Path, hint: &str) -> Result<T> {
    let text = read_text(path)?;
    serde_json::from_str(&text).map_err(|e| json_error(path, e, hint))
}

/// Parse `text` (from `path`, for messages) as a JSON **object** of type `T`. serde would also
/// fill a struct from an array, by position; a parameter file written as an array is a
/// mistake, so anything but an object is refused where it starts.
pub fn parse_json_object<T: DeserializeOwned>(text: &str, path: &Path, hint: &str) -> Result<T> {
    if let Some((offset, c)) = text.char_indices().find(|(_, c)| !c.is_whitespace()) {
        if c != '{' {
            let line = text[..offset].matches('\n').count() as u64 + 1;
            let column = (offset - text[..offset].rfind('\n').map_or(0, |i| i + 1)) as u64 + 1;
            return Err(Error::input(
                path,
                line,
                column,
                format!("expected a JSON object `{{ … }}`, found `{c}`; {hint}"),
            ));
        }
    }
    serde_json::from_str(text).map_err(|e| json_error(path, e, hint))
}

/// A JSON parameter file: one object, checked after reading.
pub trait ParameterFile: DeserializeOwned {
    /// What the file holds, for error messages (its keys).
    fn hint() -> String;
    /// Check every value's domain.
    fn validate(&self) -> Result<()>;

    /// Read and validate `path`.
    fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = read_text(path)?;
        Self::from_json_str(&text, path)
    }

    /// Parse and validate JSON text; `path` only names the source in error messages.
    fn from_json_str(text: &str, path: impl AsRef<Path>) -> Result<Self> {
        let file: Self = parse_json_object(text, path.as_ref(), &Self::hint())?;
        file.validate()?;
        Ok(file)
    }
}

/// Write `value` as pretty-printed JSON plus a final newline, atomically. serde_json writes
/// a non-finite `f64` as `null`; the types here say where that can happen.
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<()> {
    write_atomically(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value)
            .map_err(|e| json_error(path, e, "cannot serialise"))?;
        w.write_all(b"\n").map_err(|e| Error::io(path, e))
    })
}

/// The one JSON error converter: syntax/schema errors at their line and column, I/O as I/O.
fn json_error(path: &Path, e: serde_json::Error, hint: &str) -> Error {
    if e.is_io() {
        return Error::Other(format!("{}: {e}", path.display()));
    }
    Error::json(path, &e, Some(hint))
}
