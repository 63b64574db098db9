//! `hairfit eval` end to end, as a user runs it: the output contract, the values (identical to the
//! library's), streaming and the errors for bad input.

use crate::support::cli;

use cli::{hairfit, s, write};
use hairfit::families::marschner::params::ParameterFile as _;

use hairfit::families::marschner::params::ParamFile;
use hairfit::families::marschner::{scattering, scattering_lanes, ModelConfig};
use hairfit::geometry::Angles;

const PARAMS_1: &str = r#"{"sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2,
  "w_c_deg": 15, "eccentricity": 0.9}"#;
const PARAMS_3: &str = r#"{"eta": 1.55, "sigma_a": [0.2, 0.4, 0.8], "alpha_r_deg": -7,
  "beta_r_deg": 8, "k_g": 2, "w_c_deg": 15, "eccentricity": 0.9}"#;
const ANGLES: &str = "theta_i,phi_i,theta_r,phi_r,label\n\
-20,0,25,30,a\n\
10,-40,-5,170,b\n\
-60,10,45,-80,c\n\
-10,0,75,0,d\n";

/// Parse eval's CSV output into (header, rows of fields).
fn read_csv(text: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (header, rows)
}

#[test]
fn one_channel_appends_s_and_carries_other_columns() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS_1);
    let input = write(dir.path(), "a.csv", ANGLES);
    let out = hairfit(&["eval", "--params", s(&params), "--input", s(&input)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (header, rows) = read_csv(std::str::from_utf8(&out.stdout).unwrap());
    assert_eq!(
        header,
        ["theta_i", "phi_i", "theta_r", "phi_r", "label", "s"]
    );
    assert_eq!(rows.len(), 4);
    assert_eq!(rows[2][4], "c");

    // The printed value is the library's eval path exactly (it must round-trip an f64), and
    // that path agrees with the scalar reference model (tests/families/marschner_lanes.rs: within 1e-11
    // relative times the grazing conditioning, which is below 4 at these directions).
    let p = ParamFile::from_json_str(PARAMS_1, "p.json")
        .unwrap()
        .to_params();
    for row in &rows {
        let deg: Vec<f64> = row[..4].iter().map(|v| v.parse().unwrap()).collect();
        let angles = Angles::from_degrees(deg[0], deg[1], deg[2], deg[3]);
        let (mut fast, mut reference) = ([0.0], [0.0]);
        scattering_lanes(&p, &ModelConfig::default(), &[angles], &mut fast);
        scattering(&p, &ModelConfig::default(), &angles, &mut reference);
        let printed: f64 = row[5].parse().unwrap();
        assert_eq!(printed.to_bits(), fast[0].to_bits(), "row {row:?}");
        assert!(
            (fast[0] - reference[0]).abs() <= 4e-11 * reference[0].abs(),
            "row {row:?}: {} vs reference {}",
            fast[0],
            reference[0]
        );
    }
}

#[test]
fn three_channels_append_s_0_to_s_2_and_output_file_matches_stdout() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS_3);
    let input = write(dir.path(), "a.csv", ANGLES);
    let out_path = dir.path().join("out.csv");
    let to_file = hairfit(&[
        "eval",
        "--params",
        s(&params),
        "--input",
        s(&input),
        "--output",
        s(&out_path),
        "--mode",
        "exact",
    ]);
    assert!(
        to_file.status.success(),
        "{}",
        String::from_utf8_lossy(&to_file.stderr)
    );
    let to_stdout = hairfit(&[
        "eval",
        "--params",
        s(&params),
        "--input",
        s(&input),
        "--mode",
        "exact",
    ]);
    let file_text = std::fs::read_to_string(&out_path).unwrap();
    assert_eq!(file_text.as_bytes(), &to_stdout.stdout[..]);
    let (header, rows) = read_csv(&file_text);
    assert_eq!(&header[5..], ["s_0", "s_1", "s_2"]);
    // More absorption, less light: the channels are ordered by sigma_a on every row.
    for row in rows {
        let v: Vec<f64> = row[5..].iter().map(|x| x.parse().unwrap()).collect();
        assert!(v[0] > v[1] && v[1] > v[2], "{v:?}");
    }
}

#[test]
fn effect_switches_change_the_values() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS_1);
    let input = write(dir.path(), "a.csv", ANGLES);
    let column = |extra: &[&str]| -> Vec<f64> {
        let mut args = vec!["eval", "--params", s(&params), "--input", s(&input)];
        args.extend_from_slice(extra);
        let out = hairfit(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let (_, rows) = read_csv(std::str::from_utf8(&out.stdout).unwrap());
        rows.iter().map(|r| r[5].parse().unwrap()).collect()
    };
    let all = column(&[]);
    let r_only = column(&["--lobes", "R"]);
    let tt_trt = column(&["--lobes", "TT,TRT"]);
    // S is a sum over lobes: R alone plus TT+TRT is everything (to rounding: a few ulps).
    for i in 0..all.len() {
        assert!(
            (r_only[i] + tt_trt[i] - all[i]).abs() <= 1e-14 * all[i],
            "row {i}"
        );
    }
    assert_ne!(column(&["--no-glints"]), all);
    assert_ne!(column(&["--no-eccentricity"]), all);
}

/// `hairfit ARGS` fails (an error, or clap's usage exit 2) with a message containing every needle.
fn fails_with(args: &[&str], needles: &[&str]) {
    let err = cli::failed(&hairfit(args));
    for n in needles {
        assert!(err.contains(n), "stderr {err:?} lacks {n:?}");
    }
}

#[test]
fn bad_angles_name_file_line_and_column_and_leave_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS_1);
    let out_path = dir.path().join("out.csv");
    let cases = [
        (
            "missing.csv",
            "theta_i,phi_i,theta_r\n1,2,3\n",
            vec!["missing.csv:1:", "phi_r"],
        ),
        (
            "nan.csv",
            "theta_i,phi_i,theta_r,phi_r\n1,2,3,4\n1,x2,3,4\n",
            vec!["nan.csv:3:2", "x2"],
        ),
        (
            "axis.csv",
            "theta_i,phi_i,theta_r,phi_r\n1,2,3,4\n1,2,90,4\n",
            vec!["axis.csv:3:3", "90"],
        ),
        (
            "ragged.csv",
            "theta_i,phi_i,theta_r,phi_r\n1,2,3,4\n1,2,3\n",
            vec!["ragged.csv:3:", "fields"],
        ),
        (
            "inf.csv",
            "theta_i,phi_i,theta_r,phi_r\n1,2,3,inf\n",
            vec!["inf.csv:2:4", "finite"],
        ),
    ];
    for (name, text, needles) in cases {
        let input = write(dir.path(), name, text);
        fails_with(
            &[
                "eval",
                "--params",
                s(&params),
                "--input",
                s(&input),
                "--output",
                s(&out_path),
            ],
            &needles,
        );
        assert!(
            !out_path.exists(),
            "{name}: a failed eval left an output file"
        );
    }
    // Nothing else (no temporary file) is left in the directory either.
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.starts_with(".hairfit"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn bad_parameter_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "a.csv", ANGLES);
    let cases = [
        ("syntax.json", "{\"sigma_a\": 0.4,\n \"alpha_r_deg\": }", vec!["syntax.json:2:"]),
        ("unknown.json", "{\"sigma_a\": 0.4, \"alpha_r_deg\": -7, \"beta_r_deg\": 8, \"k_g\": 2, \"w_c_deg\": 15, \"colour\": 1}", vec!["unknown.json:1:", "colour"]),
        ("missing.json", "{\"sigma_a\": 0.4}", vec!["missing.json:1:", "alpha_r_deg"]),
        ("ecc.json", "{\"sigma_a\": 0.4, \"alpha_r_deg\": -7, \"beta_r_deg\": 8, \"k_g\": 2, \"w_c_deg\": 15, \"eccentricity\": 0.5}", vec!["ecc.json", "eccentricity", "0.7071"]),
    ];
    for (name, text, needles) in cases {
        let params = write(dir.path(), name, text);
        fails_with(
            &["eval", "--params", s(&params), "--input", s(&input)],
            &needles,
        );
    }
    let params = write(dir.path(), "p.json", PARAMS_1);
    fails_with(
        &[
            "eval",
            "--params",
            s(&params),
            "--input",
            s(&input),
            "--lobes",
            "R,XX",
        ],
        &["XX"],
    );
    fails_with(
        &[
            "eval",
            "--params",
            s(&params),
            "--input",
            s(&input),
            "--mode",
            "quartic",
        ],
        &["quartic"],
    );
}

#[test]
fn streams_many_rows_in_chunks_with_comments_bom_and_crlf() {
    // 50_000 rows spans several evaluation chunks; the rows must come out in input order.
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS_1);
    let mut text = String::from("\u{feff}# a comment line\r\ntheta_i,phi_i,theta_r,phi_r,id\r\n");
    let n = 50_000;
    for i in 0..n {
        let t = -80.0 + 160.0 * (i as f64 / n as f64);
        text.push_str(&format!(
            "{t},{},{},{},{i}\r\n",
            i % 360,
            -t / 2.0,
            (i * 7) % 360
        ));
    }
    let input = write(dir.path(), "big.csv", &text);
    let out_path = dir.path().join("big_out.csv");
    let out = hairfit(&[
        "eval",
        "--params",
        s(&params),
        "--input",
        s(&input),
        "--output",
        s(&out_path),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (header, rows) = read_csv(&std::fs::read_to_string(&out_path).unwrap());
    assert_eq!(header[0], "theta_i");
    assert_eq!(rows.len(), n);
    for (i, row) in rows.iter().enumerate() {
        assert_eq!(row[4], i.to_string());
        let v: f64 = row[5].parse().unwrap();
        assert!(v.is_finite() && v >= 0.0);
    }
}

/// One thread evaluates each chunk on the calling thread, more threads on the pool: the output
/// is the same bytes either way (40,000 rows: two full chunks and a partial one, and a short
/// last lane group), and every printed value is the library's for its row, bit for bit.
#[test]
fn one_thread_and_two_threads_print_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS_3);
    let mut text = String::from("theta_i,phi_i,theta_r,phi_r\n");
    let mut state: u64 = 0x2545_F491_4F6C_DD1D;
    let mut uniform = |lo: f64, hi: f64| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
    };
    let n = 40_003;
    for _ in 0..n {
        let row = [
            uniform(-85.0, 85.0),
            uniform(-360.0, 360.0),
            uniform(-85.0, 85.0),
            uniform(-360.0, 360.0),
        ];
        text.push_str(&format!("{},{},{},{}\n", row[0], row[1], row[2], row[3]));
    }
    let input = write(dir.path(), "a.csv", &text);
    let run = |threads: &str| {
        let mut command =
            cli::hairfit_command(&["eval", "--params", s(&params), "--input", s(&input)]);
        command.env("RAYON_NUM_THREADS", threads);
        let out = command.output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        out.stdout
    };
    let one = run("1");
    assert!(
        one == run("2"),
        "one and two threads printed different output"
    );

    let p = ParamFile::from_json_str(PARAMS_3, "p.json")
        .unwrap()
        .to_params();
    let (header, rows) = read_csv(std::str::from_utf8(&one).unwrap());
    assert_eq!(header[4..], ["s_0", "s_1", "s_2"]);
    assert_eq!(rows.len(), n);
    for row in rows.iter().step_by(97).chain(rows.last()) {
        let deg: Vec<f64> = row[..4].iter().map(|v| v.parse().unwrap()).collect();
        let angles = Angles::from_degrees(deg[0], deg[1], deg[2], deg[3]);
        let mut expected = [0.0; 3];
        scattering_lanes(&p, &ModelConfig::default(), &[angles], &mut expected);
        for (printed, want) in row[4..].iter().zip(expected) {
            let printed: f64 = printed.parse().unwrap();
            assert_eq!(printed.to_bits(), want.to_bits(), "row {row:?}");
        }
    }
}
