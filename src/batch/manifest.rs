//! The batch manifest: a CSV (header `name,data`, then columns named after `hairfit fit`
//! options without their dashes) or a JSON array of objects with the same keys. Each item
//! becomes the argument list of one `hairfit fit` run, checked by the fit's own parser.

use std::path::{Path, PathBuf};

use clap::Parser;

use crate::cli::fit::FitCommandArgs;
use crate::error::{Error, Result};

mod fit_words;

pub use fit_words::{as_manifest_words, FitCommandLine, REPEAT_SEPARATOR};
use fit_words::{check_fit_words, check_key, fit_options, option_words, unknown_column, FitOption};

/// One fit of the manifest.
#[derive(Debug, Clone, PartialEq)]
pub struct Item {
    /// Output sub-directory name, unique in the manifest.
    pub name: String,
    /// Line of the manifest the item is on (1-based; the element index + 1 for JSON).
    pub line: u64,
    /// The `data` cell as the manifest writes it (summary.csv shows this text).
    pub data: String,
    /// `hairfit fit` arguments without `--out`: the data path (relative to the manifest's
    /// directory, as a user in the current directory would type it) and the options.
    pub argv: Vec<String>,
    /// The item's `fix` cell as written, and its column (CSV; JSON names the key), for an
    /// error found once the data's channels are known ([`Manifest::check_channels`]).
    pub fix: Option<(u64, String)>,
}

impl Item {
    /// The parsed `hairfit fit` arguments writing into `out` (`strict`: `hairfit batch
    /// --strict`, a run-level option every item then gets).
    pub fn fit_args(&self, out: &Path, strict: bool) -> Result<FitCommandArgs> {
        let mut argv = self.argv.clone();
        if strict {
            argv.push("--strict".into());
        }
        argv.push("--out".into());
        argv.push(out.display().to_string());
        FitCommandLine::try_parse_from(&argv)
            .map(|c| c.args)
            .map_err(|e| Error::Other(format!("item `{}`: {}", self.name, e.render())))
    }

    /// The fit options without the data path (what a re-run compares).
    pub fn options(&self) -> &[String] {
        &self.argv[1..]
    }
}

/// Where a manifest error is: CSV line and column, or JSON item and key.
#[derive(Debug, Clone, Copy)]
struct Place<'a> {
    json: bool,
    /// CSV line, or JSON item number (1-based).
    line: u64,
    column: u64,
    key: &'a str,
}

impl Place<'_> {
    fn error(&self, path: &Path, message: impl Into<String>) -> Error {
        let message = message.into();
        if !self.json {
            return Error::input(path, self.line, self.column, message);
        }
        let key = if self.key.is_empty() {
            String::new()
        } else {
            format!(", key `{}`", self.key)
        };
        Error::Other(format!(
            "{}: item {}{key}: {message}",
            path.display(),
            self.line
        ))
    }
}

/// Item names `hairfit batch` writes itself into `--out` (case-insensitive: some file systems
/// are).
pub const RESERVED_NAMES: [&str; 4] = ["summary.csv", "index.html", ".batch", ".hairfit"];

/// A loaded manifest.
#[derive(Debug, Clone)]
pub struct Manifest {
    pub path: PathBuf,
    pub items: Vec<Item>,
}

/// A manifest cell: its position and text.
struct Cell<'a> {
    column: u64,
    key: &'a str,
    value: String,
}

impl Manifest {
    /// Read a manifest (`.json` by extension, CSV otherwise); every error names the manifest's
    /// line and column (JSON: item and key) and what to write instead. Every item's options
    /// are checked here, before anything runs.
    pub fn load(path: &Path) -> Result<Manifest> {
        let text = crate::json_file::read_text(path)?;
        let json = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        let options = fit_options();
        let rows = if json {
            json_rows(path, &text, &options)?
        } else {
            csv_rows(path, &text, &options)?
        };
        let base = path.parent().unwrap_or(Path::new(""));
        let mut items: Vec<Item> = Vec::with_capacity(rows.len());
        for (line, cells) in rows {
            let item = item_from_cells(path, json, base, &options, line, &cells)?;
            if let Some(first) = items
                .iter()
                .find(|i| i.name.eq_ignore_ascii_case(&item.name))
            {
                let earlier = if json {
                    format!("item {}", first.line)
                } else {
                    format!("line {}", first.line)
                };
                let place = Place {
                    json,
                    line,
                    column: 1,
                    key: "name",
                };
                return Err(place.error(
                    path,
                    format!(
                        "item name `{}` is already used by {earlier} (names are output directories and must differ, ignoring case)",
                        item.name
                    ),
                ));
            }
            items.push(item);
        }
        if items.is_empty() {
            return Err(Error::input(path, 1, 1, "the manifest lists no items"));
        }
        Ok(Manifest {
            path: path.to_path_buf(),
            items,
        })
    }

    /// Check each item `shard` owns against its data's channels, before any item runs: a
    /// `fix` of `sigma_a[k]` that names a channel the data do not have is an error at the
    /// `fix` cell's line and column. Only data whose channels are known without loading them
    /// are checked (a CSV header, a scan's `columns`: [`crate::data::channels_without_loading`]);
    /// a JSON dataset's channels need the whole file, so its item finds out when it runs.
    pub fn check_channels(&self, shard: super::Shard) -> Result<()> {
        let json = self
            .path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        for (i, item) in self.items.iter().enumerate() {
            let Some((column, cell)) = &item.fix else {
                continue;
            };
            if !shard.owns(i) {
                continue;
            }
            let Ok(args) = item.fit_args(Path::new("x"), false) else {
                continue; // checked by load; the item's run reports it
            };
            let Some(channels) = crate::data::channels_without_loading(&args.data, &args.load)
            else {
                continue;
            };
            if let Err(e) = args.fit.check_fixes(channels.len()) {
                let place = Place {
                    json,
                    line: item.line,
                    column: *column,
                    key: "fix",
                };
                return Err(place.error(
                    &self.path,
                    format!(
                        "`fix` = `{cell}`: {e} (item `{}`: its data {} has the channel{} {})",
                        item.name,
                        item.data,
                        if channels.len() == 1 { "" } else { "s" },
                        channels.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// A manifest row: its line and its (column name, cell) pairs.
type Row = (u64, Vec<(String, String)>);

fn csv_rows(path: &Path, text: &str, options: &[FitOption]) -> Result<Vec<Row>> {
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let header_line = reader
        .headers()
        .map_err(|e| csv_error(path, e))?
        .position()
        .map_or(1, |p| p.line());
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| csv_error(path, e))?
        .iter()
        .map(str::to_string)
        .collect();
    if header.len() < 2 || header[0] != "name" || header[1] != "data" {
        return Err(Error::input(
            path,
            header_line,
            1,
            format!(
                "the header must start with `name,data` (found `{}`), then optional columns named after `hairfit fit` options without their dashes, e.g. `name,data,loss,mode,fix`",
                header.join(",")
            ),
        ));
    }
    // The header's own mistakes point at the header, before any item.
    for (i, key) in header.iter().enumerate() {
        let at = |m: String| Error::input(path, header_line, i as u64 + 1, m);
        if let Some(m) = check_key(key, options, false) {
            return Err(at(m));
        }
        if header[..i].contains(key) {
            return Err(at(format!(
                "column `{key}` appears twice; give it once (repeated values go in one cell, separated by `;`)"
            )));
        }
    }
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| csv_error(path, e))?;
        let line = record.position().map_or(0, |p| p.line());
        let cells = header
            .iter()
            .zip(record.iter())
            .map(|(k, v)| (k.clone(), v.to_string()))
            .collect();
        rows.push((line, cells));
    }
    Ok(rows)
}

fn csv_error(path: &Path, e: csv::Error) -> Error {
    let line = e.position().map_or(1, |p| p.line());
    Error::input(path, line, 1, format!("not a valid CSV manifest: {e}"))
}

fn json_rows(path: &Path, text: &str, options: &[FitOption]) -> Result<Vec<Row>> {
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| Error::json(path, &e, None))?;
    let array = value.as_array().ok_or_else(|| {
        Error::Other(format!(
            "{}: a JSON manifest is an array of objects like {{\"name\": \"a\", \"data\": \"a.csv\", \"loss\": \"cauchy\"}}",
            path.display()
        ))
    })?;
    let mut rows = Vec::new();
    for (i, element) in array.iter().enumerate() {
        let at = i as u64 + 1;
        let place = |key| Place {
            json: true,
            line: at,
            column: 0,
            key,
        };
        let object = element
            .as_object()
            .ok_or_else(|| place("").error(path, "not an object"))?;
        let mut cells = Vec::new();
        for (key, v) in object {
            if let Some(m) = check_key(key, options, true) {
                return Err(place(key).error(path, m));
            }
            let text = match v {
                serde_json::Value::String(s) => s.clone(),
                serde_json::Value::Bool(b) => b.to_string(),
                serde_json::Value::Number(n) => n.to_string(),
                serde_json::Value::Null => String::new(),
                serde_json::Value::Array(values) => values
                    .iter()
                    .map(|x| match x {
                        serde_json::Value::String(s) => s.clone(),
                        other => other.to_string(),
                    })
                    .collect::<Vec<_>>()
                    .join(&REPEAT_SEPARATOR.to_string()),
                serde_json::Value::Object(_) => {
                    return Err(place(key)
                        .error(path, "an object; give a string, number, boolean or array"))
                }
            };
            cells.push((key.clone(), text));
        }
        // `name` and `data` first, as in the CSV form.
        cells.sort_by_key(|(k, _)| match k.as_str() {
            "name" => 0,
            "data" => 1,
            _ => 2,
        });
        rows.push((at, cells));
    }
    Ok(rows)
}

fn item_from_cells(
    path: &Path,
    json: bool,
    base: &Path,
    options: &[FitOption],
    line: u64,
    cells: &[(String, String)],
) -> Result<Item> {
    let cells: Vec<Cell> = cells
        .iter()
        .enumerate()
        .map(|(i, (k, v))| Cell {
            column: i as u64 + 1,
            key: k,
            value: v.clone(),
        })
        .collect();
    let place = |column, key| Place {
        json,
        line,
        column,
        key,
    };
    let find = |key: &str| cells.iter().find(|c| c.key == key);
    let name = find("name").map(|c| c.value.clone()).unwrap_or_default();
    check_name(&name).map_err(|m| place(1, "name").error(path, m))?;
    let data = find("data").map(|c| c.value.clone()).unwrap_or_default();
    if data.is_empty() {
        return Err(place(2, "data").error(path, format!("item `{name}` has no data file")));
    }
    let data_path = if Path::new(&data).is_absolute() {
        PathBuf::from(&data)
    } else {
        base.join(&data)
    };
    let mut argv = vec![data_path.display().to_string()];
    // A family's own options (`terms`, `width-nodes`, …) are valid only with its `model`, so a
    // cell is checked alone together with the item's model cell.
    let model_words: Vec<String> = match (find("model"), options.iter().find(|o| o.long == "model"))
    {
        (Some(cell), Some(option)) => option_words(option, &cell.value).unwrap_or_default(),
        _ => Vec::new(),
    };
    for cell in cells.iter().filter(|c| c.key != "name" && c.key != "data") {
        let at = place(cell.column, cell.key);
        let Some(option) = options.iter().find(|o| o.long == cell.key) else {
            return Err(at.error(path, unknown_column(cell.key, options, json)));
        };
        let words = option_words(option, &cell.value)
            .map_err(|m| at.error(path, format!("`{}`: {m}", cell.key)))?;
        // Check each cell alone so an error points at its column.
        let mut alone = vec![argv[0].clone()];
        if cell.key != "model" {
            alone.extend(model_words.iter().cloned());
        }
        alone.extend(words.iter().cloned());
        check_fit_words(&alone)
            .map_err(|m| at.error(path, format!("`{}` = `{}`: {m}", cell.key, cell.value)))?;
        argv.extend(words);
    }
    // The options together (e.g. a conflict between two columns).
    check_fit_words(&argv).map_err(|m| {
        place(1, "").error(path, format!("item `{name}`: {}", as_manifest_words(&m)))
    })?;
    let fix = find("fix")
        .filter(|c| !c.value.trim().is_empty())
        .map(|c| (c.column, c.value.clone()));
    Ok(Item {
        name,
        line,
        data,
        argv,
        fix,
    })
}

fn check_name(name: &str) -> std::result::Result<(), String> {
    let ok = !name.is_empty()
        && name.len() <= 100
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-'));
    if !ok {
        return Err(format!(
            "item name `{name}` is not a plain directory name: use 1–100 letters, digits, `.`, `_` or `-`, not starting with `.`"
        ));
    }
    if RESERVED_NAMES.iter().any(|r| r.eq_ignore_ascii_case(name)) {
        return Err(format!(
            "item name `{name}` is reserved: `hairfit batch` writes {} in --out itself; choose another name",
            RESERVED_NAMES.join(", ")
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str, ext: &str) -> Result<Manifest> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(format!("m.{ext}"));
        std::fs::write(&path, text).unwrap();
        Manifest::load(&path)
    }

    #[test]
    fn csv_items_become_fit_arguments() {
        let m = load(
            "name,data,loss,fix,no-glints\na,a.csv,cauchy,eta=1.5;k_g=2,true\nb,/abs/b.csv,,,false\n",
            "csv",
        )
        .unwrap();
        assert_eq!(m.items.len(), 2);
        let a = &m.items[0];
        assert!(
            a.argv[0].ends_with("a.csv") && a.argv[0] != "a.csv",
            "{:?}",
            a.argv
        );
        assert_eq!(
            &a.argv[1..],
            [
                "--loss",
                "cauchy",
                "--fix",
                "eta=1.5",
                "--fix",
                "k_g=2",
                "--no-glints"
            ]
        );
        assert_eq!(m.items[1].argv, vec!["/abs/b.csv".to_string()]);
        assert_eq!(m.items[1].line, 3);
    }

    #[test]
    fn json_items_match_the_csv_form() {
        let m = load(
            r#"[{"data": "a.csv", "name": "a", "loss": "cauchy", "fix": ["eta=1.5", "k_g=2"], "no-glints": true}]"#,
            "json",
        )
        .unwrap();
        // JSON objects are unordered: options come in key order, which means the same fit.
        assert_eq!(
            &m.items[0].argv[1..],
            [
                "--fix",
                "eta=1.5",
                "--fix",
                "k_g=2",
                "--loss",
                "cauchy",
                "--no-glints"
            ]
        );
    }

    #[test]
    fn errors_name_line_and_column() {
        // A misspelt column is the header's mistake: line 1.
        let e = load("name,data,los\na,a.csv,cauchy\n", "csv").unwrap_err();
        let s = e.to_string();
        assert!(s.contains(":1:3:") && s.contains("`los`"), "{s}");
        assert!(s.contains("(did you mean `loss`?)"), "{s}");
        // A name like none of the options gets no guess.
        let e = load("name,data,colour\na,a.csv,red\n", "csv").unwrap_err();
        assert!(!e.to_string().contains("did you mean"), "{e}");
        let e = load("name,data,sed\na,a.csv,3\n", "csv").unwrap_err();
        assert!(e.to_string().contains("(did you mean `seed`?)"), "{e}");
        let e = load("name,data,loss\na,a.csv,cauchyy\n", "csv").unwrap_err();
        assert!(e.to_string().contains(":2:3:"), "{e}");
        let e = load("name,data\na,a.csv\nA,b.csv\n", "csv").unwrap_err();
        assert!(
            e.to_string().contains(":3:1:") && e.to_string().contains("line 2"),
            "{e}"
        );
        let e = load("name,data\n../up,a.csv\n", "csv").unwrap_err();
        assert!(e.to_string().contains("plain directory name"), "{e}");
        let e = load("data,name\n", "csv").unwrap_err();
        assert!(e.to_string().contains("name,data"), "{e}");
        let e = load("name,data,no-glints\na,a.csv,maybe\n", "csv").unwrap_err();
        assert!(e.to_string().contains("true or false"), "{e}");
        let e = load("name,data\n", "csv").unwrap_err();
        assert!(e.to_string().contains("no items"), "{e}");
    }
}
