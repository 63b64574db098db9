//! `hairfit compare` end to end: on data made by one family, the ranking puts it first and
//! the findings name what the others lose and where; every listed family gets a fit directory,
//! a summary, a place in the ranking and an RMS per region in compare.json. Tests that list
//! families use `--models all` or the default, so a new family needs no change here.

use crate::support::cli;

use cli::{hairfit_ok, s as p, stdout, write};
use std::path::Path;

use hairfit::compare::Comparison;
use hairfit::families::ModelFamily;
use hairfit::plot::escape;

/// Synthesize with `model` and `params`, 2% relative noise, and compare.
fn compare_on(dir: &Path, model: &str, params: &str) -> (Comparison, String) {
    let truth = write(dir, &format!("{model}.json"), params);
    let data = dir.join(format!("{model}.csv"));
    hairfit_ok(&[
        "synth",
        "--model",
        model,
        "--params",
        p(&truth),
        "--rig",
        "azimuthal:incidences=15,30,45:steps=36",
        "--noise",
        "relative:0.02",
        "--seed",
        "3",
        "--output",
        p(&data),
    ]);
    let out = dir.join(format!("cmp_{model}"));
    let text = stdout(&hairfit_ok(&[
        "compare",
        p(&data),
        "--starts",
        "4",
        "--width-nodes",
        "256",
        "--no-progress",
        "--out",
        p(&out),
    ]));
    for f in [
        "compare.json",
        "index.html",
        "compare.svg",
        "compare.png",
        "marschner/fit.json",
        "marschner/params.json",
        "chiang/fit.json",
        "chiang/params.json",
        "chiang/index.html",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    (Comparison::load(&out.join("compare.json")).unwrap(), text)
}

/// Every listed family has its summary, its place in the ranking (sorted by AIC, ΔAIC
/// against the first), and an RMS in every region; the lobe regions come first.
fn assert_complete(c: &Comparison, families: &[ModelFamily]) {
    let listed: Vec<ModelFamily> = c.models.iter().map(|m| m.family).collect();
    assert_eq!(listed, families);
    let mut ranked: Vec<ModelFamily> = c.ranking.iter().map(|r| r.family).collect();
    ranked.sort_by_key(|f| families.iter().position(|g| g == f));
    assert_eq!(ranked, families);
    for w in c.ranking.windows(2) {
        assert!(w[0].aic <= w[1].aic);
    }
    for r in &c.ranking {
        let delta = r.aic - c.ranking[0].aic;
        assert!((r.delta_aic - delta).abs() <= 1e-9 * delta.abs().max(1.0));
        assert_eq!(r.tied_with_best, delta < hairfit::compare::AIC_TIE);
    }
    assert_eq!(c.regions[0].axis, "lobe");
    for region in c.regions.iter().filter(|r| r.n >= 3) {
        let named: Vec<ModelFamily> = region.rms.0.iter().map(|v| v.0).collect();
        assert_eq!(named, families, "{}", region.name);
    }
}

#[test]
fn compare_ranks_the_family_that_made_the_data_first() {
    let dir = tempfile::tempdir().unwrap();
    let both = [ModelFamily::Marschner, ModelFamily::Chiang];
    let (m, text) = compare_on(
        dir.path(),
        "marschner",
        r#"{"sigma_a": [0.3, 0.5, 0.9], "alpha_r_deg": -7, "beta_r_deg": 7.5, "k_g": 2, "w_c_deg": 15, "eccentricity": 0.9}"#,
    );
    assert_complete(&m, &both);
    assert_eq!(m.best(), Some(ModelFamily::Marschner), "{text}");
    let chiang = m.rank_of(ModelFamily::Chiang).unwrap();
    assert!(chiang.delta_aic > 0.0 && !chiang.tied_with_best, "{text}");
    assert_eq!(chiang.rank, 2);
    assert!(chiang.chi2_ratio.unwrap() > 1.0);
    assert!(text.contains("Marschner fits best"), "{text}");
    assert!(
        text.contains("Chiang loses against Marschner: ΔAIC"),
        "{text}"
    );
    // One line per family in rank order.
    let first = text.find("1  marschner").expect(&text);
    assert!(text.find("2  chiang").expect(&text) > first, "{text}");
    assert!(
        m.findings
            .iter()
            .any(|f| f.starts_with("Chiang misses the data most at")),
        "{:?}",
        m.findings
    );
    // The azimuthal rig measures on the specular cone only (θh = 0): the R and TT regions
    // have residuals, the TRT region (beside the cone) none, so it has no RMS.
    let lobes: Vec<(&str, bool)> = m
        .regions
        .iter()
        .filter(|r| r.axis == "lobe")
        .map(|r| (r.name.as_str(), r.n > 0 && !r.rms.0.is_empty()))
        .collect();
    assert_eq!(lobes, [("R", true), ("TT", true), ("TRT", false)]);
    assert!(m.scale_note.contains("not comparable"));

    let (c, text) = compare_on(
        dir.path(),
        "chiang",
        r#"{"sigma_a": [0.3, 0.5, 0.9], "beta_m": 0.25, "beta_n": 0.35, "alpha_deg": -2.5}"#,
    );
    assert_complete(&c, &both);
    assert_eq!(c.best(), Some(ModelFamily::Chiang), "{text}");
    assert!(c.rank_of(ModelFamily::Marschner).unwrap().delta_aic > 0.0);
    assert!(
        c.findings.iter().any(|f| f.starts_with("Marschner misses")),
        "{:?}",
        c.findings
    );
    // σ is in the data (relative noise), so χ² is a log-likelihood and AIC = χ² + 2k.
    for s in &c.models {
        assert!((s.aic - (s.chi2 + 2.0 * s.n_params as f64)).abs() < 1e-6 * s.aic.abs());
    }
}

/// A small 3-channel Marschner dataset (36 samples) for the tests of compare's rules, which
/// need data but no particular fit.
fn small_data(dir: &Path) -> std::path::PathBuf {
    let truth = write(
        dir,
        "truth.json",
        r#"{"sigma_a": [0.3, 0.5, 0.9], "alpha_r_deg": -7, "beta_r_deg": 7.5, "k_g": 2, "w_c_deg": 15, "eccentricity": 0.9}"#,
    );
    let data = dir.join("d.csv");
    hairfit_ok(&[
        "synth",
        "--params",
        p(&truth),
        "--rig",
        "azimuthal:incidences=15,30,45:steps=12",
        "--noise",
        "relative:0.02",
        "--output",
        p(&data),
    ]);
    data
}

/// compare's quickest options, then `extra`.
fn quick_compare<'a>(data: &'a Path, out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let mut a = vec![
        "compare",
        p(data),
        "--starts",
        "2",
        "--width-nodes",
        "128",
        "--intervals",
        "linear",
        "--no-progress",
        "--out",
        p(out),
    ];
    a.extend_from_slice(extra);
    a
}

/// [`quick_compare`] of `families` (named in `extra`): its `--width-nodes` only when a listed
/// family takes it (else it would be refused as an option of no listed family).
fn quick_compare_of<'a>(
    data: &'a Path,
    out: &'a Path,
    families: &[ModelFamily],
    extra: &[&'a str],
) -> Vec<&'a str> {
    let mut a = quick_compare(data, out, extra);
    if !families
        .iter()
        .any(|f| f.own_options().contains(&"--width-nodes"))
    {
        let at = a.iter().position(|a| *a == "--width-nodes").unwrap();
        a.drain(at..at + 2);
    }
    a
}

/// Every path under `dir` whose name marks a lock or a staging directory.
fn bookkeeping_inside(dir: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let entry = entry.unwrap();
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.contains("hairfit-lock") || name.contains("hairfit-stage") {
            found.push(entry.path().display().to_string());
        }
        if entry.path().is_dir() {
            found.extend(bookkeeping_inside(&entry.path()));
        }
    }
    found
}

/// The walkthrough found `.marschner.hairfit-lock` and `.chiang.hairfit-lock` inside a
/// finished compare's --out: each fit directory was locked on its own, beside it, i.e. inside
/// DIR. DIR is now published as one set, as `fit` publishes its --out: its one lock sits
/// beside DIR while the run lasts and goes with it, and a rerun into it replaces it whole.
#[test]
fn a_finished_compare_leaves_no_lock_or_staging_inside_its_out() {
    let dir = tempfile::tempdir().unwrap();
    let data = small_data(dir.path());
    let out = dir.path().join("cmp");
    for run in ["first", "rerun"] {
        hairfit_ok(&quick_compare(&data, &out, &[]));
        assert_eq!(bookkeeping_inside(&out), Vec::<String>::new(), "{run}");
        for f in ["compare.json", "marschner/fit.json", "chiang/index.html"] {
            assert!(out.join(f).is_file(), "{run}: {f} missing");
        }
        let beside: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains("hairfit-"))
            .collect();
        assert_eq!(
            beside,
            Vec::<String>::new(),
            "{run}: no lock left beside --out"
        );
    }
    // Each fit directory is still a fit's directory of its own.
    hairfit_ok(&["report", p(&out.join("chiang"))]);
}

/// `compare --out FILE` said "File exists (os error 17)"; it now says what `fit` says, naming
/// the option and the file, and leaves the file alone.
#[test]
fn compare_out_that_is_a_file_is_refused_like_fit_does() {
    let dir = tempfile::tempdir().unwrap();
    let data = small_data(dir.path());
    let file = write(dir.path(), "notes.txt", "mine");
    let out = cli::hairfit(&quick_compare(&data, &file, &[]));
    cli::assert_fails_with(
        &out,
        &["--out", "notes.txt", "that is a file, not a directory"],
    );
    assert!(
        !cli::stderr(&out).contains("os error"),
        "{}",
        cli::stderr(&out)
    );
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
}

/// `compare --fix k_g=2` failed only after the Marschner fit had run and been written (the
/// Chiang model has no k_g). Every --fix is now checked for both families before anything
/// is fitted: a parameter of one family names the family that lacks it and lists what both
/// have; nothing is written.
#[test]
fn compare_fix_is_checked_for_both_families_before_any_fit() {
    let dir = tempfile::tempdir().unwrap();
    let data = small_data(dir.path());
    let out = dir.path().join("cmp");
    let both = "sigma_a (every channel), sigma_a[c] (one channel), eta";
    for (fix, needles) in [
        (
            "k_g=2",
            &[
                "`k_g` is a Marschner parameter the Chiang model does not have",
                both,
            ][..],
        ),
        (
            "alpha_deg=-2",
            &[
                "`alpha_deg` is a Chiang parameter the Marschner model does not have",
                "--model chiang --fix alpha_deg=-2",
            ][..],
        ),
        (
            "bogus=1",
            &["neither model family has a parameter `bogus`", both][..],
        ),
        // Known only once the data load (3 channels), still before either fit.
        (
            "sigma_a[5]=0.3",
            &[
                "`sigma_a[5]` names a channel the data do not have",
                "3 channels",
            ][..],
        ),
    ] {
        let run = cli::hairfit(&quick_compare(&data, &out, &["--fix", fix]));
        cli::assert_fails_with(&run, needles);
        assert!(!out.exists(), "--fix {fix}: nothing may be written");
    }
    // What both families have is fixed in both fits.
    hairfit_ok(&quick_compare(&data, &out, &["--fix", "eta=1.6"]));
    let c = Comparison::load(&out.join("compare.json")).unwrap();
    for m in &c.models {
        let eta = serde_json::to_value(&m.params).unwrap()["eta"].as_f64();
        assert_eq!(eta, Some(1.6), "{}", m.family);
    }
}

/// `--models all` fits every family, each in DIR/<family>, ranked in one compare.json and
/// drawn in one figure; a list in another order is reported in that order.
#[test]
fn compare_models_lists_every_family_it_fits() {
    let dir = tempfile::tempdir().unwrap();
    // A small scan off the cone too (θ_i = 20°, θ_r from −72° to 72°), so every lobe region
    // has residuals.
    let truth = write(
        dir.path(),
        "truth.json",
        r#"{"sigma_a": [0.3, 0.5, 0.9], "alpha_r_deg": -7, "beta_r_deg": 7.5, "k_g": 2, "w_c_deg": 15, "eccentricity": 0.9}"#,
    );
    let data = dir.path().join("scan.csv");
    hairfit_ok(&[
        "synth",
        "--params",
        p(&truth),
        "--rig",
        "longitudinal:incidences=20:phi=0,60,180:steps=13:max=72",
        "--noise",
        "relative:0.02",
        "--output",
        p(&data),
    ]);
    let out = dir.path().join("all");
    let text = stdout(&hairfit_ok(&quick_compare(
        &data,
        &out,
        &["--models", "all"],
    )));
    let c = Comparison::load(&out.join("compare.json")).unwrap();
    assert_complete(&c, &ModelFamily::ALL);
    let lobes: Vec<(&str, bool)> = c
        .regions
        .iter()
        .filter(|r| r.axis == "lobe")
        .map(|r| (r.name.as_str(), r.n >= 3))
        .collect();
    assert_eq!(lobes, [("R", true), ("TT", true), ("TRT", true)]);
    for family in ModelFamily::ALL {
        for f in ["fit.json", "params.json", "index.html"] {
            assert!(out.join(family.as_str()).join(f).is_file(), "{family}/{f}");
        }
        assert!(text.contains(&format!(" {} ", family.as_str())), "{text}");
    }
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    for family in ModelFamily::ALL {
        assert!(
            html.contains(&format!("<th>RMS {}</th>", escape(family.title()))),
            "{family}"
        );
    }
    let svg = std::fs::read_to_string(out.join("compare.svg")).unwrap();
    for family in ModelFamily::ALL {
        // The key's text as plotters writes SVG text (an apostrophe as &apos;).
        assert!(
            svg.contains(&family.title().replace('\'', "&apos;")),
            "{family} not in the legend"
        );
    }

    let mut reversed: Vec<ModelFamily> = ModelFamily::ALL.to_vec();
    reversed.reverse();
    let list: Vec<&str> = reversed.iter().map(|f| f.as_str()).collect();
    let out = dir.path().join("reversed");
    hairfit_ok(&quick_compare(&data, &out, &["--models", &list.join(",")]));
    assert_complete(
        &Comparison::load(&out.join("compare.json")).unwrap(),
        &reversed,
    );

    // One family alone is a ranking of one.
    let out = dir.path().join("one");
    hairfit_ok(&quick_compare_of(
        &data,
        &out,
        &reversed[..1],
        &["--models", list[0]],
    ));
    let one = Comparison::load(&out.join("compare.json")).unwrap();
    assert_complete(&one, &reversed[..1]);
    assert!(
        one.findings[0].contains("the only family listed"),
        "{:?}",
        one.findings
    );
}

/// A bad --models is refused before the data load, naming what is wrong; nothing is written.
#[test]
fn compare_models_errors_name_the_valid_families() {
    let dir = tempfile::tempdir().unwrap();
    let data = small_data(dir.path());
    let out = dir.path().join("cmp");
    let names = ModelFamily::names();
    for (models, needles) in [
        (
            "marschner,bogus",
            vec!["--models", "unknown model family `bogus`", names.as_str()],
        ),
        ("chiang,Chiang", vec!["--models", "`Chiang` is named twice"]),
        (",", vec!["--models", "is empty", names.as_str()]),
    ] {
        let run = cli::hairfit(&quick_compare(&data, &out, &["--models", models]));
        cli::assert_fails_with(&run, &needles);
        assert!(!out.exists(), "--models {models}: nothing may be written");
    }
    // --model is not compare's: --models is.
    let run = cli::hairfit(&quick_compare(&data, &out, &["--model", "chiang"]));
    cli::assert_fails_with(&run, &["drop --model", "--models chiang"]);
}

/// A family-only option goes to the listed families that take it; when none does, it is an
/// error naming the families that do, before anything is fitted.
#[test]
fn a_family_option_no_listed_family_takes_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let data = small_data(dir.path());
    let out = dir.path().join("cmp");
    for family in ModelFamily::ALL {
        let others: Vec<ModelFamily> = ModelFamily::ALL
            .into_iter()
            .filter(|&f| f != family)
            .collect();
        // An option only `family` takes, with the others listed alone.
        let Some(&flag) = family
            .own_options()
            .iter()
            .find(|f| others.iter().all(|o| !o.own_options().contains(f)))
        else {
            continue;
        };
        let Some(other) = others.first() else {
            continue;
        };
        let mut extra = vec!["--models", other.as_str(), flag];
        match flag {
            "--mode" => extra.push("exact"),
            "--lobes" | "--terms" => extra.push("R"),
            "--width-nodes" => extra.push("64"),
            _ => {}
        }
        let run = cli::hairfit(&quick_compare_of(&data, &out, &[*other], &extra));
        cli::assert_fails_with(
            &run,
            &[
                &format!("{flag} applies to --model"),
                family.as_str(),
                &format!("--models lists {other}"),
            ],
        );
        assert!(!out.exists(), "{flag}: nothing may be written");
    }
}

/// A family-only option several listed families take goes to each of them with the same
/// value; a value one of them refuses says so.
#[test]
fn an_option_several_families_take_goes_to_each() {
    let takers: Vec<ModelFamily> = ModelFamily::ALL
        .into_iter()
        .filter(|f| f.own_options().contains(&"--terms"))
        .collect();
    if takers.len() < 2 {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let data = small_data(dir.path());
    let out = dir.path().join("cmp");
    let list: Vec<&str> = takers.iter().map(|f| f.as_str()).collect();
    let list = list.join(",");
    let run = cli::hairfit(&quick_compare_of(
        &data,
        &out,
        &takers,
        &["--models", &list, "--terms", "no-such-term"],
    ));
    cli::assert_fails_with(
        &run,
        &["compare gives --terms to every listed family that takes it"],
    );
    assert!(!out.exists());
}

/// Issue 27's check: with every family listed, data synthesized from Marschner 2003 rank
/// Marschner first and data synthesized from Karis 2016 rank Karis first, every other family
/// behind it by more than the AIC tie margin, and the summary states what each one loses. The
/// scan covers the three lobes at three incidences with 2% noise: enough that a wrong family
/// misses by hundreds of AIC units, where the generating one sits at χ² ≈ N.
#[test]
fn compare_all_ranks_the_generating_family_first() {
    let dir = tempfile::tempdir().unwrap();
    let truths = [
        (
            ModelFamily::Marschner,
            r#"{"sigma_a": [0.3, 0.5, 0.9], "alpha_r_deg": -7, "beta_r_deg": 7.5, "k_g": 2, "w_c_deg": 15, "eccentricity": 0.9}"#,
        ),
        (
            ModelFamily::Karis,
            r#"{"model": "karis", "base_color": [0.2, 0.45, 0.7], "roughness": 0.4, "specular": 0.6, "scatter": 0}"#,
        ),
    ];
    for (family, params) in truths {
        let name = family.as_str();
        let truth = write(dir.path(), &format!("{name}.json"), params);
        let data = dir.path().join(format!("{name}.csv"));
        hairfit_ok(&[
            "synth",
            "--model",
            name,
            "--params",
            p(&truth),
            "--rig",
            "longitudinal:incidences=10,30,50:phi=0,45,90,135,180:steps=15:max=75",
            "--noise",
            "relative:0.02",
            "--seed",
            "5",
            "--output",
            p(&data),
        ]);
        let out = dir.path().join(format!("all_{name}"));
        let text = stdout(&hairfit_ok(&quick_compare(
            &data,
            &out,
            &["--models", "all"],
        )));
        let c = Comparison::load(&out.join("compare.json")).unwrap();
        assert_eq!(c.best(), Some(family), "{text}");
        for r in &c.ranking[1..] {
            assert!(
                r.delta_aic > hairfit::compare::AIC_TIE && !r.tied_with_best,
                "{} against {name}: {text}",
                r.family
            );
            let loses = format!("{} loses against {}", r.family.title(), family.title());
            assert!(
                c.findings.iter().any(|f| f.starts_with(&loses)),
                "{loses}: {:?}",
                c.findings
            );
        }
    }
}

/// Every fit of a comparison records the loader's settings and warnings as `hairfit fit` does:
/// the fit takes them from the loader's report, so no command adds them afterwards (compare's
/// fits lacked the warnings before). Angles that look like radians are the loader's warning.
#[test]
fn each_compared_fit_records_the_loaders_settings_and_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let data = small_data(dir.path());
    // The same samples with their angles in radians and no unit line: read as degrees, they
    // all lie within ±π, which the loader warns about.
    let text = std::fs::read_to_string(&data).unwrap();
    let mut rows = Vec::new();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let cells: Vec<String> = line
            .split(',')
            .enumerate()
            .map(|(k, c)| match c.parse::<f64>() {
                Ok(v) if k < 4 => (v.to_radians()).to_string(),
                _ => c.to_string(),
            })
            .collect();
        rows.push(cells.join(","));
    }
    let radians = write(dir.path(), "radians.csv", rows.join("\n") + "\n");
    let out = dir.path().join("C");
    let families = [ModelFamily::KajiyaKay, ModelFamily::Karis];
    hairfit_ok(&quick_compare_of(
        &radians,
        &out,
        &families,
        &["--models", "kajiya-kay,karis"],
    ));
    for f in families {
        let path = out.join(f.as_str()).join("fit.json");
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let first = json["warnings"][0].as_str().unwrap_or("");
        assert!(
            first.starts_with("angles look like radians"),
            "{}: warnings {}",
            path.display(),
            json["warnings"]
        );
        assert!(
            json["options"]["load"].is_string(),
            "{}: options.load {}",
            path.display(),
            json["options"]["load"]
        );
    }
}
