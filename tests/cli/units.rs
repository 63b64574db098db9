//! Angle units through the binary: the `# angles:` line in any case anywhere before the first
//! data row (CSV, scan and `eval` alike), contradicting unit lines refused, and the warning when
//! a file read as degrees looks like radians.

use crate::support::cli;

use cli::{hairfit, s, stderr, write};
use std::path::Path;

const PARAMS: &str = r#"{"sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2,
  "w_c_deg": 15, "eccentricity": 0.9}"#;

/// Directions in degrees, a radiance per row (values do not matter for loading).
const ROWS_DEG: [[f64; 4]; 4] = [
    [30.0, 0.0, -30.0, 170.0],
    [30.0, 0.0, -25.0, -120.0],
    [15.0, 0.0, -10.0, 60.0],
    [45.0, 0.0, -40.0, 10.0],
];

/// The rows as text, in degrees or (as `{:?}` of to_radians) radians.
fn rows(radians: bool, with_radiance: bool) -> String {
    ROWS_DEG
        .iter()
        .map(|a| {
            let v: Vec<String> = a
                .iter()
                .map(|&d| {
                    if radians {
                        format!("{:?}", d.to_radians())
                    } else {
                        d.to_string()
                    }
                })
                .collect();
            let tail = if with_radiance { ",1.5\n" } else { "\n" };
            v.join(",") + tail
        })
        .collect()
}

/// `hairfit load --json` of `path` with `extra`: the report as JSON.
fn load_json(path: &Path, extra: &[&str]) -> serde_json::Value {
    let mut a = vec!["load", s(path), "--json"];
    a.extend_from_slice(extra);
    let o = hairfit(&a);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

const HEADER: &str = "theta_i,phi_i,theta_r,phi_r,radiance\n";

#[test]
fn radians_read_as_degrees_are_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    // The issue's case: a file in radians without a unit line loaded as "accepted" silently.
    let rad = write(
        dir.path(),
        "rad.csv",
        format!("{HEADER}{}", rows(true, true)),
    );
    let report = load_json(&rad, &[]);
    let warnings = report["warnings"].as_array().unwrap();
    assert_eq!(warnings.len(), 1, "{report}");
    assert!(
        warnings[0]
            .as_str()
            .unwrap()
            .starts_with("angles look like radians: pass --angles rad"),
        "{report}"
    );
    let o = hairfit(&["load", s(&rad)]);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("warning: angles look like radians"),
        "the summary shows it"
    );
    // `fit --strict` refuses it, naming the option that settles it; without --strict the fit
    // carries the warning.
    let out = dir.path().join("fit");
    let o = hairfit(&[
        "fit",
        s(&rad),
        "--out",
        s(&out),
        "--strict",
        "--starts",
        "2",
        "--no-progress",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("look like radians: pass --angles rad")
            && stderr(&o).contains("--strict"),
        "{}",
        stderr(&o)
    );
    assert!(!out.join("fit.json").exists(), "nothing is published");
    // Said explicitly, either way, there is nothing to warn about.
    for extra in [&["--angles", "rad"][..], &["--angles", "deg"][..]] {
        let r = load_json(&rad, extra);
        assert_eq!(
            r["warnings"].as_array().map_or(0, Vec::len),
            0,
            "{extra:?}: {r}"
        );
    }
    // Real degrees: no warning.
    let deg = write(
        dir.path(),
        "deg.csv",
        format!("{HEADER}{}", rows(false, true)),
    );
    assert_eq!(
        load_json(&deg, &[])["warnings"]
            .as_array()
            .map_or(0, Vec::len),
        0
    );
}

#[test]
fn the_unit_line_is_case_insensitive_and_valid_until_the_first_data_row() {
    let dir = tempfile::tempdir().unwrap();
    let reference = write(
        dir.path(),
        "ref.csv",
        format!("{HEADER}{}", rows(true, true)),
    );
    let expect = load_json(&reference, &["--angles", "rad"]);
    assert_eq!(expect["accepted"], 4);
    for (name, text) in [
        (
            "capital.csv",
            format!("# Angles: RAD\n{HEADER}{}", rows(true, true)),
        ),
        (
            "after_header.csv",
            format!("{HEADER}# angles: rad\n{}", rows(true, true)),
        ),
        (
            "spaced.csv",
            format!("#   ANGLES :  radians \n\n{HEADER}{}", rows(true, true)),
        ),
    ] {
        let p = write(dir.path(), name, &text);
        let r = load_json(&p, &[]);
        assert_eq!(r["accepted"], 4, "{name}: {r}");
        assert_eq!(
            r["warnings"].as_array().map_or(0, Vec::len),
            0,
            "{name}: {r}"
        );
        // Same samples as with --angles rad: read with the unit line, then contradicted.
        let o = hairfit(&["load", s(&p), "--angles", "deg"]);
        assert_eq!(o.status.code(), Some(1), "{name}");
        assert!(
            stderr(&o).contains("--angles deg"),
            "{name}: {}",
            stderr(&o)
        );
    }
    // Two unit lines that disagree: an error naming both lines.
    let two = write(
        dir.path(),
        "two.csv",
        format!("# angles: deg\n{HEADER}# angles: rad\n{}", rows(true, true)),
    );
    let o = hairfit(&["load", s(&two)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("two.csv:3") && err.contains("line 1"), "{err}");
    // Agreeing repeats are fine.
    let same = write(
        dir.path(),
        "same.csv",
        format!("# angles: rad\n{HEADER}# Angles: rad\n{}", rows(true, true)),
    );
    assert_eq!(load_json(&same, &[])["accepted"], 4);
}

#[test]
fn a_scan_honours_its_unit_line() {
    let dir = tempfile::tempdir().unwrap();
    // Columns theta_r,phi_r,radiance at θ_i = 0.5 rad, φ_i = 0.
    let body: String = ROWS_DEG
        .iter()
        .map(|a| format!("{:?},{:?},2\n", a[2].to_radians(), a[3].to_radians()))
        .collect();
    let p = write(dir.path(), "scan.txt", format!("# ANGLES: rad\n{body}"));
    let opts = [
        "--columns",
        "theta_r,phi_r,radiance",
        "--fixed",
        "theta_i=0.5,phi_i=0",
    ];
    let mut a = vec!["load", s(&p), "--json"];
    a.extend(opts);
    let o = hairfit(&a);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["accepted"], 4, "{r}");
    assert_eq!(r["warnings"].as_array().map_or(0, Vec::len), 0, "{r}");
    // Without the line the same scan is read as degrees and looks like radians.
    let bare = write(dir.path(), "bare.txt", &body);
    let mut a = vec!["load", s(&bare), "--json"];
    a.extend(opts);
    let r: serde_json::Value = serde_json::from_slice(&hairfit(&a).stdout).unwrap();
    assert_eq!(r["warnings"].as_array().map_or(0, Vec::len), 1, "{r}");
}

#[test]
fn eval_honours_the_unit_line_and_takes_angles() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS);
    let header = "theta_i,phi_i,theta_r,phi_r\n";
    let deg = write(
        dir.path(),
        "deg.csv",
        format!("{header}{}", rows(false, false)),
    );
    let rad_line = write(
        dir.path(),
        "rad_line.csv",
        format!("# Angles: rad\n{header}{}", rows(true, false)),
    );
    let rad_bare = write(
        dir.path(),
        "rad_bare.csv",
        format!("{header}{}", rows(true, false)),
    );
    // The S column of eval's output.
    let values = |input: &Path, extra: &[&str]| -> Vec<f64> {
        let mut a = vec!["eval", "--params", s(&params), "--input", s(input)];
        a.extend_from_slice(extra);
        let o = hairfit(&a);
        assert!(o.status.success(), "{}", stderr(&o));
        String::from_utf8_lossy(&o.stdout)
            .lines()
            // A radians output starts with its `# angles: rad` line, then the header.
            .filter(|l| !l.starts_with('#'))
            .skip(1)
            .map(|l| l.rsplit(',').next().unwrap().parse().unwrap())
            .collect()
    };
    let expect = values(&deg, &[]);
    assert_eq!(expect.len(), 4);
    // Radians from the degrees' to_radians: the model sees the same angles up to the last bit
    // of the text round trip; 1e-12 relative is far below any unit mix-up (factor 57).
    let close = |got: Vec<f64>, what: &str| {
        for (g, e) in got.iter().zip(&expect) {
            assert!((g - e).abs() <= 1e-12 * e.abs(), "{what}: {g} vs {e}");
        }
    };
    close(values(&rad_line, &[]), "unit line");
    close(values(&rad_bare, &["--angles", "rad"]), "--angles rad");
    let o = hairfit(&[
        "eval",
        "--params",
        s(&params),
        "--input",
        s(&rad_line),
        "--angles",
        "deg",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("drop --angles"), "{}", stderr(&o));
}
