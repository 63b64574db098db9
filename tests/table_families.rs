//! What every table family (`hairfit::table_family::ALL`) must do, checked for each one the same
//! way: exact derivatives, parameter files that read back what they wrote, term switches that
//! remove a term's values and parameters, and fits that recover the truth — noise-free to 1e-6
//! relative, with noise within a few standard errors. A family's own equations and invariants
//! are tested in its own file against an independent reference.

use hairfit::demo::{demo_directions, DEMO_SCALE};
use hairfit::family::{FamilyModel, FamilyParams, ModelFamily, ModelSetup};
use hairfit::files::{FitJson, LoadReport, ParamStatus};
use hairfit::fit::family::table::{TableForward, TableParam};
use hairfit::fit::problem::{FitParam, Forward};
use hairfit::fit::{fit_family, FitOptions};
use hairfit::model::{Angles, Measurement};
use hairfit::synth::{Acquisition, Noise, Source};
use hairfit::table_family::{
    demo_params, every_parameter, kajiya_kay::KajiyaKay, DynTable, TableFamily, TableParamFile,
    TableParams, TermSet, ALL,
};

/// The families this file runs its battery on; [`every_family_has_a_battery`] fails when a
/// family joins `table_family::ALL` without one.
const BATTERIES: &[&str] = &["kajiya-kay"];

#[test]
fn every_family_has_a_battery() {
    let all: Vec<&str> = ALL.iter().map(|t| t.name()).collect();
    assert_eq!(all, BATTERIES, "add the new family's battery test below");
}

#[test]
fn kajiya_kay() {
    battery::<KajiyaKay>();
}

/// Each family's page, docs/NAME.md, holds its parameter table exactly as the code has it, and
/// docs/README.md links the page.
#[test]
fn every_family_documents_its_table() {
    let index = std::fs::read_to_string("docs/README.md").unwrap();
    for t in ALL {
        let page = format!("docs/{}.md", t.name());
        let text = std::fs::read_to_string(&page).unwrap_or_else(|e| panic!("{page}: {e}"));
        let missing: Vec<String> = hairfit::table_family::markdown_table(t.facts())
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
    hairfit::table_family::by_name(name).unwrap()
}

/// A spread of direction pairs (radians) away from grazing, both sides of the specular cone,
/// forward and backward scattering.
fn directions() -> Vec<Angles> {
    let mut v = Vec::new();
    for (k, ti) in [-50.0, -20.0, 0.0, 15.0, 40.0].into_iter().enumerate() {
        for tr in [-45.0, -10.0, 5.0, 30.0, 60.0] {
            for pr in [-170.0, -95.0, -20.0, 0.0, 35.0, 120.0, 178.0] {
                let pi = 20.0 * k as f64 - 40.0;
                v.push(Angles::from_degrees(ti, pi, tr, pr));
            }
        }
    }
    v
}

fn battery<F: TableFamily>() {
    let t = table(F::NAME);
    jacobian_matches_central_differences::<F>(t);
    file_round_trips(t);
    terms_switch_off::<F>(t);
    noise_free_fit_recovers_truth(t);
    noisy_fit_lands_within_standard_errors(t);
}

/// The family's parameters for 3 channels nudged off the demo truth, so no derivative is
/// evaluated at a special point.
fn nudged(t: &dyn DynTable) -> TableParams<f64> {
    let mut p = demo_params(t.facts(), 3);
    for (k, values) in p.values.iter_mut().enumerate() {
        for (c, v) in values.iter_mut().enumerate() {
            *v *= 1.0 + 0.013 * (k + 2 * c + 1) as f64;
        }
    }
    p
}

/// The dual-number Jacobian is the derivative of the values: against central differences with
/// step `h = 1e-5·max(|x|, 1)`, whose truncation error is O(h²·S''') ≈ 1e-10 relative for
/// these smooth functions and whose rounding error is ≈ 1e-16/h ≈ 1e-11; 1e-6 relative (of
/// the row's largest entry) leaves room for curvature near lobe peaks and nothing more.
fn jacobian_matches_central_differences<F: TableFamily>(t: &dyn DynTable) {
    let p = nudged(t);
    let free: Vec<TableParam<F>> = every_parameter(F::PARAMETERS, 3)
        .into_iter()
        .map(TableParam::new)
        .collect();
    let forward = TableForward::<F>::new(TermSet::all(F::TERMS.len()), Measurement::S);
    let angles = directions();
    let m = angles.len() * 3;
    let (mut out, mut grad) = (vec![0.0; m], vec![0.0; m * free.len()]);
    forward.gradients(&p, &free, &angles, &mut out, &mut grad);
    let mut plain = vec![0.0; m];
    forward.values(&p, &angles, &mut plain);
    assert_eq!(
        out,
        plain,
        "{}: gradients' values differ from values",
        F::NAME
    );
    for (j, q) in free.iter().enumerate() {
        let x = q.get(&p);
        let h = 1e-5 * x.abs().max(1.0);
        let at = |dx: f64| {
            let mut pp = p.clone();
            q.set(&mut pp, x + dx);
            let mut o = vec![0.0; m];
            forward.values(&pp, &angles, &mut o);
            o
        };
        let (up, down) = (at(h), at(-h));
        for r in 0..m {
            let fd = (up[r] - down[r]) / (2.0 * h);
            let ad = grad[r * free.len() + j];
            let row_scale = (0..free.len())
                .map(|k| grad[r * free.len() + k].abs())
                .fold(out[r].abs(), f64::max);
            assert!(
                (fd - ad).abs() <= 1e-6 * row_scale.max(1e-300),
                "{} d/d{}: row {r} AD {ad} vs FD {fd}",
                F::NAME,
                q.json_name()
            );
        }
    }
}

/// A parameter file reads back as the parameters it was written from (JSON text round trip,
/// bit for bit), names its family, and is refused under another family's `--model`.
fn file_round_trips(t: &'static dyn DynTable) {
    let p = nudged(t);
    let file = TableParamFile::from_params(t, &p);
    let text = serde_json::to_string_pretty(&FamilyParams::Table(file.clone())).unwrap();
    let family = ModelFamily::parse(t.name()).unwrap();
    let back =
        FamilyParams::from_json_text(text.clone(), std::path::Path::new("p.json"), family).unwrap();
    assert_eq!(back, FamilyParams::Table(file.clone()), "{}", t.name());
    assert_eq!(back.family(), family);
    let read: FamilyParams = serde_json::from_str(&text).unwrap();
    assert_eq!(read, back, "fit.json's params read by the tag");
    let e = FamilyParams::from_json_text(text, std::path::Path::new("p.json"), ModelFamily::Chiang)
        .unwrap_err()
        .to_string();
    assert!(e.contains("p.json") && e.contains(t.name()), "{e}");
}

/// With one term off, S is the sum of the others (nothing of the term is computed) and a
/// parameter only that term reads is not fitted.
fn terms_switch_off<F: TableFamily>(t: &dyn DynTable) {
    let p = nudged(t);
    let angles = directions();
    let n = F::TERMS.len();
    let all = TermSet::all(n);
    let mut lobes_all = vec![[0.0; 3]; 3];
    for k in 0..n {
        let without = TermSet(all.0 & !(1 << k));
        if without.0 == 0 {
            continue;
        }
        let only = TermSet(1 << k);
        for a in &angles {
            let mut total = vec![0.0; 3];
            t.eval_batch(&p, all, std::slice::from_ref(a), &mut total);
            let (mut rest, mut term) = (vec![0.0; 3], vec![0.0; 3]);
            t.eval_batch(&p, without, std::slice::from_ref(a), &mut rest);
            t.eval_batch(&p, only, std::slice::from_ref(a), &mut term);
            t.by_lobe(&p, all, a, &mut lobes_all);
            for c in 0..3 {
                // Two sums of the same terms in different orders: equal to a few ulps.
                let sum = rest[c] + term[c];
                assert!(
                    (sum - total[c]).abs() <= 1e-12 * total[c].abs(),
                    "{}: terms do not add up at {a:?}",
                    F::NAME
                );
                let by_lobe: f64 = lobes_all[c].iter().sum();
                assert!((by_lobe - total[c]).abs() <= 1e-12 * total[c].abs());
            }
        }
        // What only term k reads is not fitted without it.
        let free = hairfit::table_family::fitted(F::PARAMETERS, F::TERMS, without, 3, true);
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
    let truth = demo_params(t.facts(), 3);
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

/// Noise-free data are an exact zero of the residual: every free parameter and scale is
/// recovered to 1e-6 relative (the solver's stopping tolerance, far above rounding).
fn noise_free_fit_recovers_truth(t: &'static dyn DynTable) {
    let (truth, fit) = synth_and_fit(t, 0.0);
    let file = TableParamFile::from_params(t, &truth);
    for e in fit
        .parameters
        .iter()
        .filter(|e| e.status == ParamStatus::Free)
    {
        let want = value_of(&file, &e.name);
        let got = e.value.unwrap();
        assert!(
            (got - want).abs() <= 1e-6 * want.abs().max(1e-3),
            "{}: {} = {got}, truth {want}",
            t.name(),
            e.name
        );
    }
    for (s, want) in fit.scale.iter().zip(DEMO_SCALE) {
        let got = s.value.unwrap();
        assert!(
            (got - want).abs() <= 1e-6 * want,
            "{}: scale {got}",
            t.name()
        );
    }
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
        .facts()
        .iter()
        .position(|f| f.name == base)
        .unwrap();
    let v = &file.values[k];
    v[if v.len() == 1 { 0 } else { channel }]
}
