//! `hairfit eval` refusing or flagging what a newcomer got wrong: an output that would replace
//! an input, angles that look like radians, a repeated column, a radians output that would read
//! back as degrees, azimuths beyond two turns, a fit result given as parameters, an output that
//! is a directory, a mistyped `sigma_a`, and radians in a degrees key.

use crate::support::cli;

use cli::{assert_fails_with, hairfit, hairfit_ok, s, stderr, stdout, write};

const PARAMS: &str = r#"{"sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2,
  "w_c_deg": 15, "eccentricity": 0.9}"#;
const ANGLES: &str = "theta_i,phi_i,theta_r,phi_r\n10,0,20,30\n-20,5,25,170\n";

fn eval(params: &std::path::Path, input: &std::path::Path, more: &[&str]) -> std::process::Output {
    let mut args = vec!["eval", "--params", s(params), "--input", s(input)];
    args.extend_from_slice(more);
    hairfit(&args)
}

#[test]
fn an_output_that_would_replace_an_input_is_refused_and_both_are_kept() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS);
    let input = write(dir.path(), "a.csv", ANGLES);
    for (target, flag) in [(&params, "--params"), (&input, "--input")] {
        let out = eval(&params, &input, &["--output", s(target)]);
        assert_fails_with(&out, &["--output", "would replace", flag]);
    }
    // Spelled another way (`dir/./p.json`), it is still the same file.
    let other_spelling = dir.path().join(".").join("p.json");
    let out = eval(&params, &input, &["--output", s(&other_spelling)]);
    assert_fails_with(&out, &["would replace --params"]);
    assert_eq!(std::fs::read_to_string(&params).unwrap(), PARAMS);
    assert_eq!(std::fs::read_to_string(&input).unwrap(), ANGLES);
}

#[test]
fn angles_that_look_like_radians_warn_after_the_output_unless_the_unit_is_stated() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS);
    let text = "theta_i,phi_i,theta_r,phi_r\n0.17,0,0.35,0.52\n0.3,1.0,-0.2,2.5\n";
    let input = write(dir.path(), "r.csv", text);
    let out = hairfit_ok(&["eval", "--params", s(&params), "--input", s(&input)]);
    assert!(
        stderr(&out).contains("angles look like radians: pass --angles rad"),
        "{}",
        stderr(&out)
    );
    // Stated either way, no warning.
    for more in [&["--angles", "deg"][..], &["--angles", "rad"]] {
        let mut args = vec!["eval", "--params", s(&params), "--input", s(&input)];
        args.extend_from_slice(more);
        let out = hairfit_ok(&args);
        assert!(
            !stderr(&out).contains("radians"),
            "{more:?}: {}",
            stderr(&out)
        );
    }
    // The rule looks at every row: one angle beyond π in the last row says degrees.
    let many = format!(
        "{text}{}",
        "0.1,0.2,0.3,0.4\n".repeat(40_000) + "10,0,20,30\n"
    );
    let input = write(dir.path(), "m.csv", many);
    let out = hairfit_ok(&["eval", "--params", s(&params), "--input", s(&input)]);
    assert!(!stderr(&out).contains("radians"), "{}", stderr(&out));
}

#[test]
fn a_repeated_column_is_refused_as_the_loader_refuses_it() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS);
    let input = write(
        dir.path(),
        "d.csv",
        "theta_i,phi_i,theta_r,phi_r,theta_i\n10,0,20,30,50\n",
    );
    let out = eval(&params, &input, &[]);
    assert_fails_with(&out, &["d.csv:1:5:", "column `theta_i` appears twice"]);
}

#[test]
fn a_radians_output_carries_the_unit_line_and_reads_back_as_radians() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS);
    let rad = "theta_i,phi_i,theta_r,phi_r\n0.17,0,0.35,0.52\n";
    let from_line = write(dir.path(), "l.csv", format!("# angles: rad\n{rad}"));
    let from_flag = write(dir.path(), "f.csv", rad);
    let first = stdout(&hairfit_ok(&[
        "eval",
        "--params",
        s(&params),
        "--input",
        s(&from_line),
    ]));
    let second = stdout(&hairfit_ok(&[
        "eval",
        "--params",
        s(&params),
        "--input",
        s(&from_flag),
        "--angles",
        "rad",
    ]));
    assert!(first.starts_with("# angles: rad\ntheta_i,"), "{first}");
    assert_eq!(first, second);
    // Read back (its `s` column renamed away), the output evaluates to the same values:
    // it was read as radians again.
    let again = write(dir.path(), "o.csv", first.replace(",s\n", ",s_before\n"));
    let third = stdout(&hairfit_ok(&[
        "eval",
        "--params",
        s(&params),
        "--input",
        s(&again),
    ]));
    let last = |t: &str| {
        t.lines()
            .last()
            .unwrap()
            .rsplit(',')
            .next()
            .unwrap()
            .to_string()
    };
    assert_eq!(last(&third), last(&first));
    // Degrees stay as they were: no unit line.
    let deg = write(dir.path(), "g.csv", ANGLES);
    let out = stdout(&hairfit_ok(&[
        "eval",
        "--params",
        s(&params),
        "--input",
        s(&deg),
    ]));
    assert!(out.starts_with("theta_i,"), "{out}");
}

#[test]
fn azimuths_beyond_two_turns_are_refused_on_both_paths() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS);
    // A plain line (fast path) and a quoted one (read by the csv crate).
    for (name, row) in [("plain", "10,0,20,800"), ("quoted", "10,0,20,\"800\"")] {
        let input = write(
            dir.path(),
            &format!("{name}.csv"),
            format!("theta_i,phi_i,theta_r,phi_r\n10,0,20,30\n{row}\n"),
        );
        let out = eval(&params, &input, &[]);
        assert_fails_with(&out, &[":3:4:", "phi_r = 800", "720"]);
    }
    // 720° itself is accepted, as by the loader; in radians the bound is 4π.
    let edge = write(
        dir.path(),
        "edge.csv",
        "theta_i,phi_i,theta_r,phi_r\n10,-720,20,720\n",
    );
    hairfit_ok(&["eval", "--params", s(&params), "--input", s(&edge)]);
    let rad = write(
        dir.path(),
        "rad.csv",
        "theta_i,phi_i,theta_r,phi_r\n0.1,0,0.2,13\n",
    );
    let out = eval(&params, &rad, &["--angles", "rad"]);
    assert_fails_with(&out, &["phi_r = 13 radians"]);
}

#[test]
fn a_fit_result_or_truth_file_given_as_params_says_where_the_parameters_are() {
    let out = hairfit(&[
        "eval",
        "--params",
        "fits/demo/fit.json",
        "--input",
        "data/example_angles.csv",
    ]);
    assert_fails_with(&out, &["this is a fit result", "params.json"]);
    assert!(!stderr(&out).contains("--model"), "{}", stderr(&out));
    let out = hairfit(&[
        "eval",
        "--params",
        "data/azimuthal_rgb.truth.json",
        "--input",
        "data/example_angles.csv",
    ]);
    assert_fails_with(&out, &["truth file", "\"params\""]);
}

#[test]
fn an_output_that_is_a_directory_names_the_option() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS);
    let input = write(dir.path(), "a.csv", ANGLES);
    let existing = dir.path().join("out");
    std::fs::create_dir(&existing).unwrap();
    let slash = format!("{}/", dir.path().join("new").display());
    for target in [s(&existing), slash.as_str()] {
        let out = eval(&params, &input, &["--output", target]);
        assert_fails_with(&out, &["--output", "is a directory", "eval.csv"]);
    }
}

#[test]
fn a_mistyped_sigma_a_says_what_it_must_be() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "a.csv", ANGLES);
    for (text, needle) in [
        (r#""0.2""#, "sigma_a as a number or an array of numbers"),
        (r#"[0.2, "x"]"#, "a number for each channel of sigma_a"),
    ] {
        let params = write(dir.path(), "p.json", PARAMS.replace("0.4", text));
        let out = eval(&params, &input, &[]);
        assert_fails_with(&out, &[needle]);
        assert!(!stderr(&out).contains("untagged"), "{}", stderr(&out));
    }
}

#[test]
fn radians_in_a_degrees_key_warn_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "a.csv", ANGLES);
    let params = write(
        dir.path(),
        "p.json",
        PARAMS.replace("\"beta_r_deg\": 8", "\"beta_r_deg\": 0.14"),
    );
    let out = hairfit_ok(&["eval", "--params", s(&params), "--input", s(&input)]);
    let err = stderr(&out);
    assert!(
        err.contains("warning") && err.contains("beta_r_deg = 0.14"),
        "{err}"
    );
    assert!(!err.contains("alpha_r_deg"), "{err}");
    // Degrees as meant: no warning.
    let params = write(dir.path(), "q.json", PARAMS);
    let out = hairfit_ok(&["eval", "--params", s(&params), "--input", s(&input)]);
    assert!(!stderr(&out).contains("warning"), "{}", stderr(&out));
}

/// An unclosed quote is named where it opened (line 4, the second field: after a comment line),
/// not as "this row has 2 fields" at the end of the file.
#[test]
fn an_unclosed_quote_names_where_it_opened() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS);
    let text =
        "theta_i,phi_i,theta_r,phi_r\n10,0,20,30\n# note\n10,\"0,20,30\n11,0,20,30\n12,0,20,30\n";
    let input = write(dir.path(), "q.csv", text);
    let out = eval(&params, &input, &[]);
    assert_fails_with(
        &out,
        &[
            &format!("{}:4:2:", s(&input)),
            "runs on to line 6",
            "close the quote",
        ],
    );
}

/// A table saved in a German or French locale: `;` or tabs between the columns are named with a
/// conversion (eval reads commas), and a decimal comma in a cell is named with its fix.
#[test]
fn semicolon_tables_and_decimal_commas_are_named_with_the_fix() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS);
    for (name, text) in [
        ("semi.csv", "theta_i;phi_i;theta_r;phi_r\n10;0;20;30\n"),
        ("tab.csv", "theta_i\tphi_i\ttheta_r\tphi_r\n10\t0\t20\t30\n"),
    ] {
        let input = write(dir.path(), name, text);
        let out = eval(&params, &input, &[]);
        assert_fails_with(
            &out,
            &[&format!("{name}:1:1"), "separated by `;` or tabs", "tr "],
        );
    }
    // A header that merely lacks a column gets no such hint.
    let input = write(dir.path(), "short.csv", "theta_i,phi_i,theta_r\n10,0,20\n");
    let out = eval(&params, &input, &[]);
    assert_fails_with(&out, &["missing column(s) phi_r"]);
    assert!(!stderr(&out).contains("tabs"), "{}", stderr(&out));
    let input = write(
        dir.path(),
        "comma.csv",
        "theta_i,phi_i,theta_r,phi_r\n10,0,20,\"30,5\"\n",
    );
    let out = eval(&params, &input, &[]);
    assert_fails_with(
        &out,
        &[
            "comma.csv:2:4",
            "`30,5` looks like a decimal comma: write `30.5`",
        ],
    );
}

#[test]
fn a_fit_directory_as_params_reads_its_params_json_as_python_does() {
    let dir = tempfile::tempdir().unwrap();
    let fit = dir.path().join("fit");
    std::fs::create_dir(&fit).unwrap();
    let file = write(&fit, "params.json", PARAMS);
    let input = write(dir.path(), "a.csv", ANGLES);
    // The directory and its params.json are the same parameters, so the output is byte-equal.
    let by_dir = hairfit_ok(&["eval", "--params", s(&fit), "--input", s(&input)]);
    let by_file = hairfit_ok(&["eval", "--params", s(&file), "--input", s(&input)]);
    assert_eq!(stdout(&by_dir), stdout(&by_file));
    // A directory that is not a fit's says what to give instead (not "Is a directory").
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let out = eval(&empty, &input, &[]);
    assert_fails_with(
        &out,
        &["empty", "without a params.json", "hairfit fit --out DIR"],
    );
}
