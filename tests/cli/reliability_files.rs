//! Output files are ordinary files: written atomically through a temporary file, they must still
//! get the permissions any other file the user creates gets (mode 0666 minus the umask), not the
//! temporary file's private 0600.

#![cfg(unix)]

use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::time::Duration;

use crate::support::hard::*;
use hairfit::demo::{demo_geometry, DEMO_SCALE};
use hairfit::families::marschner::demo::demo_truth;
use hairfit::families::marschner::fit::synthetic::synthesize;
use hairfit::families::marschner::ModelConfig;

fn mode(path: &Path) -> u32 {
    std::fs::metadata(path).unwrap().permissions().mode() & 0o777
}

#[test]
fn outputs_get_the_permissions_of_an_ordinary_new_file() {
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("reference");
    std::fs::File::create(&reference).unwrap();
    let expected = mode(&reference);

    let data = dir.path().join("demo.csv");
    let d = synthesize(
        &demo_truth(),
        &ModelConfig::default(),
        &demo_geometry()[..300],
        &DEMO_SCALE,
        0.02,
        1,
    );
    write_csv(&d, &data);
    let out = dir.path().join("fit");
    let f = run_hairfit(
        &[
            "fit",
            data.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--no-progress",
            "--starts",
            "2",
        ],
        &[],
        Duration::from_secs(120),
    );
    assert!(f.status.success(), "{}", f.stderr);
    for name in ["fit.json", "params.json", "curves.csv"] {
        assert_eq!(
            format!("{:o}", mode(&out.join(name))),
            format!("{expected:o}"),
            "{name} mode differs from a File::create'd file"
        );
    }
}
