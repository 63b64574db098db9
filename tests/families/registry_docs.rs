//! The users' list of families, docs/families.md's table, is the registry's: every family
//! `--model` takes, in `ModelFamily::ALL`'s order (the first the default), each row linking a
//! page that exists; and docs/export.md names every `--to` target.

use hairfit::export::Target;
use hairfit::families::ModelFamily;

/// The `--model` word of each row of docs/families.md's table, with the row.
fn table_rows() -> Vec<(String, String)> {
    let text = std::fs::read_to_string("docs/families.md").expect("docs/families.md");
    text.lines()
        .filter_map(|l| {
            let cell = l.strip_prefix("| `")?;
            let name = cell.split('`').next()?;
            // The header's first cell is `--model`.
            (!name.starts_with('-')).then(|| (name.to_string(), l.to_string()))
        })
        .collect()
}

#[test]
fn the_families_page_lists_the_registry_in_its_order() {
    let rows = table_rows();
    let listed: Vec<&str> = rows.iter().map(|(n, _)| n.as_str()).collect();
    let registered: Vec<&str> = ModelFamily::ALL.iter().map(|f| f.as_str()).collect();
    assert_eq!(
        listed, registered,
        "docs/families.md's table against the registry"
    );
    for (k, (name, row)) in rows.iter().enumerate() {
        // Only the registry's first family is the default `--model`.
        assert_eq!(row.contains("(default)"), k == 0, "{name}: {row}");
        let page = row
            .rsplit("](")
            .next()
            .and_then(|r| r.split(')').next())
            .unwrap_or_else(|| panic!("{name}'s row links no page: {row}"));
        assert!(
            std::path::Path::new("docs").join(page).is_file(),
            "{name}'s page docs/{page} does not exist"
        );
    }
}

#[test]
fn the_export_page_names_every_target() {
    let text = std::fs::read_to_string("docs/export.md").expect("docs/export.md");
    // Every `--to NAME` and `--to A|B|C` the page writes.
    let named: Vec<&str> = text
        .split("--to ")
        .skip(1)
        .flat_map(|rest| {
            let end = rest
                .find(|c: char| !(c.is_ascii_lowercase() || c == '|'))
                .unwrap_or(rest.len());
            rest[..end].split('|')
        })
        .collect();
    for target in Target::all() {
        assert!(
            named.contains(&target.name()),
            "docs/export.md never says `--to {target}`"
        );
    }
}
