//! The batch manifest: a CSV (header `name,data`, then columns named after `hairfit fit`
//! options without their dashes) or a JSON array of objects with the same keys. Each item
//! becomes the argument list of one `hairfit fit` run, checked by the fit's own parser.

use std::path::{Path, PathBuf};

use clap::{CommandFactory, Parser};

use crate::cli::fit::FitCommandArgs;
use crate::error::{Error, Result};

/// `hairfit fit`'s own argument parser, so a manifest item means what the command line means.
#[derive(Debug, Parser)]
#[command(name = "hairfit fit", no_binary_name = true)]
pub struct FitCommandLine {
    #[command(flatten)]
    pub args: FitCommandArgs,
}

/// Separates repeated values in one cell (`fix` = `eta=1.5;k_g=2`).
pub const REPEAT_SEPARATOR: char = ';';

/// One fit of the manifest.
#[derive(Debug, Clone, PartialEq)]
pub struct Item {
    /// Output sub-directory name, unique in the manifest.
    pub name: String,
    /// Line of the manifest the item is on (1-based; the element index + 1 for JSON).
    pub line: u64,
    /// `hairfit fit` arguments without `--out`: the data path (relative to the manifest's
    /// directory, as a user in the current directory would type it) and the options.
    pub argv: Vec<String>,
}

impl Item {
    /// The parsed `hairfit fit` arguments writing into `out`.
    pub fn fit_args(&self, out: &Path) -> Result<FitCommandArgs> {
        let mut argv = self.argv.clone();
        argv.push("--out".into());
        argv.push(out.display().to_string());
        FitCommandLine::try_parse_from(&argv)
            .map(|c| c.args)
            .map_err(|e| Error::Other(format!("item `{}`: {}", self.name, e.render())))
    }
}

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
    /// line and column and what to write instead.
    pub fn load(path: &Path) -> Result<Manifest> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let is_json = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        let rows = if is_json {
            json_rows(path, &text)?
        } else {
            csv_rows(path, &text)?
        };
        let base = path.parent().unwrap_or(Path::new(""));
        let options = fit_options();
        let mut items: Vec<Item> = Vec::with_capacity(rows.len());
        for (line, cells) in rows {
            let item = item_from_cells(path, base, &options, line, &cells)?;
            if let Some(first) = items
                .iter()
                .find(|i| i.name.eq_ignore_ascii_case(&item.name))
            {
                return Err(Error::input(
                    path,
                    line,
                    1,
                    format!(
                        "item name `{}` is already used on line {} (names are output directories and must differ, ignoring case)",
                        item.name, first.line
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
}

/// An option `hairfit fit` takes: its long name and whether it takes a value.
struct FitOption {
    long: String,
    takes_value: bool,
}

fn fit_options() -> Vec<FitOption> {
    FitCommandLine::command()
        .get_arguments()
        .filter_map(|a| {
            let long = a.get_long()?;
            (long != "out" && long != "help").then(|| FitOption {
                long: long.to_string(),
                takes_value: a.get_action().takes_values(),
            })
        })
        .collect()
}

/// A manifest row: its line and its (column name, cell) pairs.
type Row = (u64, Vec<(String, String)>);

fn csv_rows(path: &Path, text: &str) -> Result<Vec<Row>> {
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| csv_error(path, e))?
        .iter()
        .map(str::to_string)
        .collect();
    if header.len() < 2 || header[0] != "name" || header[1] != "data" {
        return Err(Error::input(
            path,
            1,
            1,
            format!(
                "the header must start with `name,data` (found `{}`), then optional columns named after `hairfit fit` options without their dashes, e.g. `name,data,loss,mode,fix`",
                header.join(",")
            ),
        ));
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

fn json_rows(path: &Path, text: &str) -> Result<Vec<Row>> {
    let value: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| Error::input(path, e.line() as u64, e.column() as u64, e.to_string()))?;
    let array = value.as_array().ok_or_else(|| {
        Error::input(
            path,
            1,
            1,
            "a JSON manifest is an array of objects like {\"name\": \"a\", \"data\": \"a.csv\", \"loss\": \"cauchy\"}",
        )
    })?;
    let mut rows = Vec::new();
    for (i, element) in array.iter().enumerate() {
        let at = i as u64 + 1;
        let object = element
            .as_object()
            .ok_or_else(|| Error::input(path, at, 1, format!("element {at} is not an object")))?;
        let mut cells = Vec::new();
        for (key, v) in object {
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
                    return Err(Error::input(
                        path,
                        at,
                        1,
                        format!("element {at}: `{key}` is an object; give a string, number, boolean or array"),
                    ))
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
    let find = |key: &str| cells.iter().find(|c| c.key == key);
    let name = find("name").map(|c| c.value.clone()).unwrap_or_default();
    check_name(&name).map_err(|m| Error::input(path, line, 1, m))?;
    let data = find("data").map(|c| c.value.clone()).unwrap_or_default();
    if data.is_empty() {
        return Err(Error::input(
            path,
            line,
            2,
            format!("item `{name}` has no data file"),
        ));
    }
    let data_path = if Path::new(&data).is_absolute() {
        PathBuf::from(&data)
    } else {
        base.join(&data)
    };
    let mut argv = vec![data_path.display().to_string()];
    for cell in cells.iter().filter(|c| c.key != "name" && c.key != "data") {
        let Some(option) = options.iter().find(|o| o.long == cell.key) else {
            return Err(Error::input(
                path,
                line,
                cell.column,
                unknown_column(cell.key, options),
            ));
        };
        let words = option_words(option, &cell.value)
            .map_err(|m| Error::input(path, line, cell.column, format!("`{}`: {m}", cell.key)))?;
        // Check each cell alone so an error points at its column.
        let mut alone = vec![argv[0].clone()];
        alone.extend(words.iter().cloned());
        alone.extend(["--out".to_string(), "x".to_string()]);
        if let Err(e) = FitCommandLine::try_parse_from(&alone) {
            return Err(Error::input(
                path,
                line,
                cell.column,
                format!(
                    "`{}` = `{}`: {}",
                    cell.key,
                    cell.value,
                    first_line(&e.render().to_string())
                ),
            ));
        }
        argv.extend(words);
    }
    let item = Item { name, line, argv };
    // The options together (e.g. a conflict between two columns).
    item.fit_args(Path::new("x"))
        .map_err(|e| Error::input(path, line, 1, e.to_string()))?;
    Ok(item)
}

/// The command-line words for one cell: nothing for an empty cell or a false flag.
fn option_words(option: &FitOption, value: &str) -> std::result::Result<Vec<String>, String> {
    let flag = format!("--{}", option.long);
    if !option.takes_value {
        return match value.to_ascii_lowercase().as_str() {
            "" | "false" | "no" | "0" | "off" => Ok(vec![]),
            "true" | "yes" | "1" | "on" => Ok(vec![flag]),
            other => Err(format!(
                "`{other}` is not a switch value: write true or false"
            )),
        };
    }
    Ok(value
        .split(REPEAT_SEPARATOR)
        .map(str::trim)
        .filter(|v| !v.is_empty())
        .flat_map(|v| [flag.clone(), v.to_string()])
        .collect())
}

fn check_name(name: &str) -> std::result::Result<(), String> {
    let ok = !name.is_empty()
        && name.len() <= 100
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-'));
    if ok {
        Ok(())
    } else {
        Err(format!(
            "item name `{name}` is not a plain directory name: use 1–100 letters, digits, `.`, `_` or `-`, not starting with `.`"
        ))
    }
}

fn unknown_column(key: &str, options: &[FitOption]) -> String {
    let dashed = key.trim_start_matches('-').replace('_', "-");
    let hint = if options.iter().any(|o| o.long == dashed) {
        format!(" (did you mean `{dashed}`?)")
    } else if key == "out" {
        " (the output directory is --out of `hairfit batch` plus the item's name)".into()
    } else {
        String::new()
    };
    let names: Vec<&str> = options.iter().map(|o| o.long.as_str()).collect();
    format!(
        "column `{key}` is not a `hairfit fit` option{hint}; columns after name,data are options without their dashes: {}",
        names.join(", ")
    )
}

fn first_line(s: &str) -> String {
    s.lines()
        .next()
        .unwrap_or("")
        .trim_start_matches("error: ")
        .to_string()
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
        let e = load("name,data,los\na,a.csv,cauchy\n", "csv").unwrap_err();
        let s = e.to_string();
        assert!(s.contains(":2:3:") && s.contains("`los`"), "{s}");
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
