//! docs/model.md stays in step with the code: every line of the parameter table appears in it with
//! its unit, domain, bounds, typical range and default, and no doc links outside the repository.

use hairfit::families::marschner::parameters::{NAMES, TABLE};
use hairfit::families::marschner::ParamName;
use hairfit::geometry::{Fitted, ParamFact};

const DOCS: &str = include_str!("../../docs/model.md");

/// Seven significant digits, shortest form: enough for every bound in the table (1.000001).
fn num(x: f64) -> String {
    if x.is_infinite() {
        return if x > 0.0 { "inf" } else { "-inf" }.into();
    }
    let rounded: f64 = format!("{x:.6e}").parse().unwrap();
    format!("{rounded}")
}

/// The row docs/model.md must hold for `s`.
fn row((s, name): (&ParamFact, ParamName)) -> String {
    let fit = match s.fit_hi {
        Some(hi) => format!("[{}, {}]", num(s.fit_lo), num(hi)),
        None => format!("[{}, inf)", num(s.fit_lo)),
    };
    let fitted = match s.fitted {
        Fitted::Yes => "yes",
        Fitted::OnRequest => "with `--free eta`",
        Fitted::No => "no",
    };
    format!(
        "| `{}` | {} | {} | {} | {} | {} to {} | {} | {} | {} |",
        s.name,
        s.symbol,
        s.unit.describe(),
        s.domain.text(),
        fit,
        num(s.typical.0),
        num(s.typical.1),
        s.default.map(num).unwrap_or_else(|| "—".into()),
        name.used_by().describe(),
        fitted
    )
}

#[test]
fn every_parameter_appears_with_its_unit_and_domain() {
    let missing: Vec<String> = TABLE
        .iter()
        .zip(NAMES)
        .map(row)
        .filter(|r| !DOCS.lines().any(|l| l.trim() == r))
        .collect();
    assert!(
        missing.is_empty(),
        "docs/model.md lacks these rows of the parameter table (paste them in):\n{}",
        TABLE
            .iter()
            .zip(NAMES)
            .map(row)
            .collect::<Vec<_>>()
            .join("\n")
    );
    // σ_a's unit is the one most easily lost: say it in words too.
    assert!(DOCS.contains("per fiber radius"));
}

#[test]
fn every_model_source_file_is_documented() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/src/families/marschner");
    for entry in std::fs::read_dir(dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        let module = name.trim_end_matches(".rs");
        // The folder's parameter file, fit adaptor, demo truth, cost-ledger section and registry
        // types (`family.rs`) are the family's, not the model's.
        if matches!(
            module,
            "mod" | "params" | "fit" | "demo" | "cost" | "family"
        ) {
            continue;
        }
        assert!(
            DOCS.contains(&format!("marschner::{module}::"))
                || DOCS.contains(&format!("`{module}.rs`")),
            "docs/model.md does not mention src/families/marschner/{name}"
        );
    }
}

#[test]
fn docs_link_only_to_files_inside_the_repository() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .canonicalize()
        .unwrap();
    for file in [
        "README.md",
        "docs/model.md",
        "docs/README.md",
        "docs/compare.md",
    ] {
        let path = root.join(file);
        let text = std::fs::read_to_string(&path).unwrap();
        for (i, line) in text.lines().enumerate() {
            for target in line.split("](").skip(1).filter_map(|t| t.split(')').next()) {
                if target.starts_with('#') || target.contains("://") {
                    continue;
                }
                let target = target.split('#').next().unwrap();
                let resolved = path.parent().unwrap().join(target).canonicalize();
                assert!(
                    matches!(&resolved, Ok(p) if p.starts_with(&root)),
                    "{file}:{}: link `{target}` leaves the repository or names no file",
                    i + 1
                );
            }
        }
    }
}
