//! The source tree's shape, checked: no import cycle between modules, the layers import only
//! downwards, the fit never reaches into the report, and no file grows past 650 lines without
//! saying why at its top. Reads `src/**/*.rs` as text (imports are `crate::`, `super::` and
//! `self::` paths; comments and `#[cfg(test)] mod tests` are skipped).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The layers, lowest first: a module may import its own layer and those below, never above.
const LAYERS: &[(&str, &[&str])] = &[
    (
        "foundations",
        &[
            "error",
            "atomic",
            "rng",
            "lm",
            "outdir",
            "plot",
            "json_file",
            "geometry",
        ],
    ),
    ("model families", &["families"]),
    ("files and samples", &["files", "data", "slices"]),
    (
        "fit and synthesis",
        &["fit", "synth", "trace", "eval", "export"],
    ),
    ("results", &["report", "compare", "demo", "cost"]),
    ("commands", &["cli", "batch"]),
];

/// Past this many lines a file must say at its top why it is one file.
const MAX_LINES: usize = 650;
/// The words that reason starts with, in the file's first lines.
const LONG_FILE_REASON: &str = "One file past 650 lines because";

type Module = Vec<String>;

fn src_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    let mut out = Vec::new();
    walk(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"), &mut out);
    out.sort();
    out
}

/// `src/fit/problem/evaluator.rs` → `fit::problem::evaluator`; `mod.rs` and `lib.rs` name
/// their directory.
fn module_of(path: &Path) -> Module {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let rel = path.strip_prefix(&src).unwrap().with_extension("");
    let mut segs: Module = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    if matches!(
        segs.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        segs.pop();
    }
    segs
}

/// The code without comments and without a trailing `#[cfg(test)] mod tests`.
fn code_of(text: &str) -> String {
    let cut = text.find("#[cfg(test)]\nmod tests").unwrap_or(text.len());
    text[..cut]
        .lines()
        .map(|l| l.find("//").map_or(l, |i| &l[..i]))
        .collect::<Vec<_>>()
        .join("\n")
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// Every path that starts with `crate`, `super` or `self`, with one level of `{a, b::c}` groups
/// expanded (enough to name the module each item comes from).
fn paths_in(code: &str) -> Vec<Vec<String>> {
    let bytes: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let starts_word = i == 0 || !is_ident(bytes[i - 1]) && bytes[i - 1] != ':';
        let rest: String = bytes[i..bytes.len().min(i + 7)].iter().collect();
        let head = ["crate::", "super::", "self::"]
            .into_iter()
            .find(|h| rest.starts_with(h));
        let Some(head) = head.filter(|_| starts_word) else {
            i += 1;
            continue;
        };
        let mut segs = vec![head.trim_end_matches("::").to_string()];
        i += head.len();
        loop {
            if i < bytes.len() && bytes[i] == '{' {
                let close = (i..bytes.len())
                    .find(|&j| bytes[j] == '}')
                    .unwrap_or(bytes.len());
                let group: String = bytes[i + 1..close].iter().collect();
                for item in group.split(',') {
                    let first = item.trim().split("::").next().unwrap_or("");
                    let first = first.split(" as ").next().unwrap_or("").trim();
                    let first = first.trim_matches(|c: char| c == '{' || c == '}' || c == ' ');
                    if !first.is_empty() {
                        let mut p = segs.clone();
                        p.push(first.to_string());
                        out.push(p);
                    }
                }
                i = close;
                break;
            }
            let start = i;
            while i < bytes.len() && is_ident(bytes[i]) {
                i += 1;
            }
            if i == start {
                break;
            }
            segs.push(bytes[start..i].iter().collect());
            if bytes.get(i) == Some(&':') && bytes.get(i + 1) == Some(&':') {
                i += 2;
            } else {
                out.push(segs.clone());
                break;
            }
        }
    }
    out
}

/// The module a path names an item of: the longest prefix that is a module of the crate.
fn resolve(current: &Module, path: &[String], modules: &BTreeSet<Module>) -> Option<Module> {
    let (mut base, mut rest) = match path.first().map(String::as_str) {
        Some("crate") => (Vec::new(), &path[1..]),
        Some("self") => (current.clone(), &path[1..]),
        Some("super") => (current.clone(), path),
        _ => return None,
    };
    while rest.first().is_some_and(|s| s == "super") {
        base.pop();
        rest = &rest[1..];
    }
    let full: Module = base.into_iter().chain(rest.iter().cloned()).collect();
    (0..=full.len())
        .rev()
        .map(|n| full[..n].to_vec())
        .find(|m| modules.contains(m))
}

struct Tree {
    /// File module → the modules it imports from (itself excluded).
    edges: BTreeMap<Module, BTreeSet<Module>>,
    lines: BTreeMap<PathBuf, (usize, String)>,
}

fn tree() -> Tree {
    let files = src_files();
    let modules: BTreeSet<Module> = files.iter().map(|p| module_of(p)).collect();
    let mut edges = BTreeMap::new();
    let mut lines = BTreeMap::new();
    for path in &files {
        let text = std::fs::read_to_string(path).unwrap();
        let current = module_of(path);
        let targets: BTreeSet<Module> = paths_in(&code_of(&text))
            .iter()
            .filter_map(|p| resolve(&current, p, &modules))
            .filter(|m| *m != current)
            .collect();
        edges.insert(current, targets);
        let head: String = text.lines().take(12).collect::<Vec<_>>().join("\n");
        lines.insert(path.clone(), (text.lines().count(), head));
    }
    Tree { edges, lines }
}

fn name(m: &Module) -> String {
    if m.is_empty() {
        "crate".into()
    } else {
        m.join("::")
    }
}

/// Strongly connected components with more than one member (Tarjan).
fn cycles(edges: &BTreeMap<Module, BTreeSet<Module>>) -> Vec<Vec<String>> {
    struct State<'a> {
        edges: &'a BTreeMap<Module, BTreeSet<Module>>,
        index: BTreeMap<&'a Module, usize>,
        low: BTreeMap<&'a Module, usize>,
        stack: Vec<&'a Module>,
        found: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a Module) {
        let n = s.index.len();
        s.index.insert(v, n);
        s.low.insert(v, n);
        s.stack.push(v);
        let edges = s.edges;
        for w in edges.get(v).into_iter().flatten() {
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if s.stack.contains(&w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = s.stack.pop() {
                comp.push(name(w));
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                s.found.push(comp);
            }
        }
    }
    let mut s = State {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        found: Vec::new(),
    };
    for v in edges.keys() {
        if !s.index.contains_key(v) {
            visit(&mut s, v);
        }
    }
    s.found
}

/// A module's top-level module; a family's fit adaptor (`families::<x>::fit`,
/// `families::table::fit`) belongs to the fit, whose stages it hands its family to, its
/// section of the cost ledger (`families::<x>::cost`) to the ledger, and the export targets
/// that draw its model (`families::<x>::export`) to the export.
fn top(m: &Module) -> &str {
    match m.as_slice() {
        [f, _, part, ..] if f == "families" && FAMILY_PARTS.contains(&part.as_str()) => part,
        _ => m.first().map_or("crate", String::as_str),
    }
}

/// The parts of a family's folder that belong to a layer above the families (the module of that
/// name): each plugs the family into that layer.
const FAMILY_PARTS: &[&str] = &["fit", "cost", "export"];

#[test]
fn the_checker_sees_a_cycle_and_an_import_through_a_group() {
    // The checker itself: a path through `{…}` resolves, and a two-module loop is found.
    let paths = paths_in("use super::{evidence::Evidence, gof};\nlet x = crate::fit::Loss::L2;");
    assert_eq!(
        paths,
        vec![
            vec!["super".to_string(), "evidence".into()],
            vec!["super".into(), "gof".into()],
            vec!["crate".into(), "fit".into(), "Loss".into(), "L2".into()],
        ]
    );
    let a: Module = vec!["a".into()];
    let b: Module = vec!["b".into()];
    let edges = BTreeMap::from([
        (a.clone(), BTreeSet::from([b.clone()])),
        (b.clone(), BTreeSet::from([a.clone()])),
    ]);
    assert_eq!(cycles(&edges), vec![vec!["a".to_string(), "b".into()]]);
}

#[test]
fn no_file_module_imports_form_a_cycle() {
    let tree = tree();
    let found = cycles(&tree.edges);
    assert!(
        found.is_empty(),
        "modules that import each other: {found:?}"
    );
}

#[test]
fn top_level_modules_import_only_their_layer_and_below() {
    let tree = tree();
    let layer_of = |m: &str| LAYERS.iter().position(|(_, ms)| ms.contains(&m));
    let mut upward = Vec::new();
    for (from, targets) in &tree.edges {
        if from.is_empty() {
            continue; // lib.rs declares every module
        }
        let Some(lf) = layer_of(top(from)) else {
            panic!("module `{}` is in no layer: add it to LAYERS", top(from));
        };
        for to in targets
            .iter()
            .filter(|t| !t.is_empty() && top(t) != top(from))
        {
            let lt = layer_of(top(to)).unwrap_or_else(|| panic!("`{}` is in no layer", top(to)));
            if lt > lf {
                upward.push(format!(
                    "{} ({}) -> {} ({})",
                    name(from),
                    LAYERS[lf].0,
                    name(to),
                    LAYERS[lt].0
                ));
            }
        }
    }
    let mut tops: BTreeMap<&str, BTreeSet<&str>> = BTreeMap::new();
    for (from, targets) in &tree.edges {
        for to in targets {
            if !from.is_empty() && !to.is_empty() && top(from) != top(to) {
                tops.entry(top(from)).or_default().insert(top(to));
            }
        }
    }
    let top_edges: BTreeMap<Module, BTreeSet<Module>> = tops
        .iter()
        .map(|(a, bs)| {
            (
                vec![a.to_string()],
                bs.iter().map(|b| vec![b.to_string()]).collect(),
            )
        })
        .collect();
    assert!(upward.is_empty(), "imports up the layers: {upward:#?}");
    let found = cycles(&top_edges);
    assert!(found.is_empty(), "top-level modules in a cycle: {found:?}");
}

#[test]
fn the_fit_never_imports_the_report() {
    let tree = tree();
    let bad: Vec<String> = tree
        .edges
        .iter()
        .filter(|(from, _)| top(from) == "fit")
        .flat_map(|(from, targets)| {
            targets
                .iter()
                .filter(|t| top(t) == "report")
                .map(move |t| format!("{} -> {}", name(from), name(t)))
        })
        .collect();
    assert!(
        bad.is_empty(),
        "the fit hands results to the report: {bad:?}"
    );
}

#[test]
fn long_files_say_why_they_are_one_file() {
    let tree = tree();
    let bad: Vec<String> = tree
        .lines
        .iter()
        .filter(|(_, (n, head))| *n > MAX_LINES && !head.contains(LONG_FILE_REASON))
        .map(|(p, (n, _))| format!("{} ({n} lines)", p.display()))
        .collect();
    assert!(
        bad.is_empty(),
        "files over {MAX_LINES} lines without `{LONG_FILE_REASON} …` in their first lines: \
         split them along their seams or say why not: {bad:?}"
    );
}

/// The modules under `src/families/` that are no family: what families share, and the lists and
/// switches every command reads.
const FAMILY_NEUTRAL: &[&str] = &["shared", "table", "effects", "registry", "setup"];

/// `families::<x>::…` → `Some(x)` when x is a family's own folder.
fn family_folder(m: &Module) -> Option<&str> {
    match m.as_slice() {
        [f, x, ..] if f == "families" && !FAMILY_NEUTRAL.contains(&x.as_str()) => Some(x),
        _ => None,
    }
}

#[test]
fn no_family_folder_imports_another_family() {
    // A family is one folder plus one registry line: what two families share lives in
    // `families::shared` (or `table`), so removing or moving one folder touches no other.
    let tree = tree();
    let bad: Vec<String> = tree
        .edges
        .iter()
        .filter_map(|(from, targets)| Some((from, family_folder(from)?, targets)))
        .flat_map(|(from, own, targets)| {
            targets
                .iter()
                .filter(move |t| family_folder(t).is_some_and(|x| x != own))
                .map(move |t| format!("{} -> {}", name(from), name(t)))
        })
        .collect();
    assert!(
        bad.is_empty(),
        "a family's folder imports another family's: move what they share to \
         `families::shared`: {bad:?}"
    );
}
