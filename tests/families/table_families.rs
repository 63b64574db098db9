//! What every table family (`ModelFamily::table` of `ModelFamily::ALL`) must do beyond the battery every
//! registered family runs (`battery.rs`): its page holds its parameter table, a term switched
//! off fits none of its parameters, and a noisy fit lands within a few standard errors.

use hairfit::demo::{demo_directions, DEMO_SCALE};
use hairfit::families::table::{
    demo_params, DynTable, TableFamily, TableParamFile, TableParams, TermSet,
};
use hairfit::families::{deon::DEon, frostbite::Frostbite, kajiya_kay::KajiyaKay, karis::Karis};
use hairfit::families::{FamilyModel, FamilyParams, ModelFamily, ModelSetup};
use hairfit::files::{FitJson, LoadReport, ParamStatus};
use hairfit::fit::registry::fit_family;
use hairfit::fit::FitOptions;
use hairfit::geometry::Measurement;
use hairfit::synth::{Acquisition, Noise, Source};

/// The families this file runs its battery on; [`every_family_has_a_battery`] fails when a
/// table family joins the registry (`ModelFamily::ALL`) without one.
const BATTERIES: &[&str] = &["kajiya-kay", "deon", "karis", "frostbite"];

/// Every table family of the registry, in `--model` order.
fn tables() -> Vec<&'static dyn DynTable> {
    ModelFamily::ALL.iter().filter_map(|f| f.table()).collect()
}

#[test]
fn every_family_has_a_battery() {
    let all: Vec<&str> = tables().iter().map(|t| t.name()).collect();
    assert_eq!(all, BATTERIES, "add the new family's battery test below");
}

#[test]
fn kajiya_kay() {
    battery::<KajiyaKay>();
}

#[test]
fn deon() {
    battery::<DEon>();
}

#[test]
fn karis() {
    battery::<Karis>();
}

#[test]
fn frostbite() {
    battery::<Frostbite>();
}

/// Each family's page, docs/NAME.md, holds its parameter table exactly as the code has it, and
/// docs/README.md links the page.
#[test]
fn every_family_documents_its_table() {
    let index = std::fs::read_to_string("docs/README.md").unwrap();
    for t in tables() {
        let page = format!("docs/{}.md", t.name());
        let text = std::fs::read_to_string(&page).unwrap_or_else(|e| panic!("{page}: {e}"));
        let missing: Vec<String> = hairfit::families::table::markdown_table(t.parameters())
            .into_iter()
            .filter(|row| !text.lines().any(|l| l.trim() == row))
            .collect();
        assert!(missing.is_empty(), "{page} lacks:\n{}", missing.join("\n"));
        for term in t.terms() {
            assert!(
                text.contains(&format!("`{}`", term.name)),
                "{page}: term {}",
                term.name
            );
        }
        assert!(
            index.contains(&format!("({}.md)", t.name())),
            "docs/README.md links {page}"
        );
    }
}

fn table(name: &str) -> &'static dyn DynTable {
    hairfit::families::ModelFamily::parse(name)
        .unwrap()
        .table()
        .unwrap()
}

fn battery<F: TableFamily>() {
    let t = table(F::NAME);
    switched_off_terms_fit_none_of_their_parameters::<F>();
    noisy_fit_lands_within_standard_errors(t);
}

/// With a term off, a parameter only that term reads is not fitted (that the term's values
/// go with it is the family battery's check, `battery.rs`).
fn switched_off_terms_fit_none_of_their_parameters<F: TableFamily>() {
    let all = TermSet::all(F::TERMS.len());
    for k in 0..F::TERMS.len() {
        let without = TermSet(all.0 & !(1 << k));
        if without.0 == 0 {
            continue;
        }
        let free = hairfit::families::table::fitted(F::PARAMETERS, F::TERMS, without, 3, true);
        for (i, f) in F::PARAMETERS.iter().enumerate() {
            if f.terms == [F::TERMS[k].name] {
                assert!(
                    free.iter().all(|(j, _)| *j != i),
                    "{}: {} is fitted with {} off",
                    F::NAME,
                    f.name,
                    F::TERMS[k].name
                );
            }
        }
    }
}

/// Synthesize the demo geometry from the family's demo truth (`noise`: relative, 0 = none)
/// and fit it with the default options (2 starts are enough from the Latin hypercube).
fn synth_and_fit(t: &'static dyn DynTable, noise: f64) -> (TableParams<f64>, FitJson) {
    let family = ModelFamily::parse(t.name()).unwrap();
    let truth = demo_params(t.parameters(), 3);
    let file = FamilyParams::Table(TableParamFile::from_params(t, &truth));
    let setup = ModelSetup::default();
    let model = FamilyModel::new(&file, &setup);
    let noise = Noise::parse(&if noise > 0.0 {
        format!("relative:{noise}")
    } else {
        "none".into()
    })
    .unwrap();
    let source = Source {
        model: &model,
        file: &file,
        records: setup.records(family),
    };
    let how = Acquisition {
        directions: &demo_directions(),
        label: "test",
        noise: &noise,
        scale: &DEMO_SCALE,
        measurement: Measurement::S,
        seed: 7,
    };
    let (dataset, _) = hairfit::synth::synthesize_model(&source, &how).unwrap();
    let data = hairfit::fit::fit_data(&dataset);
    let opts = FitOptions {
        family,
        intervals: hairfit::fit::Intervals::Linear,
        ..FitOptions::default()
    };
    let out = fit_family(&data, "test.csv", LoadReport::default(), &opts).unwrap();
    (truth, out.json)
}

/// 2% relative noise on 2340 × 3 values: each free parameter within 4 standard errors of the
/// truth (the seed is fixed, so this is deterministic; 4 SE keeps a handful of parameters from
/// failing by chance at any seed while still catching a biased or wrong SE).
fn noisy_fit_lands_within_standard_errors(t: &'static dyn DynTable) {
    let (truth, fit) = synth_and_fit(t, 0.02);
    let file = TableParamFile::from_params(t, &truth);
    assert_eq!(
        fit.verdict,
        hairfit::files::Verdict::Good,
        "{:?}",
        fit.reasons
    );
    for e in fit
        .parameters
        .iter()
        .filter(|e| e.status == ParamStatus::Free)
    {
        let want = value_of(&file, &e.name);
        let (got, se) = (e.value.unwrap(), e.std_error.unwrap());
        assert!(
            (got - want).abs() <= 4.0 * se,
            "{}: {} = {got} ± {se}, truth {want}",
            t.name(),
            e.name
        );
    }
}

/// The file value of `name` (`k_d[1]` included) in `file`.
fn value_of(file: &TableParamFile, name: &str) -> f64 {
    let (base, channel) = match name.strip_suffix(']').and_then(|n| n.split_once('[')) {
        Some((b, c)) => (b, c.parse::<usize>().unwrap()),
        None => (name, 0),
    };
    let k = file
        .table
        .parameters()
        .iter()
        .position(|f| f.name == base)
        .unwrap();
    let v = &file.values[k];
    v[if v.len() == 1 { 0 } else { channel }]
}

/// A refused table file's message lists what the file holds, defaults as the family's page
/// writes them (seven significant digits, not a float's seventeen).
#[test]
fn a_refused_file_names_its_keys_and_defaults_as_the_page_does() {
    let path = std::path::Path::new("karis.json");
    let family = ModelFamily::parse("karis").unwrap();
    let err = FamilyParams::from_json_text(r#"{"model": "karis"}"#.into(), path, family)
        .unwrap_err()
        .to_string();
    assert!(err.contains("missing `base_color`"), "{err}");
    // The engine's 0.035 rad shift, in degrees.
    assert!(err.contains("shift_deg, optional, 2.005352"), "{err}");
    assert!(!err.contains("2.0053522829578814"), "{err}");
}
