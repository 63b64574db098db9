//! `hairfit --help` names every family and export target the code has (the lists come from
//! `ModelFamily::ALL` and `Target::all()`, so a new one cannot be left out of the help), and no
//! command's default output is a path kept in git (running a command must not modify the
//! checkout).

use crate::support::cli;

use cli::{hairfit_ok, root, stdout};
use hairfit::export::Target;
use hairfit::families::ModelFamily;

/// clap wraps help at the terminal's width; joined on whitespace a name split over two lines
/// still matches.
fn help(args: &[&str]) -> String {
    let text = stdout(&hairfit_ok(args));
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[test]
fn the_help_names_every_family() {
    let top = help(&["--help"]);
    for family in ModelFamily::ALL {
        assert!(top.contains(family.citation()), "{family:?} in: {top}");
    }
    for command in ["fit", "demo", "eval", "synth", "cost", "compare"] {
        let text = help(&[command, "--help"]);
        for family in ModelFamily::ALL {
            assert!(
                text.contains(&format!("{}: {}", family.as_str(), family.citation())),
                "`{command} --help` lacks {family:?}: {text}"
            );
        }
    }
}

#[test]
fn the_help_names_every_export_target() {
    let top = help(&["--help"]);
    let export = help(&["export", "--help"]);
    for target in Target::all() {
        assert!(top.contains(target.program()), "{target} in: {top}");
        assert!(
            export.contains(&format!("{target} ({})", target.program())),
            "{target} in: {export}"
        );
    }
}

/// Every target is reached by its name and each of its spellings, in any case, and no two
/// targets claim one word; its example file name has its extension.
#[test]
fn every_target_parses_from_its_names_and_no_word_is_shared() {
    let mut words = std::collections::BTreeMap::new();
    for target in Target::all() {
        for word in std::iter::once(target.name()).chain(target.aliases().iter().copied()) {
            for spelling in [word.to_string(), word.to_ascii_uppercase()] {
                assert_eq!(spelling.parse::<Target>().unwrap(), *target, "{spelling}");
            }
            assert!(
                words.insert(word, target.name()).is_none(),
                "`{word}` names two targets"
            );
        }
        assert!(
            target
                .file_name()
                .ends_with(&format!(".{}", target.extension())),
            "{target}: {}",
            target.file_name()
        );
    }
    let err = "nope".parse::<Target>().unwrap_err().to_string();
    let names: Vec<&str> = Target::all().iter().map(|t| t.name()).collect();
    assert!(
        err.contains(names[..names.len() - 1].join(", ").as_str()),
        "{err}"
    );
}

#[test]
fn no_default_output_is_a_tracked_path() {
    let git = std::process::Command::new("git")
        .args(["ls-files"])
        .current_dir(root())
        .output();
    // A source tarball has no git: nothing is tracked, nothing to check.
    let Some(git) = git.ok().filter(|o| o.status.success()) else {
        return;
    };
    let tracked = String::from_utf8_lossy(&git.stdout).into_owned();
    let top = stdout(&hairfit_ok(&["--help"]));
    let commands: Vec<&str> = top
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .collect();
    assert!(
        commands.contains(&"demo") && commands.contains(&"cost"),
        "{commands:?}"
    );
    let mut defaults = Vec::new();
    for command in commands {
        let text = help(&[command, "--help"]);
        // Every `[default: PATH]` that names a file or directory.
        for part in text.split("[default: ").skip(1) {
            let value = part.split(']').next().unwrap_or_default();
            if value.contains('/') {
                defaults.push((command, value.to_string()));
            }
        }
    }
    assert!(
        defaults.iter().any(|(c, _)| *c == "demo"),
        "demo's default --out was not found: {defaults:?}"
    );
    for (command, path) in &defaults {
        let inside = format!("{}/", path.trim_end_matches('/'));
        let hit = tracked
            .lines()
            .find(|f| *f == path.as_str() || f.starts_with(&inside));
        assert!(
            hit.is_none(),
            "`hairfit {command}` writes {path} by default, which holds tracked {hit:?}"
        );
    }
}
