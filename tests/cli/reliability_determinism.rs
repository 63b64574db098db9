//! Determinism: the same data, options and seed give bit-identical fit.json numbers (wall times
//! aside), params.json and curves.csv, with RAYON_NUM_THREADS=1 and 2 and across repeated runs.

use std::path::Path;
use std::time::Duration;

use crate::support::hard::*;
use hairfit::demo::{demo_geometry, DEMO_SCALE};
use hairfit::families::marschner::demo::demo_truth;
use hairfit::families::marschner::fit::synthetic::synthesize;
use hairfit::families::marschner::ModelConfig;

/// Keys whose values are measured times, not results.
const TIMES: [&str; 2] = ["wall_s", "wall_time_s"];

/// Every output of a run: fit.json numbers (with paths), the rest of fit.json as text, and the
/// bytes of params.json and curves.csv.
type Outputs = (Vec<(String, f64)>, String, Vec<u8>, Vec<u8>);

/// The [`Outputs`] of the run in `out`.
fn outputs(out: &Path) -> Outputs {
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("fit.json")).unwrap()).unwrap();
    let mut nums = Vec::new();
    numbers(&fit, "", &TIMES, &mut nums);
    // Everything but numbers (statuses, names, warnings) must match too.
    let mut skeleton = fit.clone();
    strip_numbers(&mut skeleton);
    (
        nums,
        skeleton.to_string(),
        std::fs::read(out.join("params.json")).unwrap(),
        std::fs::read(out.join("curves.csv")).unwrap(),
    )
}

fn strip_numbers(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Number(_) => *v = serde_json::Value::Null,
        serde_json::Value::Array(a) => a.iter_mut().for_each(strip_numbers),
        serde_json::Value::Object(o) => o.values_mut().for_each(strip_numbers),
        _ => {}
    }
}

/// Run each variant with RAYON_NUM_THREADS = 1, 2, 2 and compare every output bit for bit.
fn assert_deterministic(variants: &[&[&str]]) {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("demo.csv");
    let d = synthesize(
        &demo_truth(),
        &ModelConfig::default(),
        &demo_geometry(),
        &DEMO_SCALE,
        0.02,
        4,
    );
    write_csv(&d, &data);
    for (v, extra) in variants.iter().enumerate() {
        let mut reference = None;
        for (run, threads) in ["1", "2", "2"].iter().enumerate() {
            let out = dir.path().join(format!("v{v}-run{run}"));
            let mut args = vec![
                "fit",
                data.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
                "--no-progress",
                "--seed",
                "17",
            ];
            args.extend_from_slice(extra);
            // 120 s: each fit takes ~1–3 s; only a hang gets near it.
            let f = run_hairfit(
                &args,
                &[("RAYON_NUM_THREADS", threads)],
                Duration::from_secs(120),
            );
            assert!(f.status.success(), "variant {v} run {run}: {}", f.stderr);
            let got = outputs(&out);
            assert!(
                got.0.len() > 50,
                "too few numbers to compare: {}",
                got.0.len()
            );
            match &reference {
                None => reference = Some(got),
                Some(r) => {
                    let what = format!("variant {v}, run {run} (RAYON_NUM_THREADS={threads})");
                    assert_eq!(r.0.len(), got.0.len(), "{what}: different fit.json shape");
                    for ((pa, a), (pb, b)) in r.0.iter().zip(&got.0) {
                        assert_eq!(pa, pb, "{what}");
                        assert_eq!(a.to_bits(), b.to_bits(), "{what}: {pa} = {a:e} vs {b:e}");
                    }
                    assert_eq!(r.1, got.1, "{what}: fit.json text fields differ");
                    assert!(r.2 == got.2, "{what}: params.json differs");
                    assert!(r.3 == got.3, "{what}: curves.csv differs");
                }
            }
        }
    }
}

/// L2 with the projected scale (cubic), and a robust loss with explicit scales (exact roots): the
/// two code paths whose parallel reductions differ.
#[test]
fn same_seed_same_bits_for_any_thread_count_and_run() {
    assert_deterministic(&[
        &["--starts", "6"],
        &["--starts", "3", "--loss", "cauchy", "--mode", "exact"],
    ]);
}

/// The global stages too: Nelder–Mead (with a robust loss) and the seeded particle swarm.
#[test]
fn same_seed_same_bits_with_the_global_stages() {
    assert_deterministic(&[
        &[
            "--starts",
            "4",
            "--loss",
            "cauchy",
            "--global",
            "nelder-mead",
        ],
        &["--starts", "4", "--global", "pso"],
    ]);
}
