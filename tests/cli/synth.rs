//! `hairfit synth` end to end: reproducible bytes, a bit-exact round trip through the loader and
//! the model, the truth sidecar, channel handling, and clear errors for bad options.

use crate::support::cli;

use cli::{hairfit, s, write};
use hairfit::families::marschner::params::ParameterFile as _;
use std::path::Path;
use std::process::Output;

use hairfit::data::{load, write_csv, LoadOptions};
use hairfit::families::marschner::fit::synthetic::{synthesize_directions, synthesize_rig};
use hairfit::families::marschner::params::{ParamFile, SigmaA};
use hairfit::families::marschner::{scattering, Effects, ModelConfig, RootMode};
use hairfit::geometry::{Angles, Measurement};
use hairfit::synth::{truth_path, Noise, Rig, Truth};

const PARAMS_3: &str = r#"{"eta": 1.55, "sigma_a": [0.2, 0.4, 0.8], "alpha_r_deg": -7,
  "beta_r_deg": 8, "k_g": 2, "w_c_deg": 15, "eccentricity": 0.9}"#;
const PARAMS_1: &str = r#"{"sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2,
  "w_c_deg": 15, "eccentricity": 0.9}"#;

fn ok(out: &Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn synth(dir: &Path, params: &Path, name: &str, extra: &[&str]) -> (Vec<u8>, Truth) {
    let csv = dir.join(name);
    let mut args = vec!["synth", "--params", s(params), "--output", s(&csv)];
    args.extend_from_slice(extra);
    ok(&hairfit(&args));
    let truth = Truth::load(&truth_path(&csv)).unwrap();
    (std::fs::read(&csv).unwrap(), truth)
}

#[test]
fn same_seed_same_bytes_different_seed_different_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "p.json", PARAMS_3);
    let opts = [
        "--rig",
        "sphere:n=300",
        "--noise",
        "photon:1000+relative:0.02+floor:1e-4+outliers:0.05",
    ];
    fn with_seed<'a>(opts: &[&'a str], seed: &'a str) -> Vec<&'a str> {
        [opts, &["--seed", seed]].concat()
    }
    let (a, ta) = synth(dir.path(), &p, "a.csv", &with_seed(&opts, "5"));
    let (b, tb) = synth(dir.path(), &p, "b.csv", &with_seed(&opts, "5"));
    let (c, tc) = synth(dir.path(), &p, "c.csv", &with_seed(&opts, "6"));
    assert!(a == b, "same seed must give identical bytes");
    assert!(a != c);
    // The truth differs only in the recorded command line (the output name) for the same seed.
    assert_eq!(
        Truth {
            command_line: None,
            ..ta.clone()
        },
        Truth {
            command_line: None,
            ..tb
        }
    );
    assert_ne!(ta.outliers, tc.outliers);
    assert_eq!(ta.seed, 5);
}

#[test]
fn noise_free_round_trip_through_the_loader_is_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "p.json", PARAMS_3);
    let csv = dir.path().join("rt.csv");
    let args = [
        "synth",
        "--params",
        s(&p),
        "--rig",
        "photo:lights=5:views=40",
        "--scale",
        "2.5,1,0.25",
        "--mode",
        "exact",
        "--output",
        s(&csv),
    ];
    ok(&hairfit(&args));
    let (data, report) = load(&csv, &LoadOptions::default()).unwrap();
    assert_eq!(report.accepted, 200);
    assert_eq!(data.channels, ["r", "g", "b"]);
    assert!(data.sigma.is_none(), "no noise, no sigma column");
    let params = ParamFile::from_json_str(PARAMS_3, "p.json")
        .unwrap()
        .to_params();
    let config = ModelConfig {
        mode: RootMode::Exact,
        effects: Effects::default(),
    };
    let scale = [2.5, 1.0, 0.25];
    let mut s_model = [0.0; 3];
    for i in 0..data.len() {
        let [theta_i, phi_i, theta_r, phi_r] = data.angles(i);
        let angles = Angles {
            theta_i,
            phi_i,
            theta_r,
            phi_r,
        };
        scattering(&params, &config, &angles, &mut s_model);
        for c in 0..3 {
            // Bit for bit: the file holds degrees whose to_radians are the radians the model
            // was evaluated at, and shortest round-trip values.
            assert_eq!(
                data.value(i, c),
                scale[c] * s_model[c],
                "sample {i} channel {c}"
            );
        }
    }
}

#[test]
fn library_dataset_equals_its_reloaded_file() {
    let params = ParamFile::from_json_str(PARAMS_1, "p.json")
        .unwrap()
        .to_params();
    let rig = Rig::parse("azimuthal:incidences=20,40:steps=36").unwrap();
    let noise = Noise::parse("relative:0.03+outliers:0.1").unwrap();
    let (ds, truth) = synthesize_rig(
        &params,
        &ModelConfig::default(),
        &rig,
        &noise,
        &[1.5],
        Measurement::S,
        9,
    )
    .unwrap();
    assert_eq!(truth.n_samples, 72);
    assert_eq!(ds.channels, ["radiance"]);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.csv");
    write_csv(&ds, &path).unwrap();
    let (back, _) = load(&path, &LoadOptions::default()).unwrap();
    // Everything but the in-memory metadata survives the file exactly (including each
    // sample's line number in the file).
    let mut ds = ds;
    ds.meta.clear();
    assert_eq!(back, ds);
    // The sphere rig's angles are full-mantissa degrees (asin(z).to_degrees()), the hardest
    // case for a degree file: still exact.
    let rig = Rig::parse("sphere:n=500").unwrap();
    let (mut ds, _) = synthesize_rig(
        &params,
        &ModelConfig::default(),
        &rig,
        &Noise::default(),
        &[1.0],
        Measurement::S,
        4,
    )
    .unwrap();
    write_csv(&ds, &path).unwrap();
    let (back, _) = load(&path, &LoadOptions::default()).unwrap();
    ds.meta.clear();
    assert_eq!(back, ds);
}

#[test]
fn truth_records_every_input() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "p.json", PARAMS_1);
    let (_, t) = synth(
        dir.path(),
        &p,
        "t.csv",
        &[
            "--rig",
            "longitudinal:incidences=10:phi=0:steps=5",
            "--noise",
            "outliers:0.5+relative:0.1",
            "--seed",
            "42",
            "--channels",
            "3",
            "--scale",
            "3",
            "--lobes",
            "R,TRT",
            "--no-glints",
        ],
    );
    // A scalar sigma_a replicated to 3 channels: the truth holds the per-channel values, with a
    // note saying so.
    assert_eq!(
        t.params.marschner().unwrap().sigma_a,
        SigmaA::PerChannel(vec![0.4; 3])
    );
    assert_eq!(t.params.marschner().unwrap().alpha_r_deg, -7.0);
    assert!(t
        .notes
        .iter()
        .any(|n| n.contains("replicated to all 3 channels")));
    assert_eq!(t.channels, ["r", "g", "b"]);
    assert!(t
        .scale
        .iter()
        .all(|s| s.value == Some(3.0) && s.std_error.is_none()));
    assert_eq!(t.rig, "longitudinal:incidences=10:phi=0:steps=5:max=85");
    assert_eq!(t.noise, "relative:0.1+outliers:0.5");
    assert!(t.sigma_written);
    assert_eq!(t.seed, 42);
    assert_eq!(t.n_samples, 5);
    assert!(!t.model.effects.lobes.tt && !t.model.effects.glints);
    assert_eq!(t.hairfit_version, env!("CARGO_PKG_VERSION"));
    let cmd = t.command_line.unwrap();
    assert!(cmd.starts_with("hairfit synth --params ") && cmd.contains("--no-glints"));
    // The truth's params are a valid parameter file that reproduces the synthesis inputs.
    let json = serde_json::to_string(&t.params).unwrap();
    assert_eq!(
        Some(&ParamFile::from_json_str(&json, "truth").unwrap()),
        t.params.marschner()
    );
}

#[test]
fn scalar_sigma_a_without_channels_is_one_radiance_column() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "p.json", PARAMS_1);
    let (bytes, t) = synth(
        dir.path(),
        &p,
        "one.csv",
        &["--rig", "azimuthal:steps=4", "--noise", "floor:0.001"],
    );
    let text = String::from_utf8(bytes).unwrap();
    let header = text.lines().find(|l| !l.starts_with('#')).unwrap();
    assert_eq!(header, "theta_i,phi_i,theta_r,phi_r,radiance,sigma");
    assert_eq!(t.params.marschner().unwrap().sigma_a, SigmaA::Scalar(0.4));
    assert!(t.notes.is_empty());
}

/// Run synth with `extra` options and return stderr; asserts failure and that no output exists.
fn synth_error(extra: &[&str], params: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "p.json", params);
    let csv = dir.path().join("bad.csv");
    let mut args = vec!["synth", "--params", s(&p)];
    if !extra.contains(&"--output") {
        args.extend(["--output", s(&csv)]);
    }
    args.extend_from_slice(extra);
    let out = hairfit(&args);
    assert!(!out.status.success(), "{extra:?} should fail");
    assert!(!csv.exists() && !truth_path(&csv).exists());
    // Nothing at all is left behind in the directory but the parameter file.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    String::from_utf8(out.stderr).unwrap()
}

#[test]
fn bad_options_get_clear_errors_and_write_nothing() {
    let cases: [(&[&str], &str, &str); 9] = [
        (&["--rig", "ring"], PARAMS_3, "unknown rig `ring`"),
        (
            &["--rig", "sphere:n=0"],
            PARAMS_3,
            "n: `0` is not a whole number >= 1",
        ),
        (
            &["--rig", "sphere", "--noise", "relative:-1"],
            PARAMS_3,
            "must be > 0",
        ),
        (
            &["--rig", "sphere", "--channels", "2"],
            PARAMS_3,
            "--channels 2, but sigma_a in",
        ),
        (
            &["--rig", "sphere", "--channels", "0"],
            PARAMS_1,
            "--channels 0",
        ),
        (
            &["--rig", "sphere", "--scale", "1,2"],
            PARAMS_3,
            "--scale has 2 values but there are 3 channels",
        ),
        (
            &["--rig", "sphere", "--scale", "-1"],
            PARAMS_1,
            "--scale: -1 is not a positive finite number",
        ),
        (
            &["--rig", "sphere", "--lobes", "R,XX"],
            PARAMS_1,
            "unknown lobe `XX`",
        ),
        (
            &["--rig", "sphere"],
            r#"{"sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2,
                "w_c_deg": 15, "eccentricity": 0.5}"#,
            "eccentricity",
        ),
    ];
    for (extra, params, expected) in cases {
        let err = synth_error(extra, params);
        assert!(err.contains(expected), "{extra:?}: {err}");
    }
}

#[test]
fn output_must_be_a_csv_and_params_must_exist() {
    let dir = tempfile::tempdir().unwrap();
    let err = synth_error(
        &["--rig", "sphere", "--output", s(&dir.path().join("x.dat"))],
        PARAMS_1,
    );
    assert!(err.contains("name the file FILE.csv"), "{err}");
    let out = hairfit(&[
        "synth",
        "--params",
        s(&dir.path().join("missing.json")),
        "--rig",
        "sphere",
        "--output",
        s(&dir.path().join("y.csv")),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("missing.json"), "{err}");
    // A malformed parameter file is reported at its line and column.
    let p = write(
        dir.path(),
        "broken.json",
        "{\"sigma_a\": 0.4,\n \"alpha_r_deg\": oops}",
    );
    let out = hairfit(&[
        "synth",
        "--params",
        s(&p),
        "--rig",
        "sphere",
        "--output",
        s(&dir.path().join("z.csv")),
    ]);
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("broken.json:2:"), "{err}");
}

#[test]
fn sigma_column_is_the_noise_models_sigma_of_the_clean_value() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "p.json", PARAMS_1);
    let csv = dir.path().join("n.csv");
    let args = [
        "synth",
        "--params",
        s(&p),
        "--rig",
        "azimuthal:incidences=30:steps=90",
        "--noise",
        "relative:0.05+floor:1e-3",
        "--scale",
        "4",
        "--lobes",
        "R,TT",
        "--output",
        s(&csv),
    ];
    ok(&hairfit(&args));
    let (data, _) = load(&csv, &LoadOptions::default()).unwrap();
    let params = ParamFile::from_json_str(PARAMS_1, "p.json")
        .unwrap()
        .to_params();
    let config = ModelConfig {
        mode: RootMode::Cubic,
        effects: Effects {
            lobes: Effects::parse_lobes("R,TT").unwrap(),
            ..Effects::default()
        },
    };
    let noise = Noise::parse("relative:0.05+floor:1e-3").unwrap();
    let mut moved = 0;
    for i in 0..data.len() {
        let [theta_i, phi_i, theta_r, phi_r] = data.angles(i);
        let mut s_model = [0.0];
        let angles = Angles {
            theta_i,
            phi_i,
            theta_r,
            phi_r,
        };
        scattering(&params, &config, &angles, &mut s_model);
        let clean = 4.0 * s_model[0];
        // σ is computed from the clean value (R+TT only, scale 4), bit for bit.
        assert_eq!(data.sigma_of(i, 0), Some(noise.sigma(clean)));
        if data.value(i, 0) != clean {
            moved += 1;
        }
    }
    // Gaussian noise moves every value.
    assert_eq!(moved, data.len());
}

#[test]
fn explicit_directions_are_used_as_given() {
    let params = ParamFile::from_json_str(PARAMS_3, "p.json")
        .unwrap()
        .to_params();
    let dirs = [[-20.0, 0.0, 25.0, 30.0], [10.0, -40.0, -5.0, 170.0]];
    let config = ModelConfig::default();
    let (ds, truth) = synthesize_directions(
        &params,
        &config,
        &dirs,
        "demo scan",
        &Noise::default(),
        &[1.0, 2.0, 3.0],
        Measurement::S,
        0,
    )
    .unwrap();
    assert_eq!(truth.rig, "demo scan");
    assert_eq!(truth.measurement, Measurement::S);
    assert_eq!(ds.len(), 2);
    // The same directions as radiance under a collimated source.
    let (radiance, truth) = synthesize_directions(
        &params,
        &config,
        &dirs,
        "demo scan",
        &Noise::default(),
        &[1.0, 2.0, 3.0],
        Measurement::Radiance,
        0,
    )
    .unwrap();
    assert_eq!(truth.measurement, Measurement::Radiance);
    let mut s_model = [0.0; 3];
    for (i, d) in dirs.iter().enumerate() {
        assert_eq!(ds.angles(i), d.map(f64::to_radians));
        let [theta_i, phi_i, theta_r, phi_r] = ds.angles(i);
        let angles = Angles {
            theta_i,
            phi_i,
            theta_r,
            phi_r,
        };
        scattering(&params, &config, &angles, &mut s_model);
        for (c, s_c) in s_model.iter().enumerate() {
            assert_eq!(ds.value(i, c), (c + 1) as f64 * s_c);
            // S · (scale · cos θ_i), in the synthesizer's order: bit for bit.
            let cos_i = theta_i.cos();
            assert_eq!(radiance.value(i, c), s_c * ((c + 1) as f64 * cos_i));
        }
    }
    let err = synthesize_directions(
        &params,
        &config,
        &[[0.0, 0.0, 90.0, 0.0]],
        "x",
        &Noise::default(),
        &[1.0; 3],
        Measurement::S,
        0,
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("direction 0") && err.contains("|theta| < 90"),
        "{err}"
    );
}

/// The data and its truth are published together: a truth file that cannot be written leaves
/// no CSV (and an earlier CSV untouched), and no temporary file.
#[test]
fn the_csv_and_its_truth_are_written_both_or_neither() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "p.json", PARAMS_1);
    let csv = dir.path().join("d.csv");
    // A directory where the sidecar goes: its rename fails.
    std::fs::create_dir(truth_path(&csv)).unwrap();
    let args = [
        "synth",
        "--params",
        s(&p),
        "--rig",
        "sphere:n=50",
        "--output",
        s(&csv),
    ];
    let out = hairfit(&args);
    assert_eq!(out.status.code(), Some(1));
    assert!(!csv.exists(), "the CSV was published without its truth");
    std::fs::write(&csv, "an earlier dataset").unwrap();
    assert_eq!(hairfit(&args).status.code(), Some(1));
    assert_eq!(std::fs::read_to_string(&csv).unwrap(), "an earlier dataset");
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["d.csv", "d.truth.json", "p.json"],
        "temporaries left"
    );
}

#[test]
fn synth_refuses_to_replace_its_own_parameter_file() {
    let dir = tempfile::tempdir().unwrap();
    let truth = write(dir.path(), "x.truth.json", PARAMS_1);
    let out = hairfit(&[
        "synth",
        "--params",
        s(&truth),
        "--rig",
        "sphere:n=50",
        "--output",
        s(&dir.path().join("x.csv")),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("would replace --params"), "{err}");
    assert_eq!(std::fs::read_to_string(&truth).unwrap(), PARAMS_1);
    assert!(!dir.path().join("x.csv").exists());
}

/// The issue's case: 10⁸ azimuthal steps aborted at 9.6 GB. Refused before allocating, naming
/// the options; `--max-memory` sets the limit either way.
#[test]
fn synth_estimates_memory_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "p.json", PARAMS_1);
    let csv = dir.path().join("d.csv");
    let run = |rig: &str, extra: &[&str]| {
        let mut a = vec![
            "synth",
            "--params",
            s(&p),
            "--rig",
            rig,
            "--output",
            s(&csv),
        ];
        a.extend_from_slice(extra);
        hairfit(&a)
    };
    let t0 = std::time::Instant::now();
    let out = run("azimuthal:steps=100000000", &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("--rig") && err.contains("steps") && err.contains("--max-memory"),
        "{err}"
    );
    // Refused, not attempted: allocating 9.6 GB alone takes longer than this.
    assert!(t0.elapsed() < std::time::Duration::from_secs(5));
    // 3 incidences × 10k steps ≈ 3.8 MB: refused under 1M, written under 100M.
    let out = run("azimuthal:steps=10000", &["--max-memory", "1M"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--max-memory"));
    ok(&run("azimuthal:steps=10000", &["--max-memory", "100M"]));
    let out = run("sphere:n=10", &["--max-memory", "lots"]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "clap refuses a size it cannot read"
    );
}

/// `--max-memory 1K` said "need about 0.0 GB, more than the 0.0 GB": sizes are now stated in
/// their own unit (bytes, KiB, MiB, GiB), so a small limit reads as what it is.
#[test]
fn memory_sizes_are_stated_in_a_readable_unit() {
    // 36 samples × 3 channels at 176 bytes each: 6336 bytes.
    let err = synth_error(
        &[
            "--rig",
            "azimuthal:incidences=15,30,45:steps=12",
            "--max-memory",
            "1K",
        ],
        PARAMS_3,
    );
    assert!(
        err.contains("need about 6.2 KiB, more than the 1 KiB --max-memory allows"),
        "{err}"
    );
    assert!(!err.contains("GB"), "{err}");
    let err = synth_error(
        &["--rig", "azimuthal:steps=100000000", "--max-memory", "1.5G"],
        PARAMS_1,
    );
    assert!(err.contains("more than the 1.5 GiB --max-memory"), "{err}");
}
