//! `hairfit export --to unity`: a frostbite fit exports its own inputs (HDRP evaluates the same
//! model, so the mapping is exact); a Marschner fit exports with a finite, stated loss; the two
//! files are what Unity reads (JSON with the inputs, a C# editor script setting them); and the
//! output names and fits that cannot be exported are refused as for the other renderers.

use crate::support::cli;

use std::path::{Path, PathBuf};

use std::process::Output;

use crate::support::export::marschner_fit_dir;
use cli::{failed, hairfit, stderr};
use hairfit::export::SourceFit;
use hairfit::families::frostbite::export::fit_unity;

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// `root/name` holding a frostbite fit: params.json in the family's file form and a minimal
/// fit.json (with `terms` when given); no curves.csv, so the mapping covers the sphere.
fn frostbite_fit_dir(root: &Path, name: &str, params: &str, terms: Option<&[&str]>) -> PathBuf {
    let dir = root.join(name);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("params.json"), params).unwrap();
    let mut fit = serde_json::json!({
        "hairfit_version": "test",
        "status": "converged",
        "data": { "channels": ["r", "g", "b"] },
        "residuals": { "space": "log", "rms": 1.0, "reduced_chi2": 1.0 }
    });
    if let Some(t) = terms {
        fit["terms"] = serde_json::json!(t);
    }
    std::fs::write(dir.join("fit.json"), fit.to_string()).unwrap();
    dir
}

/// `hairfit export DIR --to unity --output JSON`, whatever its exit status.
fn to_unity(dir: &Path, json: &Path) -> Output {
    hairfit(&["export", p(dir), "--to", "unity", "--output", p(json)])
}

/// The stderr of a successful `--to unity` export.
fn exported(dir: &Path, json: &Path) -> String {
    stderr(&cli::succeeded(to_unity(dir, json), &["export --to unity"]))
}

const BROWN: &str = r#"{"model": "frostbite", "base_color": [0.3, 0.18, 0.08],
    "smoothness": 0.82, "radial_smoothness": 0.6, "cuticle_angle_deg": 2.5}"#;

/// HDRP renders the frostbite family itself: the mapping starts at the fit's own inputs and
/// stays there, |Δ ln S| at rounding level, every input within 1e-9 and the gain 1.
#[test]
fn a_frostbite_fit_exports_its_own_inputs() {
    let root = tempfile::tempdir().unwrap();
    let dir = frostbite_fit_dir(root.path(), "brown", BROWN, None);
    let m = fit_unity(&SourceFit::load(&dir).unwrap()).unwrap();
    assert!(m.errors.rms < 1e-12 && m.errors.max < 1e-10, "{m:?}");
    let u = &m.inputs;
    for (got, want) in u.base_color.iter().zip([0.3, 0.18, 0.08]) {
        assert!((got - want).abs() < 1e-9, "{u:?}");
    }
    for (got, want) in [
        (u.smoothness, 0.82),
        (u.radial_smoothness, 0.6),
        (u.cuticle_angle_deg, 2.5),
        (u.gain, 1.0),
    ] {
        assert!((got - want).abs() < 1e-9, "{u:?}");
    }
}

/// Through the binary: NAME.json and NAME.cs beside it; the JSON holds the inputs, the HDRP
/// conventions, the mapping's error and the source; the script sets every input by the property
/// names declared once at its top and validates the material.
#[test]
fn the_cli_writes_the_json_and_the_editor_script() {
    let root = tempfile::tempdir().unwrap();
    let dir = frostbite_fit_dir(root.path(), "brown", BROWN, None);
    let json = root.path().join("out").join("brown_unity.json");
    std::fs::create_dir_all(json.parent().unwrap()).unwrap();
    let err = exported(&dir, &json);
    assert!(
        err.contains("rms |d ln S| 0.0000") && err.contains("brown_unity.cs"),
        "{err}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["engine"], "Unity HDRP");
    assert!(v["conventions"].as_str().unwrap().contains("HDRP 17"));
    assert_eq!(v["held"]["ior"], 1.55);
    assert_eq!(v["script"], "brown_unity.cs");
    let material = &v["material"];
    assert!((material["smoothness"].as_f64().unwrap() - 0.82).abs() < 1e-9);
    assert!((material["cuticle_angle_deg"].as_f64().unwrap() - 2.5).abs() < 1e-9);
    let srgb = material["base_color_srgb"][0].as_f64().unwrap();
    assert!(
        (srgb - (1.055 * 0.3f64.powf(1.0 / 2.4) - 0.055)).abs() < 1e-9,
        "{srgb}"
    );
    assert!(v["mapping"]["rms_abs_d_ln_s"].as_f64().unwrap() < 1e-12);
    assert_eq!(v["source_fit"]["channels_as_rgb"][2], "b");

    let cs = std::fs::read_to_string(json.with_extension("cs")).unwrap();
    for needle in [
        "using UnityEngine.Rendering.HighDefinition;",
        "public static class hairfit_brown",
        "const string SmoothnessProperty = \"_Smoothness\";",
        "new Color(0.3f, 0.18f, 0.08f, 1f)",
        "const float Smoothness = 0.82f;",
        "const float RadialSmoothness = 0.6f;",
        "const float CuticleAngleDegrees = 2.5f;",
        "material.SetColor(BaseColorProperty, color);",
        "material.SetFloat(CuticleAngleProperty, CuticleAngleDegrees);",
        "HDMaterial.ValidateMaterial(material);",
        "[MenuItem(\"Tools/hairfit/",
    ] {
        assert!(cs.contains(needle), "script lacks `{needle}`:\n{cs}");
    }
    // Balanced braces, and the whole class inside the editor-only guard.
    assert_eq!(cs.matches('{').count(), cs.matches('}').count());
    assert!(cs.find("#if UNITY_EDITOR") < cs.find("public static class"));
    assert!(cs.trim_end().ends_with("#endif"));
}

/// A Marschner fit is another model: the mapping ends with a finite loss (0.05 < rms < 1 on
/// this fit: Marschner's 1/cos²θ_d, eccentricity and glints have no HDRP input), stated in the
/// JSON and on stderr alike.
#[test]
fn a_marschner_fit_exports_with_a_finite_stated_loss() {
    let root = tempfile::tempdir().unwrap();
    let dir = marschner_fit_dir(root.path(), "m");
    let json = root.path().join("m.json");
    let err = exported(&dir, &json);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rms = v["mapping"]["rms_abs_d_ln_s"].as_f64().unwrap();
    let max = v["mapping"]["max_abs_d_ln_s"].as_f64().unwrap();
    println!("Marschner fit to Unity: rms {rms:.4}, max {max:.3}");
    assert!(rms.is_finite() && rms > 0.05 && rms < 1.0, "{rms}");
    assert!(max >= rms);
    assert!(err.contains(&format!("rms |d ln S| {rms:.4}")));
    assert_eq!(v["source_fit"]["model"], "Marschner");
}

/// What HDRP cannot render of a frostbite fit is said: terms switched off (HDRP always adds R,
/// TT and TRT) and a freed η (HDRP fixes 1.55); the inputs are refitted, with a loss.
#[test]
fn what_hdrp_cannot_render_is_warned_about() {
    let root = tempfile::tempdir().unwrap();
    let dir = frostbite_fit_dir(root.path(), "r", BROWN, Some(&["R"]));
    let m = fit_unity(&SourceFit::load(&dir).unwrap()).unwrap();
    assert!(m.errors.rms > 1e-3, "{m:?}");
    let json = root.path().join("r.json");
    let err = exported(&dir, &json);
    assert!(
        err.contains("warning: the fit ran with terms R only"),
        "{err}"
    );

    let eta = BROWN.replace(
        "\"cuticle_angle_deg\": 2.5",
        "\"cuticle_angle_deg\": 2.5, \"eta\": 1.7",
    );
    let dir = frostbite_fit_dir(root.path(), "eta", &eta, None);
    let json = root.path().join("eta.json");
    let err = exported(&dir, &json);
    assert!(err.contains("freed eta (1.7000)"), "{err}");
}

/// Output names: `--to unity` needs `--output` (two files cannot go to stdout); the JSON may
/// not be named `.cs` (the script's name) or with another renderer's extension, nor be a
/// directory; and the other renderers now refuse `.json`. All before any fitting.
#[test]
fn output_names_are_checked_as_for_the_other_renderers() {
    let root = tempfile::tempdir().unwrap();
    let dir = frostbite_fit_dir(root.path(), "brown", BROWN, None);
    let e = failed(&hairfit(&["export", p(&dir), "--to", "unity"]));
    assert!(e.contains("--output NAME.json"), "{e}");
    let cs = root.path().join("hair.cs");
    let e = failed(&to_unity(&dir, &cs));
    assert!(e.contains("hair.json") && e.contains(".cs"), "{e}");
    let mtlx = root.path().join("hair.mtlx");
    let e = failed(&to_unity(&dir, &mtlx));
    assert!(e.contains("--to materialx"), "{e}");
    let e = failed(&to_unity(&dir, root.path()));
    assert!(e.contains("directory"), "{e}");
    let json = root.path().join("hair.json");
    let e = failed(&hairfit(&[
        "export",
        p(&dir),
        "--to",
        "pbrt",
        "--output",
        p(&json),
    ]));
    assert!(e.contains("--to unity"), "{e}");
    let e = failed(&hairfit(&["export", p(&dir), "--to", "unreal-ish"]));
    assert!(e.contains("unity"), "{e}");
    assert!(!cs.exists() && !json.exists() && !mtlx.exists());
}

/// Unity takes RGB: a two-channel fit is refused, as for every renderer.
#[test]
fn a_fit_that_is_not_rgb_is_refused() {
    let root = tempfile::tempdir().unwrap();
    let two = r#"{"model": "frostbite", "base_color": [0.3, 0.2], "smoothness": 0.8,
        "radial_smoothness": 0.7, "cuticle_angle_deg": 3}"#;
    let dir = root.path().join("two");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("params.json"), two).unwrap();
    std::fs::write(dir.join("fit.json"), "{}").unwrap();
    let json = root.path().join("two.json");
    let e = failed(&to_unity(&dir, &json));
    assert!(e.contains("2 channels") && e.contains("RGB"), "{e}");
}
