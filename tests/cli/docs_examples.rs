//! Every command example of README.md and GUIDE.md runs as written from a fresh clone: each
//! ```sh block's `hairfit …` lines run in order, in a temporary copy of what a clone ships
//! (data/, examples/, fits/), and must exit 0; a path under `/tmp/` is taken inside that copy,
//! and no example may change a file the clone tracks. A command whose line ends in `# slow` is
//! only checked against the parser (its subcommand exists, every `--option` it spells is in that
//! subcommand's --help), which keeps this test under a minute. Any other line in a sh block must
//! be a comment or one of the few non-hairfit commands the docs show (installing, the test
//! command, Python), so a new example cannot slip past unrun.
//!
//! Not trycmd: it compares every command's full output (a fit's summary has timings), cannot
//! run a command whose options are only parse-checked, and is not in the build's crate cache.

use std::path::Path;
use std::time::{Duration, Instant};

use crate::support::cli;
use cli::{hairfit_command, root, run_within, stderr, stdout};

/// Lines the docs show that are not hairfit commands, by their first word(s); they are run by
/// CI itself (scripts/test.sh) or need what a fresh clone lacks (an install, scipy).
const NOT_HAIRFIT: [&str; 5] = [
    "cargo install",
    "scripts/",
    "git clone",
    "pip install",
    "python",
];

/// One example: the file and line it is on, its words after `hairfit`, whether it runs.
struct Example {
    at: String,
    words: Vec<String>,
    slow: bool,
}

/// The `hairfit` commands of `file`'s ```sh blocks (continuation lines joined).
fn examples(file: &str) -> Vec<Example> {
    let text = std::fs::read_to_string(root().join(file)).unwrap();
    let mut found = Vec::new();
    let mut in_sh = false;
    let mut pending: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim();
        if trimmed.starts_with("```") {
            in_sh = !in_sh && (trimmed == "```sh" || trimmed == "```bash");
            continue;
        }
        if !in_sh {
            continue;
        }
        let (start, mut joined) = pending.take().unwrap_or((i + 1, String::new()));
        if let Some(head) = trimmed.strip_suffix('\\') {
            joined.push_str(head);
            pending = Some((start, joined));
            continue;
        }
        joined.push_str(trimmed);
        let at = format!("{file}:{start}");
        let (command, comment) = match joined.find(" #") {
            Some(k) => (joined[..k].trim(), joined[k + 2..].trim()),
            None => (joined.trim(), ""),
        };
        if command.is_empty() || command.starts_with('#') {
            continue;
        }
        // `cargo run --release -- ARGS` is `hairfit ARGS` (README, "Install").
        let hairfit_args = command
            .strip_prefix("hairfit ")
            .or_else(|| command.strip_prefix("cargo run --release -- "));
        if let Some(rest) = hairfit_args {
            found.push(Example {
                words: split_words(rest, &at),
                at,
                slow: comment.starts_with("slow"),
            });
        } else {
            assert!(
                NOT_HAIRFIT.iter().any(|p| command.starts_with(p)),
                "{at}: `{command}` is neither a hairfit command nor one the docs may show \
                 unrun (NOT_HAIRFIT)"
            );
        }
    }
    found
}

/// Shell words: spaces separate, single and double quotes group (no expansions in the docs).
fn split_words(line: &str, at: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut word: Option<String> = None;
    let mut quote = None;
    for c in line.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), c) => word.get_or_insert_with(String::new).push(c),
            (None, '\'' | '"') => {
                quote = Some(c);
                word.get_or_insert_with(String::new);
            }
            (None, ' ') => words.extend(word.take()),
            (None, c) => word.get_or_insert_with(String::new).push(c),
        }
    }
    assert!(quote.is_none(), "{at}: unclosed quote in `{line}`");
    words.extend(word);
    words
}

/// Copy the tracked files of data/, examples/ and fits/ under `dir` into `to` (what a clone
/// has: no fits/NAME of earlier runs); their paths.
fn copy_shipped(dir: &Path, to: &Path) -> Vec<String> {
    let git = std::process::Command::new("git")
        .args(["ls-files", "data", "examples", "fits"])
        .current_dir(dir)
        .output()
        .ok()
        .filter(|o| o.status.success());
    let files: Vec<String> = match git {
        Some(out) => String::from_utf8_lossy(&out.stdout)
            .lines()
            .map(String::from)
            .collect(),
        // A source tarball: everything under the three directories.
        None => walk(dir, Path::new(""), &["data", "examples", "fits"]),
    };
    for f in &files {
        let target = to.join(f);
        std::fs::create_dir_all(target.parent().unwrap()).unwrap();
        std::fs::copy(dir.join(f), &target).unwrap();
    }
    files
}

fn walk(base: &Path, rel: &Path, tops: &[&str]) -> Vec<String> {
    let mut out = Vec::new();
    for top in tops {
        let dir = base.join(rel).join(top);
        for entry in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            let sub = Path::new(top).join(&name);
            if entry.path().is_dir() {
                out.extend(walk(base, rel, &[sub.to_str().unwrap()]));
            } else {
                out.push(sub.to_string_lossy().into_owned());
            }
        }
    }
    out
}

/// A slow example's parse check: the subcommand exists and knows every `--option` given.
fn check_parses(example: &Example) {
    let sub = &example.words[0];
    let (out, _) = run_within(
        hairfit_command(&[sub.as_str(), "--help"]),
        Duration::from_secs(30),
    );
    assert!(
        out.status.success(),
        "{}: no subcommand `{sub}`",
        example.at
    );
    let help = stdout(&out);
    for word in &example.words[1..] {
        if let Some(option) = word.strip_prefix("--") {
            let option = option.split('=').next().unwrap();
            assert!(
                help.contains(&format!("--{option} ")) || help.contains(&format!("--{option}\n")),
                "{}: `hairfit {sub}` has no --{option}",
                example.at
            );
        }
    }
}

fn run_file(file: &str) {
    let sandbox = tempfile::tempdir().unwrap();
    let shipped = copy_shipped(&root(), sandbox.path());
    let tmp = sandbox.path().join("tmp");
    std::fs::create_dir(&tmp).unwrap();
    let in_sandbox = |word: &String| match word.strip_prefix("/tmp/") {
        Some(rest) => tmp.join(rest).to_string_lossy().into_owned(),
        None => word.clone(),
    };
    let all = examples(file);
    assert!(!all.is_empty(), "{file} has no hairfit examples");
    let started = Instant::now();
    for example in &all {
        if example.slow {
            check_parses(example);
            continue;
        }
        let words: Vec<String> = example.words.iter().map(in_sandbox).collect();
        let words: Vec<&str> = words.iter().map(String::as_str).collect();
        let mut command = hairfit_command(&words);
        command.current_dir(sandbox.path());
        let (out, took) = run_within(command, Duration::from_secs(60));
        assert!(
            out.status.success(),
            "{}: `hairfit {}` exited {:?}:\n{}",
            example.at,
            words.join(" "),
            out.status.code(),
            stderr(&out)
        );
        eprintln!(
            "{}: {:.1} s  hairfit {}",
            example.at,
            took.as_secs_f64(),
            words.join(" ")
        );
    }
    eprintln!(
        "{file}: {} examples in {:.1} s",
        all.len(),
        started.elapsed().as_secs_f64()
    );
    // An example that rewrites a committed file would leave a user's clone modified.
    let changed: Vec<&String> = shipped
        .iter()
        .filter(|f| {
            std::fs::read(sandbox.path().join(f)).ok() != std::fs::read(root().join(f)).ok()
        })
        .collect();
    assert!(
        changed.is_empty(),
        "{file}'s examples change tracked files: {changed:?}"
    );
}

#[test]
fn readme_examples_run_from_a_fresh_clone() {
    run_file("README.md");
}

#[test]
fn guide_examples_run_from_a_fresh_clone() {
    run_file("GUIDE.md");
}
