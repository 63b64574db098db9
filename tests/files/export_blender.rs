//! Blender as a Python module (`bpy`, scripts/install-test-tools.sh --with-bpy) runs the
//! exported script, finds the material and every input value, and renders a wisp of hair curves
//! with Cycles to fits/export/demo_blender.png. Ignored by default (bpy is a ~400 MB install
//! and the render takes a minute):
//! `cargo test --release --test files export_blender:: -- --ignored`.

use crate::support;
use std::path::Path;

use hairfit::families::chiang::export::{export, write_export, Renderer};

#[test]
#[ignore = "needs bpy (scripts/install-test-tools.sh --with-bpy); renders with Cycles"]
fn blender_runs_the_export_and_renders_it() {
    let probe = support::export::test_python()
        .args(["-c", "import bpy"])
        .output();
    match probe {
        Ok(o) if o.status.success() => {}
        _ => panic!("bpy is missing: run scripts/install-test-tools.sh --with-bpy"),
    }
    let root = tempfile::tempdir().unwrap();
    let out = export(Path::new("fits/demo"), Renderer::Blender).unwrap();
    let script = root.path().join("demo_blender.py");
    write_export(&script, &out).unwrap();
    let png = Path::new("fits/export/demo_blender.png");
    let run = support::export::test_python()
        .arg("tests/export_blender_render.py")
        .arg(&script)
        .arg(png)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for key in [
        "Absorption Coefficient",
        "Roughness",
        "Radial Roughness",
        "IOR",
        "Offset",
    ] {
        assert!(stdout.contains(&format!("input {key}:")), "{key}: {stdout}");
    }
    let bytes = std::fs::read(png).unwrap();
    assert!(bytes.starts_with(b"\x89PNG"), "not a PNG");
}
