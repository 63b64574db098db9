//! A manifest's columns as `hairfit fit`'s options: the fit's own parser ([`FitCommandLine`]),
//! which options a column may name, the command-line words of a cell, and fit messages put in
//! the manifest's words.

use clap::{CommandFactory, Parser};

use crate::cli::fit::FitCommandArgs;

/// Separates repeated values in one cell (`fix` = `eta=1.5;k_g=2`).
pub const REPEAT_SEPARATOR: char = ';';

/// `hairfit fit`'s own argument parser, so a manifest item means what the command line means.
#[derive(Debug, Parser)]
#[command(name = "hairfit fit", no_binary_name = true)]
pub struct FitCommandLine {
    #[command(flatten)]
    pub args: FitCommandArgs,
}

/// Fit options that are the whole run's, not an item's: a column naming one is an error
/// that says how to give it instead.
const RUN_LEVEL: [(&str, &str); 2] = [
    (
        "strict",
        "pass `hairfit batch --strict`: it applies to every item of the run and to --merge",
    ),
    (
        "out",
        "the output directory is --out of `hairfit batch` plus the item's name",
    ),
];

/// An option `hairfit fit` takes: its long name, whether it takes a value, and whether it
/// may be given more than once (`fix`, `free`: `;` separates the values in one cell).
pub(super) struct FitOption {
    pub(super) long: String,
    takes_value: bool,
    repeatable: bool,
}

pub(super) fn fit_options() -> Vec<FitOption> {
    FitCommandLine::command()
        .get_arguments()
        .filter_map(|a| {
            let long = a.get_long()?;
            (long != "out" && long != "help").then(|| FitOption {
                long: long.to_string(),
                takes_value: a.get_action().takes_values(),
                repeatable: matches!(a.get_action(), clap::ArgAction::Append),
            })
        })
        .collect()
}

/// Why a column (CSV header) or key (JSON) cannot name an item's option, if it cannot.
pub(super) fn check_key(key: &str, options: &[FitOption], json: bool) -> Option<String> {
    if let Some((_, how)) = RUN_LEVEL.iter().find(|(k, _)| *k == key) {
        return Some(format!("`{key}` is not an item's option: {how}"));
    }
    if key == "name" || key == "data" || options.iter().any(|o| o.long == key) {
        return None;
    }
    Some(unknown_column(key, options, json))
}

/// Parse `words` (a data path and options) as `hairfit fit` would and check the options'
/// values (fixes, effects, model options) without loading the data: the first line of what
/// is wrong, in the manifest's words.
pub(super) fn check_fit_words(words: &[String]) -> std::result::Result<(), String> {
    let mut argv = words.to_vec();
    argv.extend(["--out".to_string(), "x".to_string()]);
    let args = FitCommandLine::try_parse_from(&argv)
        .map_err(|e| first_line(&e.render().to_string()))?
        .args;
    args.fit.check().map_err(|e| e.to_string())
}

/// The command-line words for one cell: nothing for an empty cell or a false flag.
pub(super) fn option_words(
    option: &FitOption,
    value: &str,
) -> std::result::Result<Vec<String>, String> {
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
    if !option.repeatable && value.contains(REPEAT_SEPARATOR) {
        let list = value
            .split(REPEAT_SEPARATOR)
            .map(str::trim)
            .collect::<Vec<_>>()
            .join(",");
        return Err(format!(
            "takes one value, and `;` only separates the values of repeatable options (fix, free); for a list write it comma-separated, quoted in a CSV cell: \"{list}\""
        ));
    }
    if !option.repeatable {
        return Ok(if value.trim().is_empty() {
            vec![]
        } else {
            vec![flag, value.trim().to_string()]
        });
    }
    Ok(value
        .split(REPEAT_SEPARATOR)
        .map(str::trim)
        .filter(|v| !v.is_empty())
        .flat_map(|v| [flag.clone(), v.to_string()])
        .collect())
}

/// Why `key` names no option, and which names do (`json`: the place already names the key).
pub(super) fn unknown_column(key: &str, options: &[FitOption], json: bool) -> String {
    let dashed = key.trim_start_matches('-').replace('_', "-");
    let names: Vec<&str> = options
        .iter()
        .map(|o| o.long.as_str())
        .filter(|n| !RUN_LEVEL.iter().any(|(k, _)| k == n))
        .collect();
    let hint = if options.iter().any(|o| o.long == dashed) {
        format!(" (did you mean `{dashed}`?)")
    } else {
        closest_name(&dashed, &names)
            .map(|name| format!(" (did you mean `{name}`?)"))
            .unwrap_or_default()
    };
    if json {
        format!(
            "not a `hairfit fit` option{hint}; keys besides name and data are options without their dashes: {}",
            names.join(", ")
        )
    } else {
        format!(
            "column `{key}` is not a `hairfit fit` option{hint}; columns after name,data are options without their dashes: {}",
            names.join(", ")
        )
    }
}

/// The name most like `typed`, when one is close enough to be the intended one: Jaro
/// similarity above 0.8, as clap suggests a misspelt option (`lose` → `loss`, `sed` → `seed`).
fn closest_name<'a>(typed: &str, names: &[&'a str]) -> Option<&'a str> {
    names
        .iter()
        .map(|&name| (strsim::jaro(typed, name), name))
        .filter(|&(similarity, _)| similarity > 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, name)| name)
}

/// A `hairfit fit` message in a manifest's words: the options it names (`--space linear`)
/// are columns of the manifest, so say which.
pub fn as_manifest_words(message: &str) -> String {
    let options = fit_options();
    let mut named: Vec<&str> = Vec::new();
    for o in &options {
        let flag = format!("--{}", o.long);
        let mentioned = message.match_indices(&flag).any(|(i, _)| {
            let after = message[i + flag.len()..].chars().next();
            !after.is_some_and(|c| c.is_ascii_alphanumeric() || c == '-')
        });
        if mentioned && !named.contains(&o.long.as_str()) {
            named.push(&o.long);
        }
    }
    if named.is_empty() {
        return message.to_string();
    }
    let columns: Vec<String> = named.iter().map(|n| format!("`{n}`")).collect();
    format!(
        "{message} [in the manifest: the column{} {}]",
        if columns.len() > 1 { "s" } else { "" },
        columns.join(", ")
    )
}

fn first_line(s: &str) -> String {
    s.lines()
        .next()
        .unwrap_or("")
        .trim_start_matches("error: ")
        .to_string()
}
