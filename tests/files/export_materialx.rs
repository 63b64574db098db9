//! The MaterialX export loads in the real MaterialX (Python package `materialx`, installed by
//! scripts/install-test-tools.sh) with its standard library, and `validate()` passes. In the
//! default suite: a missing python3 or package FAILS with the command that installs it.

use crate::support;
use std::path::Path;

use hairfit::families::chiang::export::{export, write_export, Renderer};

/// Load `path` with the standard data libraries imported and validate it; Ok(()) or the
/// validation message. Panics (with the install command) when the tool is missing.
fn materialx_validate(path: &Path) -> Result<(), String> {
    let script = r#"
import sys
import MaterialX as mx
lib = mx.createDocument()
mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
doc = mx.createDocument()
mx.readFromXmlFile(doc, sys.argv[1])
doc.importLibrary(lib)
ok, message = doc.validate()
node = doc.getNode(sys.argv[2])
if node is None:
    ok, message = False, "no bsdf node " + sys.argv[2]
elif node.getNodeDef() is None:
    ok, message = False, "the bsdf node has no standard-library nodedef"
print("VALID" if ok else "INVALID: " + message)
"#;
    let out = support::export::test_python()
        .arg("-c")
        .arg(script)
        .arg(path)
        .arg(bsdf_name(path))
        .output()
        .unwrap_or_else(|e| {
            panic!("python3 is not runnable ({e}): run scripts/test (or scripts/install-test-tools.sh), which installs it into target/test-venv")
        });
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    if stderr.contains("No module named 'MaterialX'") {
        panic!("the MaterialX Python package is missing: run scripts/test (or scripts/install-test-tools.sh), which installs it into target/test-venv");
    }
    assert!(out.status.success(), "python3 failed: {stderr}");
    match stdout.trim() {
        "VALID" => Ok(()),
        other => Err(other.to_string()),
    }
}

/// The `chiang_hair_bsdf` node's name in a hairfit document.
fn bsdf_name(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    let at = text.find("<chiang_hair_bsdf name=\"").unwrap() + 24;
    text[at..].split('"').next().unwrap().to_string()
}

#[test]
fn materialx_document_validates_with_the_standard_library() {
    let root = tempfile::tempdir().unwrap();
    let dir = support::export::chiang_fit_dir(root.path(), "set_a", &support::export::set_a_rgb());
    let out = export(&dir, Renderer::Materialx).unwrap();
    let path = root.path().join("set_a.mtlx");
    write_export(&path, &out).unwrap();
    if let Err(message) = materialx_validate(&path) {
        panic!("MaterialX rejects the export: {message}\n{}", out.text);
    }

    // The check can fail: the same document with a wrong input type is rejected.
    let broken = out.text.replace(
        "name=\"ior\" type=\"float\"",
        "name=\"ior\" type=\"color3\"",
    );
    let bad = root.path().join("broken.mtlx");
    std::fs::write(&bad, broken).unwrap();
    assert!(
        materialx_validate(&bad).is_err(),
        "a wrong input type must not validate"
    );
}
