//! `hairfit export --to unreal`: a Karis fit exports as its own inputs (the engine renders that
//! model), a fit made under other constants or of another family exports with a stated loss,
//! the JSON names the parent material's parameters and the engine version, the script is valid
//! Python that sets exactly those values (run against a stand-in `unreal` module), and the
//! output names and fits the export refuses.

use crate::support;
use crate::support::cli;

use std::path::{Path, PathBuf};
use std::process::Command;

use cli::{hairfit, hairfit_ok, s, stderr, stdout};
use hairfit::families::karis::export::{self as unreal, files::DEFAULT_PARENT};
use serde_json::{json, Value};

/// `root/name` holding a Karis fit: params.json as `hairfit fit` writes it, a fit.json with the
/// terms it ran with.
fn karis_fit_dir(root: &Path, name: &str, params: Value, terms: &[&str]) -> PathBuf {
    let dir = root.join(name);
    std::fs::create_dir_all(&dir).unwrap();
    let mut params = params;
    params["model"] = json!("karis");
    let channels = match params["base_color"].as_array().map(Vec::len) {
        Some(3) => json!(["r", "g", "b"]),
        Some(n) => json!(vec!["s"; n]),
        None => json!(["grey"]),
    };
    std::fs::write(dir.join("params.json"), params.to_string()).unwrap();
    let fit = json!({
        "hairfit_version": "test",
        "status": "converged",
        "data": { "channels": channels },
        "residuals": { "space": "log", "rms": 1.0, "reduced_chi2": 1.0 },
        "terms": terms,
        "params": params,
    });
    std::fs::write(dir.join("fit.json"), fit.to_string()).unwrap();
    dir
}

fn brown() -> Value {
    json!({"base_color": [0.2, 0.4, 0.6], "roughness": 0.45, "specular": 0.4, "scatter": 0.0})
}

/// The engine evaluates the Karis model, so a Karis fit with the engine's η and shift exports
/// as itself: every input to 1e-9, gain 1, rms |Δ ln S| below 1e-9, and no warning.
#[test]
fn a_karis_fit_exports_its_own_inputs() {
    let root = tempfile::tempdir().unwrap();
    let dir = karis_fit_dir(root.path(), "brown", brown(), &["R", "TT", "TRT"]);
    let out = unreal::export(&dir).unwrap();
    let m = &out.mapping;
    assert!(
        m.errors.rms < 1e-9 && m.errors.max < 1e-9,
        "{}",
        m.quality_text()
    );
    assert_eq!(m.as_fitted, Some((0.0, 0.0)));
    assert!(out.warnings.is_empty(), "{:?}", out.warnings);
    let json: Value = serde_json::from_str(&out.json).unwrap();
    let p = &json["parameters"];
    let close = |v: &Value, want: f64| (v.as_f64().unwrap() - want).abs() < 1e-9;
    for (c, want) in [0.2, 0.4, 0.6].into_iter().enumerate() {
        assert!(close(&p["BaseColor"][c], want), "{p}");
    }
    for (key, want) in [
        ("Roughness", 0.45),
        ("Specular", 0.4),
        ("Backlit", 1.0),
        ("Scatter", 0.0),
    ] {
        assert!(close(&p[key], want), "{key}: {p}");
    }
    assert!(close(&json["light_gain"], 1.0));
    assert_eq!(json["engine"]["versions"], "Unreal Engine 5.0-5.3");
    assert_eq!(json["held"], json!({"eta": 1.55, "shift_rad": 0.035}));
    assert_eq!(json["source"]["model"], "Karis 2016 (Unreal Engine 5)");
    assert_eq!(json["source"]["params"]["roughness"], 0.45);
    assert_eq!(json["mapping"]["n_sphere"], 1573);
}

/// A Karis fit made with η freed (1.6) is not what the engine renders (it hard-codes 1.55): the
/// export says what passing it on unchanged would cost, refits, and the refit costs less.
#[test]
fn a_karis_fit_off_the_engines_constants_is_refitted_with_a_warning() {
    let root = tempfile::tempdir().unwrap();
    let mut params = brown();
    params["eta"] = json!(1.6);
    let dir = karis_fit_dir(root.path(), "eta", params, &["R", "TT", "TRT"]);
    let out = unreal::export(&dir).unwrap();
    let m = &out.mapping;
    let (as_is, _) = m.as_fitted.unwrap();
    eprintln!("as fitted {as_is}, refitted {}", m.errors.rms);
    assert!(as_is > 1e-3, "{as_is}");
    assert!(m.errors.rms < as_is, "{} vs {as_is}", m.errors.rms);
    assert!(
        out.warnings.iter().any(|w| w.contains("eta")),
        "{:?}",
        out.warnings
    );
    assert!(out
        .script
        .contains("# WARNING: the Karis fit's own parameters"));
}

/// Scatter is one of the inputs: a fit with the scatter term gets it back, and the export says
/// what hair strands (which ignore Scatter) lose.
#[test]
fn scatter_is_exported_and_its_absence_on_strands_stated() {
    let root = tempfile::tempdir().unwrap();
    let mut params = brown();
    params["scatter"] = json!(0.3);
    let dir = karis_fit_dir(root.path(), "ms", params, &["R", "TT", "TRT", "scatter"]);
    let out = unreal::export(&dir).unwrap();
    let m = &out.mapping;
    assert!((m.inputs.scatter - 0.3).abs() < 1e-9, "{:?}", m.inputs);
    let (without, _) = m.without_scatter.unwrap();
    assert!(without > 0.01, "{without}");
    assert!(out
        .warnings
        .iter()
        .any(|w| w.contains("hair strands ignore it")));
}

/// A Marschner fit: the engine's inputs are fitted to its S with one gain; the loss is finite,
/// clearly not zero (Marschner's lobes are not Karis's), and stated in the JSON and the summary.
#[test]
fn a_marschner_fit_exports_with_a_stated_loss() {
    let root = tempfile::tempdir().unwrap();
    let dir = support::export::marschner_fit_dir(root.path(), "m");
    let out = unreal::export(&dir).unwrap();
    let m = &out.mapping;
    eprintln!("{}\n{:?}", m.quality_text(), m.inputs);
    assert!(
        m.errors.rms.is_finite() && m.errors.rms > 0.01,
        "{}",
        m.errors.rms
    );
    let json: Value = serde_json::from_str(&out.json).unwrap();
    assert_eq!(json["mapping"]["rms_log"].as_f64(), Some(m.errors.rms));
    assert_eq!(json["source"]["model"], "Marschner");
    let colour = json["parameters"]["BaseColor"].as_array().unwrap();
    assert!(
        colour[0] == colour[1] && colour[1] == colour[2],
        "grey: {colour:?}"
    );
    assert!(out.summary.contains("from the Marschner fit"));
    assert!(out
        .summary
        .contains(&format!("rms |d ln S| {:.4}", m.errors.rms)));
}

/// Engines take RGB: a 2-channel fit is refused as the renderer exports refuse it.
#[test]
fn a_two_channel_fit_is_refused() {
    let root = tempfile::tempdir().unwrap();
    let params = json!({"base_color": [0.2, 0.4], "roughness": 0.45, "specular": 0.4,
        "scatter": 0.0});
    let dir = karis_fit_dir(root.path(), "two", params, &["R", "TT", "TRT"]);
    let err = unreal::export(&dir).unwrap_err().to_string();
    assert!(err.contains("2 channels") && err.contains("RGB"), "{err}");
}

/// Run `script` with the stand-in `unreal` module (tests/unreal_stub), the given parent
/// materials and arguments: (exit status ok, stderr, the recorded instances).
fn run_script(script: &Path, parents: Value, args: &[&str]) -> (bool, String, Value) {
    let dir = script.parent().unwrap();
    let record = dir.join("record.json");
    let _ = std::fs::remove_file(&record);
    let stub = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/unreal_stub");
    let out = Command::new("python3")
        .arg(script)
        .args(args)
        .env("PYTHONPATH", &stub)
        .env("HAIRFIT_UNREAL_STUB_PARENTS", parents.to_string())
        .env("HAIRFIT_UNREAL_STUB_OUT", &record)
        .output()
        .expect("python3 runs (the export tests need it)");
    let recorded = std::fs::read_to_string(&record)
        .ok()
        .map_or(Value::Null, |t| serde_json::from_str(&t).unwrap());
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
        recorded,
    )
}

/// Through the binary: `--output hair.json` writes hair.json and hair.py; the script compiles
/// (`python3 -m py_compile`), and run against the stand-in module it creates the instance of
/// the default parent (or of one named on its command line) with exactly the JSON's values,
/// updates and saves it; a parent lacking a parameter is an error naming it.
#[test]
fn the_script_sets_the_jsons_values_on_an_instance_of_the_parent() {
    let root = tempfile::tempdir().unwrap();
    let dir = karis_fit_dir(root.path(), "brown", brown(), &["R", "TT", "TRT"]);
    let file = root.path().join("out/hair.json");
    let run = hairfit_ok(&["export", s(&dir), "--to", "unreal", "--output", s(&file)]);
    let script = root.path().join("out/hair.py");
    assert!(stderr(&run).contains(&format!("wrote {} and {}", s(&file), s(&script))));
    assert!(stdout(&run).is_empty());
    let compiled = Command::new("python3")
        .args(["-m", "py_compile", s(&script)])
        .output()
        .expect("python3 runs");
    assert!(compiled.status.success(), "{:?}", compiled);

    let json: Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    let p = &json["parameters"];
    let names = json!([
        ["Roughness", "Specular", "Backlit", "Scatter"],
        ["BaseColor"]
    ]);
    let parents = json!({ DEFAULT_PARENT: names, "/Game/Other/M_Hair": names });
    let (ok, err, recorded) = run_script(&script, parents.clone(), &[]);
    assert!(ok, "{err}");
    let instance = &recorded[0];
    assert_eq!(instance["path"], "/Game/Hairfit/MI_hairfit_brown");
    assert_eq!(instance["parent"], DEFAULT_PARENT);
    assert_eq!(instance["updated"], true);
    assert_eq!(instance["saved"], true);
    for key in ["Roughness", "Specular", "Backlit", "Scatter"] {
        assert_eq!(instance["scalars"][key], p[key], "{key}");
    }
    let mut colour = p["BaseColor"].as_array().unwrap().clone();
    colour.push(json!(1.0));
    assert_eq!(instance["vectors"]["BaseColor"], Value::Array(colour));

    let (ok, err, recorded) = run_script(&script, parents, &["/Game/Other/M_Hair"]);
    assert!(ok, "{err}");
    assert_eq!(recorded[0]["parent"], "/Game/Other/M_Hair");

    let lacking = json!({ DEFAULT_PARENT: [["Roughness", "Specular", "Scatter"], ["BaseColor"]] });
    let (ok, err, _) = run_script(&script, lacking, &[]);
    assert!(!ok && err.contains("lacks the parameters Backlit"), "{err}");
}

/// Without --output the JSON goes to stdout (and the summary says the script needs --output);
/// names that are another target's (.py is Blender's, .json is Unreal's for --to pbrt) and the
/// fit's own files are refused before any work; an unknown target lists unreal.
#[test]
fn outputs_are_named_as_the_other_exports_name_theirs() {
    let root = tempfile::tempdir().unwrap();
    let dir = karis_fit_dir(root.path(), "brown", brown(), &["R", "TT", "TRT"]);
    let run = hairfit_ok(&["export", s(&dir), "--to", "unreal"]);
    let json: Value = serde_json::from_str(&stdout(&run)).unwrap();
    assert_eq!(json["hairfit_export"], "unreal");
    assert!(stderr(&run).contains("the Python script is written with --output"));

    let py = root.path().join("x.py");
    let out = hairfit(&["export", s(&dir), "--to", "unreal", "--output", s(&py)]);
    cli::assert_fails_with(
        &out,
        &[
            ".py is the extension of a Blender Python script (--to blender)",
            "--to unreal writes an Unreal material-parameter file",
            &format!("name the file {}", s(&py.with_extension("json"))),
        ],
    );
    let json_out = root.path().join("x.json");
    let out = hairfit(&["export", s(&dir), "--to", "pbrt", "--output", s(&json_out)]);
    cli::assert_fails_with(
        &out,
        &[".json is the extension of an Unreal", "--to unreal"],
    );
    let own = dir.join("fit.json");
    let before = std::fs::read_to_string(&own).unwrap();
    let out = hairfit(&["export", s(&dir), "--to", "unreal", "--output", s(&own)]);
    cli::assert_fails_with(&out, &["would replace the fit", "fit.json"]);
    assert_eq!(std::fs::read_to_string(&own).unwrap(), before);
    let out = hairfit(&["export", s(&dir), "--to", "unity3"]);
    assert!(stderr(&out).contains("pbrt, blender, materialx, unreal or unity"));
    assert!(!py.exists() && !json_out.exists());
}
