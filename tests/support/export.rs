//! Test-local fit directories for the export tests: a Chiang fit dir written from the library
//! (params.json as a `ChiangParamFile`, a minimal fit.json) until `hairfit fit --model chiang`
//! exists, and a Marschner one. No curves.csv: the mapping then covers the dense sphere only,
//! which keeps these tests to seconds.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use hairfit::families::chiang::{ChiangParamFile, ChiangParams};

/// CHIANG.md's parameter set A with three channels.
pub fn set_a_rgb() -> ChiangParams<f64> {
    ChiangParams {
        eta: 1.55,
        sigma_a: vec![0.25, 0.45, 0.8],
        beta_m: 0.3,
        beta_n: 0.3,
        alpha: 2f64.to_radians(),
    }
}

fn fit_json(channels: &[&str]) -> String {
    serde_json::json!({
        "hairfit_version": "test",
        "status": "converged",
        "data": { "channels": channels },
        "residuals": { "space": "log", "rms": 1.0, "reduced_chi2": 1.0 }
    })
    .to_string()
}

/// `root/name` holding a Chiang fit of `params`.
pub fn chiang_fit_dir(root: &Path, name: &str, params: &ChiangParams<f64>) -> PathBuf {
    let dir = root.join(name);
    std::fs::create_dir_all(&dir).unwrap();
    let file = ChiangParamFile::from_params(params);
    std::fs::write(
        dir.join("params.json"),
        serde_json::to_string_pretty(&file).unwrap(),
    )
    .unwrap();
    let channels: Vec<&str> = ["r", "g", "b"][..params.sigma_a.len().min(3)].to_vec();
    let channels = if params.sigma_a.len() == 3 {
        channels
    } else {
        (0..params.sigma_a.len()).map(|_| "s").collect()
    };
    std::fs::write(dir.join("fit.json"), fit_json(&channels)).unwrap();
    dir
}

/// `root/name` holding a one-channel Marschner fit (params.json in MODEL.md's names).
pub fn marschner_fit_dir(root: &Path, name: &str) -> PathBuf {
    let dir = root.join(name);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("params.json"),
        r#"{"eta": 1.55, "sigma_a": 0.5, "alpha_r_deg": -5, "beta_r_deg": 7.5, "k_g": 2,
            "w_c_deg": 15, "eccentricity": 0.9}"#,
    )
    .unwrap();
    std::fs::write(dir.join("fit.json"), fit_json(&["s"])).unwrap();
    dir
}

/// The Python the export tests run the real tools in: target/test-venv's (where scripts/test and
/// scripts/install-test-tools.sh install them), else `python3` on PATH.
pub fn test_python() -> std::process::Command {
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-venv/bin/python3");
    std::process::Command::new(if venv.exists() {
        venv.as_os_str()
    } else {
        std::ffi::OsStr::new("python3")
    })
}
